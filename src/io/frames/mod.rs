//! Field output for ParaView: one `.vtu` (VTK XML unstructured grid) per saved frame and
//! one `.pvd` collection listing the frames with their times (issue 4, DESIGN.md §6).
//!
//! Point data: `displacement` and `velocity` (vectors, m and m/s), `contact_force`
//! (vector `G P / h` at the contact nodes, zero elsewhere, N) and `gap` (m, at the
//! candidate nodes, NaN elsewhere so ParaView leaves the others blank). Cell data, at
//! the cell centre: `strain` and `stress` (symmetric tensors in ParaView's order
//! `XX, YY, ZZ, XY, YZ, XZ`; Pa for stress) and `von_mises` (Pa). Rods are lines with the
//! uniaxial stress `E ∂u/∂x`. A scene with a large-deformation body (material model `svk`
//! or `neo-hookean`) names its tensors `green_lagrange_strain` and `cauchy_stress`
//! instead: `E = (FᵀF − I)/2` and `σ = F S Fᵀ / J` at the centre of each cell of such a
//! body (NaN for a cell inverted there), the small strain and Hooke stress elsewhere. Field data: `TimeValue` (s) and `Step`. Every array
//! carries its SI unit as a `units` attribute of its `<DataArray>` (readers ignore
//! attributes they do not know); a `String` field-data array would be the VTK way, but
//! meshio 5.3.5 refuses to open a file holding one (tested), so the units are not there.
//!
//! Files: each `.vtu` is written as `NAME.part` and renamed when complete. The `.pvd`
//! is written the same way after the first frame, at every checkpoint
//! ([`FrameStream::sync`]), at the end of the run, and otherwise at most every
//! [`COLLECTION_SECONDS`] of writing: rewriting it after every frame made the run write
//! O(F²) bytes for F frames (issue 19 §3). A run killed at any point leaves a readable
//! collection that lists completed frames only: all of them up to its last checkpoint,
//! at most [`COLLECTION_SECONDS`] behind otherwise. Arrays that do not change between
//! frames (points, cells, `node_id`) are encoded once.
//!
//! The writer is ours rather than vtkio's: vtkio builds a whole owned model of the grid
//! for every file (a copy of the mesh per frame) and has no `.pvd`, while this writer
//! encodes the frame's arrays straight from reused buffers (zlib through `flate2`,
//! base64 through `base64`). vtkio reads the files back in the tests, as VTK, meshio
//! and ParaView do in CI.
//!
//! By file: this one holds the writer (create, resume, write a frame); `encode` the VTU
//! encoding; `fields` the strain and stress of each cell; `collection` the `.pvd`;
//! `stream` the background writer thread; `outline` the obstacles' outlines.

mod collection;
mod encode;
mod fields;
mod outline;
mod stream;

pub(crate) use collection::remove_stale_frames;
use collection::{pvd_entries, write_renamed};
pub use outline::*;
pub use stream::*;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine;
use base64::engine::general_purpose::STANDARD as B64;

use crate::contact::ContactJacobian;
use crate::error::Error;
use crate::integrators::State;
use crate::model::hyperelastic::green_lagrange_and_cauchy;
use crate::model::solid::{
    Formulation, Material, MaterialModel, centre_gradient, centre_strain, hooke, von_mises,
};

pub use crate::model::geometry::{GeomCell, Geometry, Outline};

/// The VTK cell type of a geometry cell.
/// The `node_id` point array: the input mesh's id of each point (Gmsh node tag, VTK
/// point index; the index for generated meshes).
fn node_ids(g: &Geometry) -> Vec<i64> {
    (0..g.points.len())
        .map(|k| g.node_ids.get(k).map_or(k as i64, |&id| id as i64))
        .collect()
}

fn vtk_type(c: &GeomCell) -> u8 {
    match c {
        GeomCell::Line => 3,
        GeomCell::Solid(k) => k.element().vtk_type(),
    }
}

/// Point arrays of a frame: name and components, in the order they are written.
pub const POINT_ARRAYS: [(&str, usize); 4] = [
    ("displacement", 3),
    ("velocity", 3),
    ("contact_force", 3),
    ("gap", 1),
];
/// Point arrays of a frame in a frictional scene: also `contact_status` (0 open, 1 stick,
/// 2 slip, 3 closed without friction; NaN at points without a contact).
pub const FRICTION_POINT_ARRAYS: [(&str, usize); 5] = [
    ("displacement", 3),
    ("velocity", 3),
    ("contact_force", 3),
    ("gap", 1),
    ("contact_status", 1),
];
/// Cell arrays of a frame.
pub const CELL_ARRAYS: [(&str, usize); 3] = [("strain", 6), ("stress", 6), ("von_mises", 1)];

/// The cell arrays of a scene with a large-deformation body (Green–Lagrange strain,
/// Cauchy stress, von Mises of the Cauchy stress).
pub const NONLINEAR_CELL_ARRAYS: [(&str, usize); 3] = [
    ("green_lagrange_strain", 6),
    ("cauchy_stress", 6),
    ("von_mises", 1),
];

/// How array data are encoded in the `.vtu` files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Encoding {
    /// Inline base64 of zlib-compressed blocks (VTK's `vtkZLibDataCompressor`).
    #[default]
    Zlib,
    /// Inline base64, uncompressed.
    Binary,
    /// Plain text numbers.
    Ascii,
}

/// Longest time between two rewrites of the `.pvd` while frames are written (s): a
/// run killed without a checkpoint lists the frames of all but its last seconds.
pub const COLLECTION_SECONDS: f64 = 2.0;

/// Streams frames as `.vtu` files and keeps the `.pvd` collection up to date.
pub struct FrameWriter {
    dir: PathBuf,
    stem: String,
    geom: Geometry,
    encoding: Encoding,
    /// point index of each contact (from the Jacobian pattern)
    contact_point: Vec<usize>,
    /// The point of each dof (for the other side of a contact between bodies).
    point_of_dof: Vec<usize>,
    /// `contact_status` point field (frictional scenes: 0 open, 1 stick, 2 slip, 3 closed without friction; NaN
    /// away from contacts), written only when the snapshots carry statuses
    status: Vec<f64>,
    frames: Vec<(f64, String)>,
    // per-frame scratch, sized once
    disp: Vec<f64>,
    vel: Vec<f64>,
    force: Vec<f64>,
    gap: Vec<f64>,
    strain: Vec<f64>,
    stress: Vec<f64>,
    mises: Vec<f64>,
    xml: String,
    pvd: String,
    static_xml: String,
    /// The encoded `node_id` point array (it does not change between frames).
    static_point_xml: String,
    /// Frames the `.pvd` on disk lists, and when it was written.
    listed: usize,
    listed_at: Option<std::time::Instant>,
    raw: Vec<u8>,
    zip: Vec<u8>,
    deflate: flate2::Compress,
    /// seconds spent in `write_snapshot`
    busy: f64,
    #[cfg(feature = "hdf5")]
    h5: Option<super::h5::VtkHdf>,
}

impl FrameWriter {
    /// Prepares `dir/<stem>.pvd` and `dir/<stem>/` for the frames of a run whose contact
    /// Jacobian has the pattern of `jac`.
    pub fn create(
        dir: &Path,
        stem: &str,
        geom: Geometry,
        jac: &ContactJacobian,
        encoding: Encoding,
    ) -> Result<Self, Error> {
        let frames_dir = dir.join(stem);
        std::fs::create_dir_all(&frames_dir).map_err(|e| Error::write(&frames_dir, e))?;
        remove_stale_frames(&frames_dir)?;
        Self::new_unchecked(dir, stem, geom, jac, encoding)
    }

    /// Continues the frames of a checkpointed run: its first `count` frames are on disk
    /// (`<stem>/frame_000000.vtu` …) and listed, with their times, by the `.pvd` (which
    /// the run rewrote atomically after each frame, and synced before the checkpoint);
    /// they stay listed, and the next frame takes the next number (frames a killed run
    /// wrote after its checkpoint are written again, identically). The times are read
    /// back from the `.pvd` — written as Rust's shortest round-trip decimals, so
    /// exactly — rather than kept in the checkpoint, which then does not grow with the
    /// run.
    pub fn resume(
        dir: &Path,
        stem: &str,
        geom: Geometry,
        jac: &ContactJacobian,
        encoding: Encoding,
        count: usize,
    ) -> Result<Self, Error> {
        let mut w = Self::new_unchecked(dir, stem, geom, jac, encoding)?;
        let pvd = w.pvd_path();
        let text =
            crate::limits::read_text(&pvd, "frame collection", crate::limits::MAX_TEXT_BYTES)?;
        let listed = pvd_entries(&text);
        if listed.len() < count {
            return Err(Error::bad_file(
                &pvd,
                "",
                format!(
                    "lists {} frames, the checkpoint {count}: the run directory was changed",
                    listed.len()
                ),
            ));
        }
        for (k, (t, file)) in listed.into_iter().take(count).enumerate() {
            let name = format!("{stem}/frame_{k:06}.vtu");
            if file != name {
                return Err(Error::bad_file(
                    &pvd,
                    "",
                    format!("entry {k} is {file}, expected {name}: the run directory was changed"),
                ));
            }
            if !dir.join(&name).is_file() {
                return Err(Error::bad_file(
                    dir.join(&name),
                    "",
                    "is listed by the checkpoint but missing: the run directory was changed",
                ));
            }
            w.frames.push((t, name));
        }
        w.listed = w.frames.len();
        Ok(w)
    }

    fn new_unchecked(
        dir: &Path,
        stem: &str,
        geom: Geometry,
        jac: &ContactJacobian,
        encoding: Encoding,
    ) -> Result<Self, Error> {
        let mut point_of_dof = vec![usize::MAX; geom.dof_of.iter().flatten().count()];
        for (k, d) in geom.dof_of.iter().enumerate() {
            if let Some(d) = d {
                point_of_dof[*d] = k / geom.dim;
            }
        }
        // the point of each contact: the first dof of its normal column
        let contact_point: Vec<usize> = (0..jac.contacts())
            .map(|a| {
                jac.col(jac.block(a).start)
                    .0
                    .first()
                    .and_then(|&d| point_of_dof.get(d).copied())
                    .unwrap_or(usize::MAX)
            })
            .collect();
        let (np, nc) = (geom.points.len(), geom.cells.len());
        // blocks of more than one row: Coulomb friction, and a contact_status field
        let frictional = jac.ncols() > jac.contacts();
        let mut w = FrameWriter {
            dir: dir.to_path_buf(),
            stem: stem.to_string(),
            encoding,
            contact_point,
            point_of_dof,
            frames: Vec::new(),
            disp: vec![0.0; 3 * np],
            vel: vec![0.0; 3 * np],
            force: vec![0.0; 3 * np],
            gap: vec![f64::NAN; np],
            status: if frictional {
                vec![f64::NAN; np]
            } else {
                Vec::new()
            },
            strain: vec![0.0; 6 * nc],
            stress: vec![0.0; 6 * nc],
            mises: vec![0.0; nc],
            xml: String::new(),
            pvd: String::new(),
            raw: Vec::new(),
            zip: Vec::new(),
            deflate: flate2::Compress::new(flate2::Compression::fast(), true),
            busy: 0.0,
            #[cfg(feature = "hdf5")]
            h5: None,
            static_xml: String::new(),
            static_point_xml: String::new(),
            listed: 0,
            listed_at: None,
            geom,
        };
        w.static_xml = w.encode_static();
        let ids = node_ids(&w.geom);
        let mut x = String::new();
        w.array_i64(&mut x, "node_id", 1, &ids);
        w.static_point_xml = x;
        Ok(w)
    }

    /// Also appends every frame to the VTKHDF grid of the run's HDF5 file.
    #[cfg(feature = "hdf5")]
    pub fn with_hdf5(
        mut self,
        run: &super::h5::RunFile,
        reopen: Option<usize>,
    ) -> Result<Self, Error> {
        let g = &self.geom;
        let conn: Vec<i64> = g
            .cells
            .iter()
            .flat_map(|(_, n, _)| n.iter().map(|&v| v as i64))
            .collect();
        let offs: Vec<i64> = g
            .cells
            .iter()
            .scan(0i64, |o, (_, n, _)| {
                *o += n.len() as i64;
                Some(*o)
            })
            .collect();
        let types: Vec<u8> = g.cells.iter().map(|(k, _, _)| vtk_type(k)).collect();
        let ids = node_ids(g);
        self.h5 = Some(super::h5::VtkHdf::create(
            run,
            &ids,
            &g.points,
            &conn,
            &offs,
            &types,
            if self.status.is_empty() {
                &POINT_ARRAYS[..]
            } else {
                &FRICTION_POINT_ARRAYS[..]
            },
            &self.cell_arrays(),
            reopen,
        )?);
        Ok(self)
    }

    /// Frames written so far: (time, file relative to the output directory).
    pub fn frames(&self) -> &[(f64, String)] {
        &self.frames
    }

    /// Path of the `.pvd` collection.
    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join(format!("{}.pvd", self.stem))
    }

    /// Computes the fields of `state` (contact force `G P / h` with the Jacobian `jac`)
    /// and writes them as the next frame, then rewrites the `.pvd`.
    ///
    /// Allocates a [`Snapshot`]; a run streams through [`FrameStream`] instead, which
    /// reuses its snapshots, writes on its own thread and rewrites the `.pvd` only
    /// where the module doc says.
    pub fn write(&mut self, state: &State, jac: &ContactJacobian, h: f64) -> Result<(), Error> {
        let mut snap = Snapshot::with_statuses(state.q.len(), state.gap.len(), state.status.len());
        snap.copy_from(state, jac, h);
        self.write_snapshot(&snap)?;
        self.write_collection()
    }

    /// Writes `snap` as the next frame; the `.pvd` is rewritten after the first frame
    /// and when the last one written is [`COLLECTION_SECONDS`] old
    /// ([`FrameWriter::write_collection`] writes it now).
    pub fn write_snapshot(&mut self, snap: &Snapshot) -> Result<(), Error> {
        let t0 = std::time::Instant::now();
        let r = self.write_snapshot_timed(snap).and_then(|()| {
            let stale = self
                .listed_at
                .is_none_or(|t| t.elapsed().as_secs_f64() >= COLLECTION_SECONDS);
            if stale {
                self.write_collection_untimed()
            } else {
                Ok(())
            }
        });
        self.busy += t0.elapsed().as_secs_f64();
        r
    }

    /// Seconds spent writing frames so far.
    pub fn busy_seconds(&self) -> f64 {
        self.busy
    }

    fn write_snapshot_timed(&mut self, snap: &Snapshot) -> Result<(), Error> {
        self.fill(snap);
        #[cfg(feature = "hdf5")]
        if let Some(w) = self.h5.as_mut() {
            let point: &[&[f64]] = if self.status.is_empty() {
                &[&self.disp, &self.vel, &self.force, &self.gap]
            } else {
                &[&self.disp, &self.vel, &self.force, &self.gap, &self.status]
            };
            w.append(snap.time, point, &[&self.strain, &self.stress, &self.mises])?;
        }
        let name = format!("{}/frame_{:06}.vtu", self.stem, self.frames.len());
        let path = self.dir.join(&name);
        self.encode(snap.time, snap.step);
        write_renamed(&path, self.xml.as_bytes())?;
        self.frames.push((snap.time, name));
        Ok(())
    }
}
