//! Mesh input: Gmsh `.msh` (4.1 ASCII and binary through mshio; 2.2 ASCII and binary and the
//! `$PhysicalNames` section, which mshio skips, by our own small parsers), VTK XML
//! `.vtu` (our reader on quick-xml, `io::vtu`: ascii, inline binary with or without
//! zlib, raw and base64 appended data) and legacy `.vtk` (our parser: vtkio reads
//! neither meshio's default legacy 5.1 binary files nor their OFFSETS/CONNECTIVITY
//! layout; DESIGN.md §6).
//!
//! The cells of the highest dimension present (tet4/hex8, else tri3/quad4) become the
//! mesh; lower-dimensional elements only define node sets. Node sets: Gmsh physical
//! groups by name (or `physical_<tag>`), VTK integer point-data arrays as flags (node
//! in the set where non-zero). Nodes used by no cell are dropped (they would carry no
//! mass). Every error names the file and what is wrong.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use crate::error::Error;
use crate::model::solid::{CellKind, Mesh};

fn bad(path: &Path, what: impl std::fmt::Display) -> Error {
    Error::bad_file(path, "", what)
}

fn bad_at(path: &Path, at: impl std::fmt::Display, what: impl std::fmt::Display) -> Error {
    Error::bad_file(path, at, what)
}

/// The 1-based line holding byte `pos` of `bytes`.
fn line_of(bytes: &[u8], pos: usize) -> usize {
    1 + bytes[..pos.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// A third-party parser's message, cut to its first line and 200 characters (some
/// quote the rest of the file).
fn short_message(e: impl std::fmt::Display) -> String {
    let s = e.to_string();
    let line = s.lines().next().unwrap_or("");
    if line.chars().count() > 200 {
        format!("{}…", line.chars().take(200).collect::<String>())
    } else {
        line.to_string()
    }
}

/// Reads a mesh, choosing the format by extension (`.msh`, `.vtu`, `.vtk`). The file
/// must be a regular file of at most [`crate::limits::MAX_MESH_BYTES`].
pub fn read_mesh(path: &Path) -> Result<Mesh, Error> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !["msh", "vtu", "vtk"].contains(&ext.to_ascii_lowercase().as_str()) {
        return Err(bad(
            path,
            format!("unknown mesh extension `.{ext}` (expected .msh, .vtu or .vtk)"),
        ));
    }
    let bytes = crate::limits::read_input(path, "mesh", crate::limits::MAX_MESH_BYTES)?;
    parse_mesh(path, &bytes)
}

/// Parses the bytes of a mesh file; `path` chooses the format by extension and names
/// the file in errors (the fuzz targets call this directly).
pub fn parse_mesh(path: &Path, bytes: &[u8]) -> Result<Mesh, Error> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let raw = match ext.as_str() {
        "msh" => read_msh(path, bytes)?,
        "vtu" => read_vtu(path, bytes)?,
        "vtk" => read_legacy_vtk(path, bytes)?,
        _ => {
            return Err(bad(
                path,
                format!("unknown mesh extension `.{ext}` (expected .msh, .vtu or .vtk)"),
            ));
        }
    };
    raw.finish(path)
}

/// A mesh as read, before keeping the top-dimension cells and compacting the nodes.
#[derive(Default)]
struct RawMesh {
    points: Vec<[f64; 3]>,
    /// (dimension, kind or unsupported name, nodes)
    cells: Vec<(usize, Result<CellKind, String>, Vec<usize>)>,
    /// node sets by name (indices into `points`)
    sets: BTreeMap<String, Vec<usize>>,
    /// the file's id of each point (Gmsh node tag; empty: the 0-based index in the file)
    ids: Vec<u64>,
    /// the file's id of each cell (Gmsh element number; empty: the 0-based index)
    cell_ids: Vec<u64>,
}

impl RawMesh {
    fn finish(self, path: &Path) -> Result<Mesh, Error> {
        for (i, p) in self.points.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(bad(
                    path,
                    format!(
                        "node {} has non-finite coordinates {p:?}",
                        self.ids.get(i).copied().unwrap_or(i as u64)
                    ),
                ));
            }
        }
        let dim = self
            .cells
            .iter()
            .map(|c| c.0)
            .max()
            .ok_or_else(|| bad(path, "no cells"))?;
        if dim < 2 {
            return Err(bad(path, "no 2-D or 3-D cells (only points or lines)"));
        }
        let mut used = vec![usize::MAX; self.points.len()];
        let mut mesh = Mesh::default();
        for (id, (d, kind, nodes)) in self.cells.iter().enumerate() {
            if *d != dim {
                continue;
            }
            let kind = kind.clone().map_err(|name| {
                bad(path, format!("cell {id}: unsupported element type {name} (signorini reads tri3, quad4, tet4, hex8)"))
            })?;
            if nodes.len() != kind.nodes() {
                return Err(bad(
                    path,
                    format!(
                        "cell {id} ({}) has {} nodes; expected {}",
                        kind.name(),
                        nodes.len(),
                        kind.nodes()
                    ),
                ));
            }
            let mut c = Vec::with_capacity(nodes.len());
            for &v in nodes {
                if v >= self.points.len() {
                    return Err(bad(
                        path,
                        format!(
                            "cell {id} refers to node {v}, but the file defines {} nodes",
                            self.points.len()
                        ),
                    ));
                }
                if used[v] == usize::MAX {
                    used[v] = mesh.points.len();
                    mesh.points.push(self.points[v]);
                    mesh.node_ids
                        .push(self.ids.get(v).copied().unwrap_or(v as u64));
                }
                c.push(used[v]);
            }
            mesh.cells.push((kind, c));
            mesh.cell_ids
                .push(self.cell_ids.get(id).copied().unwrap_or(id as u64));
        }
        mesh.source = Some(path.to_path_buf());
        for (name, set) in self.sets {
            let mut s: Vec<usize> = set
                .iter()
                .filter(|&&v| v < used.len() && used[v] != usize::MAX)
                .map(|&v| used[v])
                .collect();
            s.sort_unstable();
            s.dedup();
            mesh.node_sets.insert(name, s);
        }
        Ok(mesh)
    }
}

fn gmsh_kind(t: usize) -> (usize, Result<CellKind, String>) {
    match t {
        2 => (2, Ok(CellKind::Tri3)),
        3 => (2, Ok(CellKind::Quad4)),
        4 => (3, Ok(CellKind::Tet4)),
        5 => (3, Ok(CellKind::Hex8)),
        1 | 8 | 26 | 27 | 28 => (1, Err(format!("gmsh type {t} (line)"))),
        15 => (0, Err("gmsh type 15 (point)".into())),
        9 | 10 | 16 | 20 | 21 | 22 | 23 | 24 | 25 => {
            (2, Err(format!("gmsh type {t} (higher-order surface)")))
        }
        11 | 12 | 17 | 18 | 19 | 29 | 30 | 31 | 92 | 93 => (
            3,
            Err(format!(
                "gmsh type {t} (higher-order or prism/pyramid volume)"
            )),
        ),
        6 | 7 => (3, Err(format!("gmsh type {t} (prism/pyramid)"))),
        _ => (0, Err(format!("gmsh type {t} (unknown)"))),
    }
}

/// `$PhysicalNames`: (dim, tag) → name. Present as text in ASCII and binary files.
fn physical_names(text: &[u8]) -> HashMap<(usize, i64), String> {
    let mut out = HashMap::new();
    let Some(start) = find(text, b"$PhysicalNames") else {
        return out;
    };
    let Some(end) = find(&text[start..], b"$EndPhysicalNames") else {
        return out;
    };
    let body = String::from_utf8_lossy(&text[start + 14..start + end]);
    for line in body.lines().skip(2) {
        let mut it = line.splitn(3, char::is_whitespace);
        if let (Some(d), Some(t), Some(n)) = (it.next(), it.next(), it.next())
            && let (Ok(d), Ok(t)) = (d.parse(), t.parse())
        {
            out.insert((d, t), n.trim().trim_matches('"').to_string());
        }
    }
    out
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

fn read_msh(path: &Path, bytes: &[u8]) -> Result<RawMesh, Error> {
    let fmt = find(bytes, b"$MeshFormat")
        .ok_or_else(|| bad(path, "no $MeshFormat section: not a Gmsh file"))?;
    let version: String = String::from_utf8_lossy(&bytes[fmt + 11..(fmt + 40).min(bytes.len())])
        .split_whitespace()
        .next()
        .unwrap_or("")
        .to_string();
    let names = physical_names(bytes);
    match version.as_str() {
        "4.1" => read_msh41(path, bytes, &names),
        "2.2" => read_msh22(path, bytes, &names),
        v => Err(bad(
            path,
            format!("Gmsh format version {v} (signorini reads 4.1 and 2.2)"),
        )),
    }
}

/// Checks the counts of a Gmsh 4.1 section header (`$Nodes`: blocks, nodes, min and max
/// tag; `$Elements`: blocks, elements, min and max tag) against the file's size before
/// mshio allocates from them: a node takes at least 8 bytes (its tag and coordinates),
/// an element 4, a block 8.
fn check_msh41_counts(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    for (section, each) in [("$Nodes", 8u64), ("$Elements", 4)] {
        let Some(start) = find(bytes, section.as_bytes()) else {
            continue;
        };
        let after = start + section.len();
        let binary = bytes.get(after) != Some(&b'\n') || find(&bytes[..start], b"4.1 1").is_some();
        let left = (bytes.len() - after) as u64;
        let counts: Vec<u64> = if binary {
            // four size_t after the newline
            (0..2)
                .filter_map(|k| {
                    let p = after + 1 + 8 * k;
                    bytes
                        .get(p..p + 8)
                        .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
                })
                .collect()
        } else {
            let line_end = bytes[after + 1..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(bytes.len(), |e| after + 1 + e);
            String::from_utf8_lossy(&bytes[(after + 1).min(line_end)..line_end])
                .split_whitespace()
                .take(2)
                .filter_map(|t| t.parse().ok())
                .collect()
        };
        let at = format!("line {}", line_of(bytes, after + 1));
        if let [blocks, items] = counts[..] {
            crate::limits::check_count(path, &at, &format!("{section} block"), blocks, 8, left)?;
            crate::limits::check_count(path, &at, &format!("{section} entry"), items, each, left)?;
        }
    }
    Ok(())
}

/// Refuses a Gmsh 4.1 `$Nodes` section that defines a node tag twice. mshio keeps the
/// tags of a block in a map (a repeated tag silently replaces the first) and discards
/// them when the block's tag range looks dense, so the check reads the tags itself; it
/// runs after mshio parsed the file, so the section's layout is known to be sound
/// (ASCII: whitespace-separated numbers; binary: `int` entity fields, `size_t` counts
/// and tags, three `f64` per node).
fn check_msh41_node_tags(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let Some(start) = find(bytes, b"$Nodes") else {
        return Ok(());
    };
    let after = start + b"$Nodes".len() + 1;
    let binary = find(&bytes[..start], b"4.1 1").is_some();
    let mut seen = std::collections::HashSet::new();
    let mut dup = |tag: u64| -> Result<(), Error> {
        if seen.insert(tag) {
            Ok(())
        } else {
            Err(bad(
                path,
                format!("$Nodes: node tag {tag} is defined twice"),
            ))
        }
    };
    if binary {
        let rd = |p: usize, n: usize| bytes.get(p..p + n);
        let u64_at = |p: usize| rd(p, 8).map(|b| u64::from_le_bytes(b.try_into().expect("8")));
        let Some(blocks) = u64_at(after) else {
            return Ok(());
        };
        let mut p = after + 32;
        for _ in 0..blocks {
            let Some(n) = u64_at(p + 12) else {
                return Ok(());
            };
            p += 20;
            for _ in 0..n {
                let Some(tag) = u64_at(p) else {
                    return Ok(());
                };
                dup(tag)?;
                p += 8;
            }
            p = p.saturating_add((n as usize).saturating_mul(24));
        }
    } else {
        let end = find(&bytes[after..], b"$EndNodes").map_or(bytes.len(), |e| after + e);
        let text = String::from_utf8_lossy(&bytes[after..end]);
        let mut it = text.split_ascii_whitespace().map(|t| t.parse::<u64>().ok());
        let Some(Some(blocks)) = it.next() else {
            return Ok(());
        };
        for _ in 0..3 {
            it.next();
        }
        for _ in 0..blocks {
            // dim, tag, parametric, count; then the tags; then x y z per node
            let head: Vec<Option<u64>> = it.by_ref().take(4).collect();
            let Some(&Some(n)) = head.get(3) else {
                return Ok(());
            };
            for _ in 0..n {
                match it.next() {
                    Some(Some(tag)) => dup(tag)?,
                    _ => return Ok(()),
                }
            }
            // coordinates are not integers: skip them by count
            for _ in 0..n.saturating_mul(3) {
                it.next();
            }
        }
    }
    Ok(())
}

fn read_msh41(
    path: &Path,
    bytes: &[u8],
    names: &HashMap<(usize, i64), String>,
) -> Result<RawMesh, Error> {
    check_msh41_counts(path, bytes)?;
    let f = guarded(|| mshio::parse_msh_bytes(bytes).map_err(short_message))
        .unwrap_or_else(|| Err("the file is malformed (mshio could not read it)".into()))
        .map_err(|e| bad(path, format!("Gmsh 4.1 parse error: {e}")))?;
    check_msh41_node_tags(path, bytes)?;
    let nodes = f.data.nodes.ok_or_else(|| bad(path, "no $Nodes section"))?;
    let elements = f
        .data
        .elements
        .ok_or_else(|| bad(path, "no $Elements section"))?;
    let mut raw = RawMesh::default();
    // node tag → index
    let mut index: HashMap<u64, usize> = HashMap::new();
    let dense = nodes.node_blocks.iter().all(|b| b.node_tags.is_none());
    for b in &nodes.node_blocks {
        match &b.node_tags {
            Some(tags) => {
                let base = raw.points.len();
                raw.ids.resize(base + b.nodes.len(), 0);
                for (tag, &k) in tags {
                    if let Some(id) = raw.ids.get_mut(base + k) {
                        *id = *tag;
                    }
                    if index.insert(*tag, base + k).is_some() {
                        return Err(bad(
                            path,
                            format!("$Nodes: node tag {tag} is defined twice"),
                        ));
                    }
                }
            }
            None if dense => {
                let base = raw.points.len() as u64;
                raw.ids
                    .extend((0..b.nodes.len() as u64).map(|k| nodes.min_node_tag + base + k));
            }
            None => {
                return Err(bad(
                    path,
                    "mixed sparse and dense node tags are not supported",
                ));
            }
        }
        raw.points.extend(b.nodes.iter().map(|n| [n.x, n.y, n.z]));
    }
    let min_tag = nodes.min_node_tag;
    let node_index = |t: u64| -> Result<usize, Error> {
        if dense {
            t.checked_sub(min_tag)
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| {
                    bad(
                        path,
                        format!("element refers to node tag {t}, below the smallest tag {min_tag}"),
                    )
                })
        } else {
            index.get(&t).copied().ok_or_else(|| {
                bad(
                    path,
                    format!("element refers to node tag {t}, which is not defined"),
                )
            })
        }
    };
    // entity (dim, tag) → physical tags
    let mut phys: HashMap<(usize, i32), Vec<i32>> = HashMap::new();
    if let Some(ent) = &f.data.entities {
        for p in &ent.points {
            phys.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &ent.curves {
            phys.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &ent.surfaces {
            phys.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &ent.volumes {
            phys.insert((3, v.tag), v.physical_tags.clone());
        }
    }
    for b in &elements.element_blocks {
        let (d, kind) = gmsh_kind(b.element_type as usize);
        let edim = b.entity_dim as usize;
        let groups = phys.get(&(edim, b.entity_tag)).cloned().unwrap_or_default();
        for e in &b.elements {
            let ns: Vec<usize> = e
                .nodes
                .iter()
                .map(|&t| node_index(t))
                .collect::<Result<_, _>>()?;
            for g in &groups {
                let name = names
                    .get(&(edim, *g as i64))
                    .cloned()
                    .unwrap_or_else(|| format!("physical_{g}"));
                raw.sets.entry(name).or_default().extend_from_slice(&ns);
            }
            raw.cells.push((d, kind.clone(), ns));
            raw.cell_ids.push(e.element_tag);
        }
    }
    Ok(raw)
}

/// Nodes per element of the Gmsh element types a 2.2 binary file may hold (its records
/// do not carry their length).
fn gmsh_nodes(t: usize) -> Option<usize> {
    Some(match t {
        15 => 1,
        1 => 2,
        2 | 8 => 3,
        3 | 4 => 4,
        7 => 5,
        6 | 9 => 6,
        5 | 16 => 8,
        10 => 9,
        11 => 10,
        17 => 20,
        12 => 27,
        _ => return None,
    })
}

/// One element of a 2.2 file: number, Gmsh type, physical tag, node tags.
type Element22 = (u64, usize, Option<u64>, Vec<u64>);

/// The nodes (tag, coordinates) and elements of a 2.2 file.
type Gmsh22 = (Vec<(u64, [f64; 3])>, Vec<Element22>);

fn read_msh22(
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
        raw.cells.push((d, kind, ns));
        raw.cell_ids.push(num);
    }
    Ok(raw)
}

/// The lines of section `$name` after its count line.
/// The lines of section `$name` after its count line, with their 1-based line numbers;
/// the count must match the lines.
fn section22<'a>(path: &Path, text: &'a str, name: &str) -> Result<Vec<(usize, &'a str)>, Error> {
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

fn read_msh22_ascii(path: &Path, bytes: &[u8]) -> Result<Gmsh22, Error> {
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
fn read_msh22_binary(path: &Path, bytes: &[u8], header: &[String]) -> Result<Gmsh22, Error> {
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

fn vtk_kind(t: u8) -> (usize, Result<CellKind, String>) {
    match t {
        5 => (2, Ok(CellKind::Tri3)),
        9 => (2, Ok(CellKind::Quad4)),
        10 => (3, Ok(CellKind::Tet4)),
        12 => (3, Ok(CellKind::Hex8)),
        1 | 2 => (0, Err(format!("VTK type {t} (vertex)"))),
        3 | 4 => (1, Err(format!("VTK type {t} (line)"))),
        6..=8 => (2, Err(format!("VTK type {t} (polygon/pixel)"))),
        11 | 13 | 14 => (3, Err(format!("VTK type {t} (voxel/wedge/pyramid)"))),
        _ => (3, Err(format!("VTK type {t} (quadratic or unknown)"))),
    }
}

thread_local! {
    /// Set while [`guarded`] runs a third-party parser on this thread.
    static GUARDED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs a third-party parser that may panic on malformed input (mshio) and turns a
/// panic into `None`: a bad file is an error, not a crash. The panic's message is
/// silenced by a process-wide hook installed once, which stays quiet only for the
/// thread inside `guarded` and hands every other panic to the hook it replaced (swapping
/// the hook around each call raced with panics on other threads).
fn guarded<T>(f: impl FnOnce() -> T + std::panic::UnwindSafe) -> Option<T> {
    static INSTALL: std::sync::Once = std::sync::Once::new();
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !GUARDED.with(|g| g.get()) {
                previous(info);
            }
        }));
    });
    GUARDED.with(|g| g.set(true));
    let r = std::panic::catch_unwind(f);
    GUARDED.with(|g| g.set(false));
    r.ok()
}

fn read_vtu(path: &Path, bytes: &[u8]) -> Result<RawMesh, Error> {
    let pieces = super::vtu::read(path, bytes)?;
    let mut raw = RawMesh::default();
    for (pi, p) in pieces.into_iter().enumerate() {
        let base = raw.points.len();
        raw.points
            .extend(p.xyz.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let index = |what: &str, c: usize, v: f64| -> Result<usize, Error> {
            if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
                Ok(v as usize)
            } else {
                Err(bad(
                    path,
                    format!("piece {pi}, cell {c}: {what} {v} is not a non-negative integer"),
                ))
            }
        };
        // VTK's offsets are the cells' end positions; some writers lead with a 0
        let offs: &[f64] = if p.offsets.len() == p.cells + 1 && p.offsets.first() == Some(&0.0) {
            &p.offsets[1..]
        } else {
            &p.offsets
        };
        if offs.len() != p.types.len() {
            return Err(bad(
                path,
                format!(
                    "piece {pi}: {} cell offsets but {} cell types",
                    offs.len(),
                    p.types.len()
                ),
            ));
        }
        let mut start = 0usize;
        for (c, (&t, &end)) in p.types.iter().zip(offs).enumerate() {
            let end = index("offset", c, end)?;
            if end < start || end > p.connectivity.len() {
                return Err(bad(
                    path,
                    format!(
                        "piece {pi}, cell {c}: offset {end} is outside [{start}, {}] (offsets \
                         must grow and stay within the connectivity)",
                        p.connectivity.len()
                    ),
                ));
            }
            let t = index("type", c, t)?;
            let (d, kind) = vtk_kind(u8::try_from(t).unwrap_or(u8::MAX));
            let mut ns = Vec::with_capacity(end - start);
            for &v in &p.connectivity[start..end] {
                ns.push(base.saturating_add(index("point index", c, v)?));
            }
            raw.cells.push((d, kind, ns));
            start = end;
        }
        for (name, vals) in p.point_data {
            let set = vals
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(i, _)| base + i);
            raw.sets.entry(name).or_default().extend(set);
        }
    }
    Ok(raw)
}

/// Legacy `.vtk`, ASCII or BINARY (big-endian), versions up to 5.1 (meshio's default):
/// POINTS, CELLS (classic list or OFFSETS/CONNECTIVITY), CELL_TYPES, and POINT_DATA
/// SCALARS or FIELD arrays (read as node-set flags).
fn read_legacy_vtk(path: &Path, bytes: &[u8]) -> Result<RawMesh, Error> {
    let mut r = Reader {
        b: bytes,
        pos: 0,
        binary: false,
        path,
    };
    let header = r.line()?;
    if !header.starts_with("# vtk DataFile") {
        return Err(bad(path, "not a legacy VTK file (first line)"));
    }
    r.line()?; // title
    r.binary = match r.line()?.trim() {
        "BINARY" => true,
        "ASCII" => false,
        other => {
            return Err(bad(
                path,
                format!("expected ASCII or BINARY, found `{other}`"),
            ));
        }
    };
    let ds = r.line()?;
    if ds.trim() != "DATASET UNSTRUCTURED_GRID" {
        return Err(bad(
            path,
            format!("only UNSTRUCTURED_GRID is supported, found `{}`", ds.trim()),
        ));
    }
    let mut raw = RawMesh::default();
    let mut conn: Vec<u64> = Vec::new();
    let mut offsets: Vec<u64> = Vec::new();
    let mut types: Vec<u8> = Vec::new();
    let mut npoints = 0usize;
    while let Some(line) = r.next_keyword_line()? {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w[0] {
            "POINTS" => {
                npoints = r.count(&w, 1)?;
                let n3 = npoints
                    .checked_mul(3)
                    .ok_or_else(|| r.err("POINTS count overflows"))?;
                let v = r.values(n3, w.get(2).copied().unwrap_or("float"))?;
                raw.points = v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
            }
            "CELLS" => {
                let n = r.count(&w, 1)?;
                let size = r.count(&w, 2)?;
                // version 5: OFFSETS <type> (n values) then CONNECTIVITY <type> (size values)
                let save = r.pos;
                let next = r.next_keyword_line()?.unwrap_or_default();
                if next.starts_with("OFFSETS") {
                    let t = next
                        .split_whitespace()
                        .nth(1)
                        .unwrap_or("vtktypeint64")
                        .to_string();
                    offsets = r.indices(n, &t, "OFFSETS")?;
                    let c = r.next_keyword_line()?.unwrap_or_default();
                    if !c.starts_with("CONNECTIVITY") {
                        return Err(bad(path, "OFFSETS not followed by CONNECTIVITY"));
                    }
                    let t = c
                        .split_whitespace()
                        .nth(1)
                        .unwrap_or("vtktypeint64")
                        .to_string();
                    conn = r.indices(size, &t, "CONNECTIVITY")?;
                } else {
                    r.pos = save;
                    let at = r.where_();
                    let list = r.indices(size, "int", "CELLS")?;
                    let mut k = 0;
                    offsets.push(0);
                    for c in 0..n {
                        let m = list.get(k).map(|&m| m as usize);
                        let Some(cell) = m.and_then(|m| list.get(k + 1..k.checked_add(1 + m)?))
                        else {
                            return Err(bad_at(
                                path,
                                at,
                                format!(
                                    "CELLS {n} {size}: cell {c} runs past the list's {size} \
                                     values (each cell is its node count then its nodes)"
                                ),
                            ));
                        };
                        conn.extend_from_slice(cell);
                        offsets.push(conn.len() as u64);
                        k += 1 + cell.len();
                    }
                    if k != list.len() {
                        return Err(bad_at(
                            path,
                            at,
                            format!("CELLS {n} {size}: the {n} cells use {k} of the {size} values"),
                        ));
                    }
                }
            }
            "CELL_TYPES" => {
                let n = r.count(&w, 1)?;
                types = r
                    .indices(n, "int", "CELL_TYPES")?
                    .iter()
                    .map(|&x| u8::try_from(x).unwrap_or(u8::MAX))
                    .collect();
            }
            "POINT_DATA" | "CELL_DATA" => {
                let on_points = w[0] == "POINT_DATA";
                let n = r.count(&w, 1)?;
                loop {
                    let save = r.pos;
                    let Some(l) = r.next_keyword_line()? else {
                        break;
                    };
                    let v: Vec<&str> = l.split_whitespace().collect();
                    match v[0] {
                        "SCALARS" => {
                            let ncomp: usize = match v.get(3) {
                                None => 1,
                                Some(s) => s
                                    .parse()
                                    .ok()
                                    .filter(|&c| (1..=4).contains(&c))
                                    .ok_or_else(|| {
                                        r.err(format!(
                                            "SCALARS {}: component count `{s}` is not in 1..=4",
                                            v.get(1).unwrap_or(&"")
                                        ))
                                    })?,
                            };
                            let lt = r.next_keyword_line()?.unwrap_or_default();
                            if !lt.starts_with("LOOKUP_TABLE") {
                                return Err(bad(path, "SCALARS without LOOKUP_TABLE"));
                            }
                            let name = *v
                                .get(1)
                                .ok_or_else(|| r.err("SCALARS without an array name"))?;
                            let total = n
                                .checked_mul(ncomp)
                                .ok_or_else(|| r.err("SCALARS size overflows"))?;
                            let vals = r.values(total, v.get(2).copied().unwrap_or("float"))?;
                            if on_points && ncomp == 1 {
                                add_flag_set(&mut raw, name, &vals);
                            }
                        }
                        "FIELD" => {
                            let arrays = r.count(&v, 2)?;
                            for _ in 0..arrays {
                                let a = r.next_keyword_line()?.unwrap_or_default();
                                let f: Vec<&str> = a.split_whitespace().collect();
                                let (ncomp, ntup) = (r.count(&f, 1)?, r.count(&f, 2)?);
                                let total = ncomp
                                    .checked_mul(ntup)
                                    .ok_or_else(|| r.err("FIELD array size overflows"))?;
                                let vals = r.values(total, f.get(3).copied().unwrap_or("float"))?;
                                if on_points && ncomp == 1 && ntup == n {
                                    let name = *f
                                        .first()
                                        .ok_or_else(|| r.err("FIELD array without a name"))?;
                                    add_flag_set(&mut raw, name, &vals);
                                }
                            }
                        }
                        "VECTORS" | "NORMALS" => {
                            let n3 = n
                                .checked_mul(3)
                                .ok_or_else(|| r.err("VECTORS count overflows"))?;
                            r.values(n3, v.get(2).copied().unwrap_or("float"))?;
                        }
                        _ => {
                            r.pos = save;
                            break;
                        }
                    }
                }
            }
            "METADATA" => {
                // skip until a blank line
                while let Ok(l) = r.line() {
                    if l.trim().is_empty() {
                        break;
                    }
                }
            }
            other => {
                return Err(r.err(format!(
                    "unexpected section `{other}` (expected POINTS, CELLS, CELL_TYPES, \
                     POINT_DATA, CELL_DATA or METADATA)"
                )));
            }
        }
    }
    if raw.points.len() != npoints || npoints == 0 {
        return Err(bad(path, "no POINTS section (or POINTS 0)"));
    }
    let offs: Vec<u64> = if offsets.first() == Some(&0) {
        offsets[1..].to_vec()
    } else {
        offsets
    };
    if offs.len() != types.len() {
        return Err(bad(
            path,
            format!("{} cells but {} CELL_TYPES", offs.len(), types.len()),
        ));
    }
    let mut start = 0usize;
    for (&t, &end) in types.iter().zip(&offs) {
        let end = end as usize;
        if end > conn.len() || end < start {
            return Err(bad(path, "cell offsets exceed the connectivity"));
        }
        let (d, kind) = vtk_kind(t);
        raw.cells.push((
            d,
            kind,
            conn[start..end].iter().map(|&v| v as usize).collect(),
        ));
        start = end;
    }
    Ok(raw)
}

fn add_flag_set(raw: &mut RawMesh, name: &str, vals: &[f64]) {
    let set = vals
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(i, _)| i);
    raw.sets.entry(name.to_string()).or_default().extend(set);
}

struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
    binary: bool,
    path: &'a Path,
}

impl Reader<'_> {
    /// `line L` of the current position.
    fn where_(&self) -> String {
        format!("line {}", line_of(self.b, self.pos.saturating_sub(1)))
    }

    /// An error at the current line.
    fn err(&self, what: impl std::fmt::Display) -> Error {
        bad_at(self.path, self.where_(), what)
    }

    /// `n` values read as indices or counts: whole numbers in `[0, 2⁵³]`.
    fn indices(&mut self, n: usize, ty: &str, what: &str) -> Result<Vec<u64>, Error> {
        let at = self.where_();
        let v = self.values(n, ty)?;
        v.iter()
            .map(|&x| {
                if x >= 0.0 && x.fract() == 0.0 && x <= 9.007_199_254_740_992e15 {
                    Ok(x as u64)
                } else {
                    Err(bad_at(
                        self.path,
                        &at,
                        format!("{what}: {x} is not a valid index (expected a whole number ≥ 0)"),
                    ))
                }
            })
            .collect()
    }

    fn line(&mut self) -> Result<String, Error> {
        if self.pos >= self.b.len() {
            return Err(self.err("truncated: the file ends where more was expected"));
        }
        let end = self.b[self.pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(self.b.len(), |e| self.pos + e);
        let s = String::from_utf8_lossy(&self.b[self.pos..end]).into_owned();
        self.pos = (end + 1).min(self.b.len());
        Ok(s)
    }

    /// Next non-blank line, or None at the end of the file.
    fn next_keyword_line(&mut self) -> Result<Option<String>, Error> {
        while self.pos < self.b.len() {
            let l = self.line()?;
            if !l.trim().is_empty() {
                return Ok(Some(l.trim().to_string()));
            }
        }
        Ok(None)
    }

    fn count(&self, w: &[&str], k: usize) -> Result<usize, Error> {
        w.get(k).and_then(|s| s.parse().ok()).ok_or_else(|| {
            self.err(format!(
                "`{}`: count {} is not a whole number",
                w.join(" "),
                w.get(k).unwrap_or(&"(missing)")
            ))
        })
    }

    fn values(&mut self, n: usize, ty: &str) -> Result<Vec<f64>, Error> {
        let left = (self.b.len() - self.pos) as u64;
        if !self.binary {
            // each ASCII value takes at least two bytes (a digit and a separator)
            let n = crate::limits::check_count(
                self.path,
                &self.where_(),
                "value",
                n as u64,
                2,
                left + 1,
            )?;
            let mut out = Vec::with_capacity(n);
            while out.len() < n {
                let l = self.line()?;
                for t in l.split_whitespace() {
                    out.push(
                        t.parse::<f64>()
                            .map_err(|_| self.err(format!("`{t}` is not a number")))?,
                    );
                }
            }
            if out.len() > n {
                return Err(self.err(format!(
                    "{} values on the lines of a block of {n}",
                    out.len()
                )));
            }
            return Ok(out);
        }
        let size = match ty {
            "double" | "vtktypeint64" | "long" | "vtktypeuint64" | "unsigned_long" => 8,
            "float" | "int" | "vtktypeint32" | "unsigned_int" | "vtktypeuint32" => 4,
            "short" | "unsigned_short" => 2,
            "char" | "unsigned_char" | "bit" => 1,
            other => return Err(self.err(format!("unsupported data type `{other}`"))),
        };
        crate::limits::check_count(
            self.path,
            &self.where_(),
            "value",
            n as u64,
            size as u64,
            left,
        )
        .map_err(|_| {
            self.err(format!(
                "truncated: {n} binary values of {size} bytes from byte {}, but the file \
                     ends at byte {}",
                self.pos,
                self.b.len()
            ))
        })?;
        let end = self.pos + n * size;
        let out = self.b[self.pos..end]
            .chunks(size)
            .map(|c| match (ty, size) {
                ("double", _) => f64::from_be_bytes(c.try_into().expect("8 bytes")),
                ("float", _) => f32::from_be_bytes(c.try_into().expect("4 bytes")) as f64,
                (t, 8) if t.contains("uint") || t.starts_with("unsigned") => {
                    u64::from_be_bytes(c.try_into().expect("8")) as f64
                }
                (_, 8) => i64::from_be_bytes(c.try_into().expect("8 bytes")) as f64,
                (t, 4) if t.contains("uint") || t.starts_with("unsigned") => {
                    u32::from_be_bytes(c.try_into().expect("4")) as f64
                }
                (_, 4) => i32::from_be_bytes(c.try_into().expect("4 bytes")) as f64,
                (t, 2) if t.starts_with("unsigned") => {
                    u16::from_be_bytes(c.try_into().expect("2")) as f64
                }
                (_, 2) => i16::from_be_bytes(c.try_into().expect("2 bytes")) as f64,
                (t, _) if t.starts_with("unsigned") || t == "bit" => c[0] as f64,
                _ => c[0] as i8 as f64,
            })
            .collect();
        self.pos = end;
        Ok(out)
    }
}
