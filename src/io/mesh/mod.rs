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

mod gmsh22;
mod gmsh41;
mod vtk;

use gmsh22::*;
use gmsh41::*;
use vtk::*;

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
                bad(
                    path,
                    format!(
                        "cell {id}: unsupported element type {name} (signorini reads {})",
                        CellKind::names(None)
                    ),
                )
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

/// A Gmsh file of any version signorini reads: 4.1 (`gmsh41.rs`) or 2.2 (`gmsh22.rs`),
/// chosen by its `$MeshFormat` line.
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
