//! The XML side of a `.vtu`: the file's layout (byte order, header type, compressor), the
//! attributes of a `DataArray` and where its values are (inline text or an offset into the
//! appended data).

use super::*;

/// Appends the text of a `DataArray` to the open one (data formats keep text).
pub(super) fn push_text(open: &mut Option<ArrayRef>, t: &str) {
    if let Some(a) = open.as_mut()
        && let Source::Ascii(s) | Source::Binary(s) = &mut a.source
    {
        s.push_str(t);
    }
}

pub(super) fn name_of(e: &BytesStart<'_>) -> String {
    e.local_name().as_ref().to_string()
}

/// The value of attribute `key` of `e`, if present.
pub(super) fn attr(path: &Path, e: &BytesStart<'_>, key: &str) -> Result<Option<String>, Error> {
    for a in e.attributes() {
        let a = a.map_err(|err| {
            bad(
                path,
                format!("<{}>", name_of(e)),
                format!("bad attribute: {err}"),
            )
        })?;
        if a.key.local_name().as_ref() == key {
            return Ok(Some(a.value.into_owned()));
        }
    }
    Ok(None)
}

/// `byte_order`, `header_type` and `compressor` of `<VTKFile>`.
pub(super) fn file_layout(path: &Path, e: &BytesStart<'_>, at: &str) -> Result<Layout, Error> {
    let big_endian = match attr(path, e, "byte_order")?.as_deref() {
        None | Some("LittleEndian") => false,
        Some("BigEndian") => true,
        Some(o) => {
            return Err(bad(
                path,
                at,
                format!("byte_order `{o}`: expected LittleEndian or BigEndian"),
            ));
        }
    };
    let word = match attr(path, e, "header_type")?.as_deref() {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(o) => {
            return Err(bad(
                path,
                at,
                format!("header_type `{o}`: expected UInt32 or UInt64"),
            ));
        }
    };
    let compressed = match attr(path, e, "compressor")?.as_deref() {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(o) => {
            return Err(bad(
                path,
                at,
                format!(
                    "compressor `{o}` is not supported: only vtkZLibDataCompressor (write the \
                     file with zlib compression, or none)"
                ),
            ));
        }
    };
    Ok(Layout {
        big_endian,
        word,
        compressed,
    })
}

/// A `DataArray` start tag in `section` of `piece`.
pub(super) fn data_array(
    path: &Path,
    e: &BytesStart<'_>,
    piece: usize,
    section: Role,
    at: &str,
) -> Result<ArrayRef, Error> {
    let name = attr(path, e, "Name")?.unwrap_or_default();
    let ty = attr(path, e, "type")?.unwrap_or_default();
    let kind = NumKind::parse(&ty).ok_or_else(|| {
        bad(
            path,
            at,
            format!("DataArray `{name}` type `{ty}`: expected Int8 … UInt64, Float32 or Float64"),
        )
    })?;
    let components = match attr(path, e, "NumberOfComponents")? {
        None => 1,
        Some(c) => c
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&c| (1..=64).contains(&c))
            .ok_or_else(|| {
                bad(
                    path,
                    at,
                    format!("DataArray `{name}` NumberOfComponents `{c}`: expected 1 to 64"),
                )
            })?,
    };
    let role = match section {
        Role::Points => Role::Points,
        Role::Connectivity => match name.as_str() {
            "connectivity" => Role::Connectivity,
            "offsets" => Role::Offsets,
            "types" => Role::Types,
            _ => Role::Ignored,
        },
        other => other,
    };
    if role == Role::Points && components != 3 {
        return Err(bad(
            path,
            at,
            format!("Points have {components} components: expected NumberOfComponents=\"3\""),
        ));
    }
    let source = match attr(path, e, "format")?.as_deref() {
        Some("ascii") => Source::Ascii(String::new()),
        Some("binary") => Source::Binary(String::new()),
        Some("appended") => {
            let off = attr(path, e, "offset")?.unwrap_or_default();
            Source::Appended(off.trim().parse::<usize>().map_err(|_| {
                bad(
                    path,
                    at,
                    format!("DataArray `{name}` offset `{off}`: expected a byte offset"),
                )
            })?)
        }
        other => {
            return Err(bad(
                path,
                at,
                format!(
                    "DataArray `{name}` format `{}`: expected ascii, binary or appended",
                    other.unwrap_or("(none)")
                ),
            ));
        }
    };
    Ok(ArrayRef {
        piece,
        role,
        name,
        kind,
        components,
        source,
    })
}
