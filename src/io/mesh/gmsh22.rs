//! Gmsh 2.2 files (ASCII and binary), read by our own parser: mshio reads 4.1 only.

use super::*;

/// One element of a 2.2 file: number, Gmsh type, physical tag, node tags.
pub(super) type Element22 = (u64, usize, Option<u64>, Vec<u64>);

/// The nodes (tag, coordinates) and elements of a 2.2 file.
pub(super) type Gmsh22 = (Vec<(u64, [f64; 3])>, Vec<Element22>);

pub(super) fn read_msh22(
    path: &Path,
    bytes: &[u8],
    names: &HashMap<(usize, i64), String>,
) -> Result<RawMesh, Error> {
    let fmt = find(bytes, b"$MeshFormat").unwrap_or(0);
    let header: Vec<String> = String::from_utf8_lossy(&bytes[fmt..(fmt + 64).min(bytes.len())])
        .lines()
        .nth(1)
        .unwrap_or("")
        .split_whitespace()
        .map(str::to_string)
        .collect();
    let (nodes, elements) = if header.get(1).map(String::as_str) == Some("1") {
        read_msh22_binary(path, bytes, &header)?
    } else {
        read_msh22_ascii(path, bytes)?
    };
    let mut raw = RawMesh::default();
    let mut index = HashMap::with_capacity(nodes.len());
    for (tag, x) in nodes {
        if index.insert(tag, raw.points.len()).is_some() {
            return Err(bad(
                path,
                format!("$Nodes: node tag {tag} is defined twice"),
            ));
        }
        raw.points.push(x);
        raw.ids.push(tag);
    }
    for (num, t, phys, tags) in elements {
        let (d, kind) = gmsh_kind(t);
        let ns: Vec<usize> = tags
            .iter()
            .map(|t| {
                index.get(t).copied().ok_or_else(|| {
                    bad(
                        path,
                        format!("element {num} refers to node tag {t}, which is not defined"),
                    )
                })
            })
            .collect::<Result<_, _>>()?;
        if let Some(p) = phys {
            let name = names
                .get(&(d, p as i64))
                .cloned()
                .unwrap_or_else(|| format!("physical_{p}"));
            raw.sets.entry(name).or_default().extend_from_slice(&ns);
        }
        let ns = match &kind {
            Ok(k) => k.from_gmsh_order(ns),
            Err(_) => ns,
        };
        raw.cells.push((d, kind, ns));
        raw.cell_ids.push(num);
    }
    Ok(raw)
}

/// The lines of section `$name` after its count line.
/// The lines of section `$name` after its count line, with their 1-based line numbers;
/// the count must match the lines.
pub(super) fn section22<'a>(
    path: &Path,
    text: &'a str,
    name: &str,
) -> Result<Vec<(usize, &'a str)>, Error> {
    let start = text
        .find(&format!("${name}"))
        .ok_or_else(|| bad(path, format!("no ${name} section")))?;
    let end = text[start..].find(&format!("$End{name}")).ok_or_else(|| {
        bad_at(
            path,
            format!("line {}", line_of(text.as_bytes(), start)),
            format!("${name} is not closed (truncated file?)"),
        )
    })?;
    let first = line_of(text.as_bytes(), start);
    let mut lines = text[start..start + end].lines().enumerate().skip(1);
    let (count_line, count) = lines
        .next()
        .map(|(i, l)| (first + i, l.trim()))
        .ok_or_else(|| bad(path, format!("${name} has no count line")))?;
    let body: Vec<(usize, &str)> = lines
        .map(|(i, l)| (first + i, l))
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    if count.parse::<usize>().ok() != Some(body.len()) {
        return Err(bad_at(
            path,
            format!("line {count_line}"),
            format!(
                "${name} count `{count}` does not match its {} lines",
                body.len()
            ),
        ));
    }
    Ok(body)
}

pub(super) fn read_msh22_ascii(path: &Path, bytes: &[u8]) -> Result<Gmsh22, Error> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        bad_at(
            path,
            format!("line {}", line_of(bytes, e.valid_up_to())),
            "Gmsh 2.2 ASCII file holds non-UTF-8 bytes",
        )
    })?;
    let mut nodes = Vec::new();
    for (ln, line) in section22(path, text, "Nodes")? {
        let v: Vec<&str> = line.split_whitespace().collect();
        let err = || {
            bad_at(
                path,
                format!("line {ln}"),
                format!("$Nodes: `{}`; expected `tag x y z`", line.trim()),
            )
        };
        let num = |k: usize| -> Result<f64, Error> {
            v.get(k).and_then(|s| s.parse().ok()).ok_or_else(err)
        };
        let tag = v
            .first()
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(err)?;
        if v.len() != 4 {
            return Err(err());
        }
        nodes.push((tag, [num(1)?, num(2)?, num(3)?]));
    }
    let mut elements = Vec::new();
    for (ln, line) in section22(path, text, "Elements")? {
        let err = || {
            bad_at(
                path,
                format!("line {ln}"),
                format!(
                    "$Elements: `{}`; expected `number type ntags tags… nodes…` with non-negative integers",
                    line.trim()
                ),
            )
        };
        let v: Vec<u64> = line
            .split_whitespace()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()
            .map_err(|_| err())?;
        let ntags = v
            .get(2)
            .and_then(|&n| usize::try_from(n).ok())
            .ok_or_else(err)?;
        if ntags > v.len().saturating_sub(3) {
            return Err(err());
        }
        let t = usize::try_from(v[1]).map_err(|_| err())?;
        let nodes = &v[3 + ntags..];
        if let Some(nn) = gmsh_nodes(t)
            && nn != nodes.len()
        {
            return Err(bad_at(
                path,
                format!("line {ln}"),
                format!(
                    "$Elements: element {} of type {t} lists {} nodes; that type has {nn}",
                    v[0],
                    nodes.len()
                ),
            ));
        }
        let phys = if ntags > 0 { Some(v[3]) } else { None };
        elements.push((v[0], t, phys, nodes.to_vec()));
    }
    Ok((nodes, elements))
}

/// Gmsh 2.2 binary: after `$Nodes` and its count line, `n` records of (i32 tag,
/// 3 × f64); after `$Elements` and its count line, blocks of an i32 header (type,
/// count, tags) followed by `count` records of i32 (number, tags, nodes). The file's
/// `1` after the header tells its byte order; little-endian files are read.
pub(super) fn read_msh22_binary(
    path: &Path,
    bytes: &[u8],
    header: &[String],
) -> Result<Gmsh22, Error> {
    if header.get(2).map(String::as_str) != Some("8") {
        return Err(bad(
            path,
            format!(
                "Gmsh 2.2 binary with data size {} (expected 8)",
                header.get(2).map_or("missing", String::as_str)
            ),
        ));
    }
    let fmt = find(bytes, b"$MeshFormat").unwrap_or(0);
    let after_header = fmt
        + bytes[fmt..]
            .iter()
            .enumerate()
            .filter(|(_, b)| **b == b'\n')
            .nth(1)
            .map(|(i, _)| i + 1)
            .ok_or_else(|| bad(path, "truncated $MeshFormat"))?;
    let one = bytes
        .get(after_header..after_header + 4)
        .ok_or_else(|| bad(path, "truncated $MeshFormat"))?;
    if i32::from_le_bytes(one.try_into().unwrap()) != 1 {
        return Err(bad(
            path,
            "Gmsh 2.2 binary file is big-endian (signorini reads little-endian files)",
        ));
    }
    // the position just after `$name\n<count>\n`, and the count
    let open = |name: &str| -> Result<(usize, usize), Error> {
        let tag = format!("${name}\n");
        let start = find(bytes, tag.as_bytes())
            .ok_or_else(|| bad(path, format!("no ${name} section")))?
            + tag.len();
        let nl = bytes[start..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| bad(path, format!("${name} has no count line")))?;
        let count = std::str::from_utf8(&bytes[start..start + nl])
            .ok()
            .and_then(|s| s.trim().parse().ok())
            .ok_or_else(|| bad(path, format!("${name} count is not a number")))?;
        Ok((start + nl + 1, count))
    };
    let short = |name: &str| {
        bad(
            path,
            format!(
                "truncated: ${name} data runs past the end of the file ({} bytes)",
                bytes.len()
            ),
        )
    };
    let i32_at = |p: usize| -> Option<i32> {
        bytes
            .get(p..p + 4)
            .map(|b| i32::from_le_bytes(b.try_into().unwrap()))
    };
    let f64_at = |p: usize| -> Option<f64> {
        bytes
            .get(p..p + 8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
    };
    let (mut p, n) = open("Nodes")?;
    let n = crate::limits::check_count(
        path,
        &format!("byte {p}"),
        "$Nodes",
        n as u64,
        28,
        (bytes.len() - p) as u64,
    )?;
    let mut nodes = Vec::with_capacity(n);
    for _ in 0..n {
        let tag = i32_at(p).ok_or_else(|| short("Nodes"))?;
        let x = [f64_at(p + 4), f64_at(p + 12), f64_at(p + 20)];
        let [Some(x0), Some(x1), Some(x2)] = x else {
            return Err(short("Nodes"));
        };
        if tag < 0 {
            return Err(bad_at(
                path,
                format!("byte {p}"),
                format!("$Nodes: negative node tag {tag}"),
            ));
        }
        nodes.push((tag as u64, [x0, x1, x2]));
        p += 28;
    }
    let (mut p, n) = open("Elements")?;
    let n = crate::limits::check_count(
        path,
        &format!("byte {p}"),
        "$Elements",
        n as u64,
        8,
        (bytes.len() - p) as u64,
    )?;
    let mut elements = Vec::with_capacity(n);
    while elements.len() < n {
        let (Some(t), Some(count), Some(ntags)) = (i32_at(p), i32_at(p + 4), i32_at(p + 8)) else {
            return Err(short("Elements"));
        };
        p += 12;
        let t = t as usize;
        let nn = gmsh_nodes(t).ok_or_else(|| {
            bad(
                path,
                format!("element type {t} is unknown (in a binary $Elements block)"),
            )
        })?;
        let rec_bytes = 4 * (1 + ntags.max(0) as u64 + nn as u64);
        if count <= 0
            || ntags < 0
            || elements.len() + count as usize > n
            || (count as u64).saturating_mul(rec_bytes) > (bytes.len() - p.min(bytes.len())) as u64
        {
            return Err(bad_at(
                path,
                format!("byte {}", p - 12),
                format!(
                    "$Elements block header (type {t}, count {count}, tags {ntags}) does not fit \
                     the {} elements announced and the bytes left",
                    n
                ),
            ));
        }
        let ntags = ntags as usize;
        for _ in 0..count {
            let rec: Vec<i32> = (0..1 + ntags + nn)
                .map(|k| i32_at(p + 4 * k))
                .collect::<Option<_>>()
                .ok_or_else(|| short("Elements"))?;
            p += 4 * rec.len();
            if rec.iter().any(|&v| v < 0) {
                return Err(bad_at(
                    path,
                    format!("byte {}", p - 4 * rec.len()),
                    format!(
                        "$Elements: element {} has a negative number or tag {rec:?}",
                        rec[0]
                    ),
                ));
            }
            let phys = if ntags > 0 { Some(rec[1] as u64) } else { None };
            let tags = rec[1 + ntags..].iter().map(|&v| v as u64).collect();
            elements.push((rec[0] as u64, t, phys, tags));
        }
    }
    Ok((nodes, elements))
}
