//! The values of a `DataArray`: ASCII text, inline base64 and appended data (raw or
//! base64), zlib-compressed or not, every count checked against the bytes that hold it
//! before anything is allocated.

use super::*;

/// Splits the file at `<AppendedData`: the markup before, and the encoding and data
/// after the `_` that starts them (raw data is not XML).
#[allow(clippy::type_complexity)]
pub(super) fn split_appended<'b>(
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
pub(super) fn appended_regions<'d>(
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
pub(super) fn base64_segments(path: &Path, at: &str, text: &str) -> Result<Vec<u8>, Error> {
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
pub(super) fn word(b: &[u8], i: usize, layout: Layout) -> Option<u64> {
    let w = layout.word;
    let s = b.get(i * w..(i + 1) * w)?;
    Some(NumKind::U(w).read(s, layout.big_endian) as u64)
}

/// The values of a binary array from its payload (header, then data), checking every
/// size against the bytes present, against `count.1` values at most and, where known,
/// exactly `count.0` values.
pub(super) fn binary_values(
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
pub(super) fn check_total(
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
pub(super) fn ascii_values(
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
