//! Gmsh files through mshio (format 4.1, ASCII and binary) with the checks mshio
//! lacks (counts, node tags) made first, and what both formats share: the element
//! types, `$PhysicalNames` and the section search (`gmsh22.rs` reads 2.2 files with
//! them; the format-version dispatch, `read_msh`, is the parent module's).

use super::*;

pub(super) fn gmsh_kind(t: usize) -> (usize, Result<CellKind, String>) {
    if let Some(k) = CellKind::from_gmsh(t) {
        return (k.dim(), Ok(k));
    }
    match t {
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
pub(super) fn physical_names(text: &[u8]) -> HashMap<(usize, i64), String> {
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

pub(super) fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Checks the counts of a Gmsh 4.1 section header (`$Nodes`: blocks, nodes, min and max
/// tag; `$Elements`: blocks, elements, min and max tag) against the file's size before
/// mshio allocates from them: a node takes at least 8 bytes (its tag and coordinates),
/// an element 4, a block 8.
pub(super) fn check_msh41_counts(path: &Path, bytes: &[u8]) -> Result<(), Error> {
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
pub(super) fn check_msh41_node_tags(path: &Path, bytes: &[u8]) -> Result<(), Error> {
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

pub(super) fn read_msh41(
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
            let ns = match &kind {
                Ok(k) => k.from_gmsh_order(ns),
                Err(_) => ns,
            };
            raw.cells.push((d, kind.clone(), ns));
            raw.cell_ids.push(e.element_tag);
        }
    }
    Ok(raw)
}

/// Nodes per element of the Gmsh element types a 2.2 binary file may hold (its records
/// do not carry their length).
pub(super) fn gmsh_nodes(t: usize) -> Option<usize> {
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
