//! Reader of VTK XML unstructured grids (`.vtu`): the pieces' points, cells (connectivity,
//! offsets, types) and point-data arrays, as [`crate::io::mesh`] turns them into a mesh.
//!
//! What it reads: `DataArray`s in every format VTK and meshio write — `ascii`, inline
//! `binary` (base64, with or without `vtkZLibDataCompressor`, `header_type` `UInt32` or
//! `UInt64`, either byte order) and `appended` (`raw` or `base64` `AppendedData`, as
//! ParaView and VTK write by default) —, of every numeric type (`Int8` … `UInt64`,
//! `Float32`, `Float64`). Other compressors (LZ4, LZMA) are refused by name.
//!
//! Ours on quick-xml rather than vtkio's: vtkio 0.7 is a pre-release that panicked on
//! malformed input (fuzzing found index panics within seconds, which a process-wide
//! panic hook had to hide) and does not read raw appended data. Here every count is
//! checked against the bytes that hold it before anything is allocated, a compressed
//! array may not claim more than zlib's largest ratio (1032:1) of its compressed size,
//! and each error names the file, the piece, the array and what is wrong.

use std::path::Path;

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

use crate::error::Error;

/// zlib's largest expansion (deflate's maximum ratio is 1032:1): a compressed block
/// claiming more is corrupt, and decompressing it could exhaust memory.
const MAX_ZLIB_RATIO: u64 = 1032;
/// Largest number of values in one array (2³¹: 16 GiB of f64).
const MAX_VALUES: u64 = 1 << 31;
/// Largest number of nodes a cell may list (VTK's quadratic and Lagrange cells stay well
/// below): bounds a piece's connectivity by its cell count before it is read.
const MAX_CELL_NODES: u64 = 64;

/// One piece of the grid, as its arrays hold it.
#[derive(Debug, Default)]
pub(crate) struct Piece {
    /// `NumberOfPoints`.
    pub points: usize,
    /// `NumberOfCells`.
    pub cells: usize,
    /// Point coordinates, 3 per point.
    pub xyz: Vec<f64>,
    /// Cell connectivity (0-based point indices within the piece).
    pub connectivity: Vec<f64>,
    /// End offset of each cell in `connectivity`.
    pub offsets: Vec<f64>,
    /// VTK cell type codes.
    pub types: Vec<f64>,
    /// Point-data arrays with one component: (name, one value per point).
    pub point_data: Vec<(String, Vec<f64>)>,
}

/// How the file stores binary data.
#[derive(Clone, Copy, Debug)]
struct Layout {
    big_endian: bool,
    /// Bytes per header word: 4 (`UInt32`) or 8 (`UInt64`).
    word: usize,
    compressed: bool,
}

/// Where a `DataArray` is and what it holds.
#[derive(Debug)]
struct ArrayRef {
    piece: usize,
    role: Role,
    name: String,
    /// Bytes per value and how to read one.
    kind: NumKind,
    components: usize,
    source: Source,
}

#[derive(Debug)]
enum Source {
    Ascii(String),
    Binary(String),
    Appended(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Points,
    Connectivity,
    Offsets,
    Types,
    PointData,
    Ignored,
}

#[derive(Clone, Copy, Debug)]
enum NumKind {
    I(usize),
    U(usize),
    F(usize),
}

impl NumKind {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "Int8" => NumKind::I(1),
            "Int16" => NumKind::I(2),
            "Int32" => NumKind::I(4),
            "Int64" => NumKind::I(8),
            "UInt8" => NumKind::U(1),
            "UInt16" => NumKind::U(2),
            "UInt32" => NumKind::U(4),
            "UInt64" => NumKind::U(8),
            "Float32" => NumKind::F(4),
            "Float64" => NumKind::F(8),
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            NumKind::I(s) | NumKind::U(s) | NumKind::F(s) => s,
        }
    }

    /// One value from `b` (`size()` bytes).
    fn read(self, b: &[u8], big_endian: bool) -> f64 {
        let mut a = [0u8; 8];
        let n = b.len();
        if big_endian {
            a[8 - n..].copy_from_slice(b);
            a.reverse();
        } else {
            a[..n].copy_from_slice(b);
        }
        let raw = u64::from_le_bytes(a);
        match self {
            NumKind::U(_) => raw as f64,
            NumKind::I(s) => {
                let shift = 64 - 8 * s as u32;
                (((raw << shift) as i64) >> shift) as f64
            }
            NumKind::F(4) => f32::from_bits(raw as u32) as f64,
            NumKind::F(_) => f64::from_bits(raw),
        }
    }
}

fn bad(path: &Path, at: impl std::fmt::Display, what: impl std::fmt::Display) -> Error {
    Error::bad_file(path, at, what)
}

/// Reads the pieces of the unstructured grid in `bytes` (the file `path`).
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<Vec<Piece>, Error> {
    // raw appended data is not XML: parse the markup before it, keep the data apart
    let (xml_bytes, appended) = split_appended(path, bytes)?;
    let xml = std::str::from_utf8(xml_bytes).map_err(|e| {
        bad(
            path,
            format!("byte {}", e.valid_up_to()),
            "is not UTF-8 text (a VTK XML file is text up to its AppendedData)",
        )
    })?;
    let line = |pos: u64| {
        let pos = (pos as usize).min(xml.len());
        format!(
            "line {}",
            1 + xml.as_bytes()[..pos]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
        )
    };
    let mut reader = Reader::from_str(xml);
    let mut layout = None;
    let mut pieces: Vec<Piece> = Vec::new();
    let mut arrays: Vec<ArrayRef> = Vec::new();
    let mut section = Role::Ignored;
    let mut grid = false;
    // the array whose text is being collected
    let mut open: Option<ArrayRef> = None;
    // depth of elements inside that array (VTK's `InformationKey`s), whose text is not data
    let mut skip = 0usize;
    loop {
        let pos = reader.buffer_position();
        let ev = match reader.read_event() {
            Ok(ev) => ev,
            // the markup before raw appended data ends unclosed: that is its end
            Err(_) if appended.is_some() && open.is_none() => break,
            Err(e) => {
                return Err(bad(
                    path,
                    line(reader.error_position()),
                    format!("XML error: {e}"),
                ));
            }
        };
        let (e, empty) = match ev {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) if skip > 0 => {
                skip -= 1;
                continue;
            }
            Event::Text(t) if skip == 0 => {
                push_text(&mut open, &t);
                continue;
            }
            Event::CData(t) if skip == 0 => {
                push_text(&mut open, &t);
                continue;
            }
            Event::End(e) => {
                match e.name().as_ref() {
                    "DataArray" => arrays.extend(open.take()),
                    "Points" | "Cells" | "PointData" | "CellData" | "FieldData" => {
                        section = Role::Ignored
                    }
                    _ => {}
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        if open.is_some() {
            // metadata inside an array (`InformationKey`): skipped with its content
            if name_of(&e) == "DataArray" {
                return Err(bad(path, line(pos), "a DataArray inside a DataArray"));
            }
            skip += usize::from(!empty);
            continue;
        }
        match name_of(&e).as_str() {
            "VTKFile" => {
                let ty = attr(path, &e, "type")?.unwrap_or_default();
                if ty != "UnstructuredGrid" {
                    return Err(bad(
                        path,
                        line(pos),
                        format!("VTKFile type `{ty}`: expected UnstructuredGrid (a .vtu mesh)"),
                    ));
                }
                layout = Some(file_layout(path, &e, &line(pos))?);
            }
            "UnstructuredGrid" => grid = true,
            "Piece" if grid => {
                let count = |key: &str| -> Result<usize, Error> {
                    let v = attr(path, &e, key)?
                        .ok_or_else(|| bad(path, line(pos), format!("Piece has no {key}")))?;
                    v.trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&n| (n as u64) < MAX_VALUES)
                        .ok_or_else(|| {
                            bad(
                                path,
                                line(pos),
                                format!("Piece {key} `{v}`: expected a count below {MAX_VALUES}"),
                            )
                        })
                };
                pieces.push(Piece {
                    points: count("NumberOfPoints")?,
                    cells: count("NumberOfCells")?,
                    ..Piece::default()
                });
            }
            "Points" => section = Role::Points,
            "Cells" => section = Role::Connectivity,
            "PointData" => section = Role::PointData,
            "CellData" | "FieldData" => section = Role::Ignored,
            "DataArray" => {
                let Some(piece) = pieces.len().checked_sub(1) else {
                    // arrays outside a piece (FieldData of the file) are not ours
                    continue;
                };
                let a = data_array(path, &e, piece, section, &line(pos))?;
                if empty {
                    arrays.push(a);
                } else {
                    open = Some(a);
                }
            }
            _ => {}
        }
    }
    let layout = layout.ok_or_else(|| bad(path, "", "no <VTKFile> element: not a VTK XML file"))?;
    if !grid || pieces.is_empty() {
        return Err(bad(path, "", "no UnstructuredGrid Piece"));
    }
    let appended = match appended {
        Some((enc, data)) => Some(appended_regions(path, enc, data, &arrays)?),
        None => None,
    };
    for (i, a) in arrays.iter().enumerate() {
        if a.role == Role::Ignored {
            continue;
        }
        let piece = &pieces[a.piece];
        let at = format!("piece {}, DataArray `{}`", a.piece, a.name);
        // how many values the piece says it holds (connectivity: at most what its cells
        // can list)
        let expected = match a.role {
            Role::Points => Some(piece.points as u64 * 3),
            Role::Offsets | Role::Types => Some(piece.cells as u64),
            Role::PointData => Some(piece.points as u64 * a.components as u64),
            _ => None,
        };
        let at_most = expected
            .unwrap_or(piece.cells as u64 * MAX_CELL_NODES)
            .min(MAX_VALUES);
        let values = match &a.source {
            Source::Ascii(s) => ascii_values(path, &at, s, expected)?,
            Source::Binary(s) => {
                let payload = base64_segments(path, &at, s)?;
                binary_values(path, &at, &payload, layout, a.kind, (expected, at_most))?
            }
            Source::Appended(_) => {
                let regions = appended.as_ref().ok_or_else(|| {
                    bad(
                        path,
                        &at,
                        "format=\"appended\" but the file has no AppendedData",
                    )
                })?;
                binary_values(path, &at, &regions[i], layout, a.kind, (expected, at_most))?
            }
        };
        if let Some(n) = expected
            && values.len() as u64 != n
        {
            return Err(bad(
                path,
                &at,
                format!("{} values, expected {n}", values.len()),
            ));
        }
        let p = &mut pieces[a.piece];
        match a.role {
            Role::Points => p.xyz = values,
            Role::Connectivity => p.connectivity = values,
            Role::Offsets => p.offsets = values,
            Role::Types => p.types = values,
            Role::PointData if a.components == 1 => p.point_data.push((a.name.clone(), values)),
            _ => {}
        }
    }
    for (i, p) in pieces.iter().enumerate() {
        if p.xyz.len() != 3 * p.points {
            return Err(bad(path, format!("piece {i}"), "has no Points DataArray"));
        }
        if p.cells > 0 && (p.offsets.is_empty() || p.types.is_empty()) {
            return Err(bad(
                path,
                format!("piece {i}"),
                "Cells needs `connectivity`, `offsets` and `types` DataArrays",
            ));
        }
    }
    Ok(pieces)
}

/// Appends the text of a `DataArray` to the open one (data formats keep text).
fn push_text(open: &mut Option<ArrayRef>, t: &str) {
    if let Some(a) = open.as_mut()
        && let Source::Ascii(s) | Source::Binary(s) = &mut a.source
    {
        s.push_str(t);
    }
}

fn name_of(e: &BytesStart<'_>) -> String {
    e.local_name().as_ref().to_string()
}

/// The value of attribute `key` of `e`, if present.
fn attr(path: &Path, e: &BytesStart<'_>, key: &str) -> Result<Option<String>, Error> {
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
fn file_layout(path: &Path, e: &BytesStart<'_>, at: &str) -> Result<Layout, Error> {
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
fn data_array(
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

/// Splits the file at `<AppendedData`: the markup before, and the encoding and data
/// after the `_` that starts them (raw data is not XML).
#[allow(clippy::type_complexity)]
fn split_appended<'b>(
    path: &Path,
    bytes: &'b [u8],
) -> Result<(&'b [u8], Option<(bool, &'b [u8])>), Error> {
    let tag = b"<AppendedData";
    let Some(start) = bytes.windows(tag.len()).position(|w| w == tag) else {
        return Ok((bytes, None));
    };
    let rest = &bytes[start..];
    let close = rest
        .iter()
        .position(|&b| b == b'>')
        .ok_or_else(|| bad(path, "AppendedData", "its tag is not closed"))?;
    let head = String::from_utf8_lossy(&rest[..close]);
    let base64 = if head.contains("encoding=\"raw\"") || head.contains("encoding='raw'") {
        false
    } else if head.contains("encoding=\"base64\"") || head.contains("encoding='base64'") {
        true
    } else {
        return Err(bad(
            path,
            "AppendedData",
            "encoding must be \"raw\" or \"base64\"",
        ));
    };
    let under = rest[close..]
        .iter()
        .position(|&b| b == b'_')
        .ok_or_else(|| bad(path, "AppendedData", "no `_` marks the start of its data"))?;
    Ok((&bytes[..start], Some((base64, &rest[close + under + 1..]))))
}

/// The bytes of each appended array (indexed like `arrays`; empty for the others): raw
/// data from its offset on, base64 data decoded from its offset to the next array's.
fn appended_regions<'d>(
    path: &Path,
    base64: bool,
    data: &'d [u8],
    arrays: &[ArrayRef],
) -> Result<Vec<std::borrow::Cow<'d, [u8]>>, Error> {
    use std::borrow::Cow;
    let mut offsets: Vec<usize> = arrays
        .iter()
        .filter_map(|a| match a.source {
            Source::Appended(o) => Some(o),
            _ => None,
        })
        .collect();
    offsets.sort_unstable();
    // base64 text ends at `</AppendedData>`
    let text_end = if base64 {
        data.iter().position(|&b| b == b'<').unwrap_or(data.len())
    } else {
        data.len()
    };
    let mut out = Vec::with_capacity(arrays.len());
    for a in arrays {
        let Source::Appended(off) = a.source else {
            out.push(Cow::Borrowed(&[][..]));
            continue;
        };
        let at = format!("piece {}, DataArray `{}`", a.piece, a.name);
        if a.role == Role::Ignored {
            out.push(Cow::Borrowed(&[][..]));
            continue;
        }
        if off > text_end {
            return Err(bad(
                path,
                &at,
                format!("appended offset {off} is past the data's {text_end} bytes"),
            ));
        }
        if base64 {
            let end = offsets
                .iter()
                .copied()
                .find(|&o| o > off)
                .unwrap_or(text_end)
                .min(text_end);
            let text = std::str::from_utf8(&data[off..end])
                .map_err(|_| bad(path, &at, "appended base64 data is not text"))?;
            out.push(Cow::Owned(base64_segments(path, &at, text)?));
        } else {
            // raw: the array's header says how far it goes; binary_values checks it
            out.push(Cow::Borrowed(&data[off..]));
        }
    }
    Ok(out)
}

/// Decodes base64 text made of one or more padded streams (VTK and meshio encode a
/// compressed array's header and data as two streams), ignoring whitespace.
fn base64_segments(path: &Path, at: &str, text: &str) -> Result<Vec<u8>, Error> {
    use base64::Engine as _;
    let clean: Vec<u8> = text.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3);
    let mut rest = &clean[..];
    while !rest.is_empty() {
        // a stream ends after its padding, or with the text
        let end = match rest.iter().position(|&b| b == b'=') {
            Some(p) => {
                let mut e = p;
                while e < rest.len() && rest[e] == b'=' {
                    e += 1;
                }
                e
            }
            None => rest.len(),
        };
        base64::engine::general_purpose::STANDARD
            .decode_vec(&rest[..end], &mut out)
            .map_err(|e| bad(path, at, format!("base64 data: {e}")))?;
        rest = &rest[end..];
    }
    Ok(out)
}

/// Reads header word `i` of `b`.
fn word(b: &[u8], i: usize, layout: Layout) -> Option<u64> {
    let w = layout.word;
    let s = b.get(i * w..(i + 1) * w)?;
    Some(NumKind::U(w).read(s, layout.big_endian) as u64)
}

/// The values of a binary array from its payload (header, then data), checking every
/// size against the bytes present, against `count.1` values at most and, where known,
/// exactly `count.0` values.
fn binary_values(
    path: &Path,
    at: &str,
    payload: &[u8],
    layout: Layout,
    kind: NumKind,
    count: (Option<u64>, u64),
) -> Result<Vec<f64>, Error> {
    let size = kind.size() as u64;
    let truncated = |what: &str| bad(path, at, format!("binary data ends inside its {what}"));
    let data: std::borrow::Cow<'_, [u8]> = if layout.compressed {
        let nb = word(payload, 0, layout).ok_or_else(|| truncated("header"))?;
        let block = word(payload, 1, layout).ok_or_else(|| truncated("header"))?;
        let last = word(payload, 2, layout).ok_or_else(|| truncated("header"))?;
        let hwords = 3u64.saturating_add(nb);
        let hbytes = hwords.saturating_mul(layout.word as u64);
        if hbytes > payload.len() as u64 {
            return Err(bad(
                path,
                at,
                format!(
                    "compression header of {nb} blocks needs {hbytes} bytes, {} present",
                    payload.len()
                ),
            ));
        }
        let total = if nb == 0 {
            0
        } else {
            (nb - 1)
                .saturating_mul(block)
                .saturating_add(if last == 0 { block } else { last })
        };
        let mut csizes = Vec::with_capacity(nb as usize);
        let mut ctotal = 0u64;
        for i in 0..nb as usize {
            let c = word(payload, 3 + i, layout).ok_or_else(|| truncated("header"))?;
            ctotal = ctotal.saturating_add(c);
            csizes.push(c);
        }
        let body = &payload[hbytes as usize..];
        if ctotal > body.len() as u64 {
            return Err(bad(
                path,
                at,
                format!(
                    "{ctotal} bytes of compressed blocks, {} present",
                    body.len()
                ),
            ));
        }
        check_total(path, at, total, size, count)?;
        if total > ctotal.saturating_mul(MAX_ZLIB_RATIO).saturating_add(64) {
            return Err(bad(
                path,
                at,
                format!(
                    "{total} bytes claimed from {ctotal} compressed: more than zlib can expand"
                ),
            ));
        }
        let mut out = Vec::with_capacity(total as usize);
        let mut pos = 0usize;
        for (i, &c) in csizes.iter().enumerate() {
            let want = if i + 1 == csizes.len() && last != 0 {
                last
            } else {
                block
            };
            let before = out.len();
            let mut z = flate2::Decompress::new(true);
            out.reserve(want as usize);
            let st = z
                .decompress_vec(
                    &body[pos..pos + c as usize],
                    &mut out,
                    flate2::FlushDecompress::Finish,
                )
                .map_err(|e| bad(path, at, format!("zlib block {i}: {e}")))?;
            if st != flate2::Status::StreamEnd || (out.len() - before) as u64 != want {
                return Err(bad(
                    path,
                    at,
                    format!(
                        "zlib block {i} inflates to {} bytes, its header says {want}",
                        out.len() - before
                    ),
                ));
            }
            pos += c as usize;
        }
        std::borrow::Cow::Owned(out)
    } else {
        let n = word(payload, 0, layout).ok_or_else(|| truncated("header"))?;
        let body = &payload[layout.word..];
        if n > body.len() as u64 {
            return Err(bad(
                path,
                at,
                format!("header says {n} bytes, {} present", body.len()),
            ));
        }
        check_total(path, at, n, size, count)?;
        std::borrow::Cow::Borrowed(&body[..n as usize])
    };
    Ok(data
        .chunks_exact(kind.size())
        .map(|c| kind.read(c, layout.big_endian))
        .collect())
}

/// A byte count that is a whole number of values and, where the count is known,
/// exactly that many.
fn check_total(
    path: &Path,
    at: &str,
    bytes: u64,
    size: u64,
    (expected, at_most): (Option<u64>, u64),
) -> Result<(), Error> {
    if !bytes.is_multiple_of(size) {
        return Err(bad(
            path,
            at,
            format!("{bytes} bytes are not a whole number of {size}-byte values"),
        ));
    }
    if bytes / size > at_most {
        return Err(bad(
            path,
            at,
            format!(
                "{} values: more than the {at_most} its piece can hold",
                bytes / size
            ),
        ));
    }
    if let Some(n) = expected
        && bytes / size != n
    {
        return Err(bad(
            path,
            at,
            format!("{} values, expected {n}", bytes / size),
        ));
    }
    Ok(())
}

/// Whitespace-separated numbers.
fn ascii_values(
    path: &Path,
    at: &str,
    text: &str,
    expected: Option<u64>,
) -> Result<Vec<f64>, Error> {
    let cap = expected.unwrap_or(0).min(text.len() as u64 / 2 + 1) as usize;
    let mut out = Vec::with_capacity(cap);
    for (i, w) in text.split_ascii_whitespace().enumerate() {
        let v: f64 = w.parse().map_err(|_| {
            bad(
                path,
                at,
                format!(
                    "value {i} `{}` is not a number",
                    w.chars().take(40).collect::<String>()
                ),
            )
        })?;
        out.push(v);
    }
    Ok(out)
}
