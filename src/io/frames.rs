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

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine;
use base64::engine::general_purpose::STANDARD as B64;

use crate::contact::ContactJacobian;
use crate::error::Error;
use crate::integrators::State;
use crate::model::hyperelastic::{Hyperelastic, green_lagrange_and_cauchy};
use crate::model::solid::{
    CellKind, Formulation, Material, MaterialModel, centre_gradient, centre_strain, hooke,
    von_mises,
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
        GeomCell::Solid(CellKind::Tri3) => 5,
        GeomCell::Solid(CellKind::Quad4) => 9,
        GeomCell::Solid(CellKind::Tet4) => 10,
        GeomCell::Solid(CellKind::Hex8) => 12,
    }
}

/// Two unit vectors completing the unit vector `n` to an orthonormal basis.
pub fn orthonormal(n: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let t = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let a = cross(n, t);
    let l = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    let a = a.map(|x| x / l);
    (a, cross(n, a))
}

/// Writes the outlines as one ASCII `.vtu` of line cells with the cell data `obstacle`
/// (index into `outlines`), atomically.
pub fn write_outlines(path: &Path, outlines: &[Outline]) -> Result<(), Error> {
    let np: usize = outlines.iter().map(|o| o.points.len()).sum();
    let nc: usize = outlines.iter().map(|o| o.segments.len()).sum();
    let mut x = format!(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n\
         <Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">\n<CellData Scalars=\"obstacle\">\n\
         <DataArray type=\"Int64\" Name=\"obstacle\" NumberOfComponents=\"1\" format=\"ascii\">\n"
    );
    for (i, o) in outlines.iter().enumerate() {
        for _ in &o.segments {
            let _ = write!(x, "{i} ");
        }
    }
    x.push_str("\n</DataArray>\n</CellData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for p in outlines.iter().flat_map(|o| &o.points) {
        let _ = writeln!(x, "{:e} {:e} {:e}", p[0], p[1], p[2]);
    }
    x.push_str("</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    let mut base = 0;
    for o in outlines {
        for s in &o.segments {
            let _ = write!(x, "{} {} ", base + s[0], base + s[1]);
        }
        base += o.points.len();
    }
    x.push_str("\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for k in 1..=nc {
        let _ = write!(x, "{} ", 2 * k);
    }
    x.push_str("\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for _ in 0..nc {
        x.push_str("3 ");
    }
    x.push_str("\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    write_renamed(path, x.as_bytes())
}

impl Geometry {
    /// The geometry of a straight rod of `elements` elements along x (one dof per node).
    pub fn rod(length: f64, elements: usize, young: f64, density: f64) -> Self {
        let n = elements.max(1);
        Geometry {
            points: (0..=n)
                .map(|i| [length * i as f64 / n as f64, 0.0, 0.0])
                .collect(),
            cells: (0..n)
                .map(|e| (GeomCell::Line, vec![e, e + 1], 0))
                .collect(),
            bodies: vec![(
                Material {
                    young,
                    poisson: 0.0,
                    density,
                    model: crate::model::solid::MaterialModel::Linear,
                },
                Formulation::Solid,
            )],
            dim: 1,
            dof_of: (0..=n).map(Some).collect(),
            ..Geometry::default()
        }
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

    /// Rewrites the `.pvd` with every frame written so far (atomically), unless it
    /// already lists them all.
    pub fn write_collection(&mut self) -> Result<(), Error> {
        let t0 = std::time::Instant::now();
        let r = self.write_collection_untimed();
        self.busy += t0.elapsed().as_secs_f64();
        r
    }

    fn write_collection_untimed(&mut self) -> Result<(), Error> {
        if self.listed == self.frames.len() && self.listed_at.is_some() {
            return Ok(());
        }
        let mut pvd = std::mem::take(&mut self.pvd);
        pvd.clear();
        pvd.push_str(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" \
             byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (t, f) in &self.frames {
            let _ = writeln!(
                pvd,
                "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{f}\"/>"
            );
        }
        pvd.push_str("  </Collection>\n</VTKFile>\n");
        let r = write_renamed(&self.pvd_path(), pvd.as_bytes());
        self.pvd = pvd;
        r?;
        self.listed = self.frames.len();
        self.listed_at = Some(std::time::Instant::now());
        Ok(())
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

    /// The cell arrays: `strain` and `stress` (small strain, Hooke) when every body is
    /// linear; `green_lagrange_strain` and `cauchy_stress` when a body has a
    /// large-deformation law (the linear bodies of such a scene write their small strain
    /// and Hooke stress, the linearizations of these measures, in the same arrays).
    fn cell_arrays(&self) -> [(&'static str, usize); 3] {
        if self
            .geom
            .bodies
            .iter()
            .any(|(m, _)| m.model != MaterialModel::Linear)
        {
            NONLINEAR_CELL_ARRAYS
        } else {
            CELL_ARRAYS
        }
    }

    fn fill(&mut self, s: &Snapshot) {
        let g = &self.geom;
        let dim = g.dim;
        for (k, d) in g.dof_of.iter().enumerate() {
            let (p, i) = (k / dim, k % dim);
            let (u, v, r) = d.map_or((0.0, 0.0, 0.0), |d| (s.q[d], s.v[d], s.reaction[d]));
            self.disp[3 * p + i] = u;
            self.vel[3 * p + i] = v;
            self.force[3 * p + i] = r;
        }
        for &(k, w, f) in &g.prescribed {
            let (p, i) = (k / dim, k % dim);
            let phi = &g.prescribed_functions[f];
            self.disp[3 * p + i] = w * phi.integral(s.time);
            self.vel[3 * p + i] = w * phi.eval(s.time);
        }
        self.gap.iter_mut().for_each(|f| *f = f64::NAN);
        self.status.iter_mut().for_each(|f| *f = f64::NAN);
        for (a, &p) in self.contact_point.iter().enumerate() {
            if p == usize::MAX || a >= s.gap.len() {
                continue;
            }
            // the contact's node, and the master node across a contact between bodies
            let other = s
                .partner
                .get(a)
                .and_then(|&d| self.point_of_dof.get(d).copied())
                .filter(|&o| o != p);
            for q in std::iter::once(p).chain(other) {
                self.gap[q] = if self.gap[q].is_nan() {
                    s.gap[a]
                } else {
                    self.gap[q].min(s.gap[a])
                };
                if !self.status.is_empty() && a < s.status.len() {
                    // a node in several contacts shows its most engaged status
                    let v = s.status[a] as f64;
                    self.status[q] = if self.status[q].is_nan() {
                        v
                    } else {
                        self.status[q].max(v)
                    };
                }
            }
        }
        for (c, (kind, nodes, body)) in g.cells.iter().enumerate() {
            let (mat, form) = &g.bodies[*body];
            let mut eps = [0.0; 6];
            let sig;
            match kind {
                GeomCell::Line => {
                    let (a, b) = (nodes[0], nodes[1]);
                    let l = g.points[b][0] - g.points[a][0];
                    eps[0] = (self.disp[3 * b] - self.disp[3 * a]) / l;
                    sig = [mat.young * eps[0], 0.0, 0.0, 0.0, 0.0, 0.0];
                }
                GeomCell::Solid(k) => {
                    let mut x = [[0.0; 3]; 8];
                    let mut u = [[0.0; 3]; 8];
                    for (j, &p) in nodes.iter().enumerate() {
                        x[j] = g.points[p];
                        u[j] = [self.disp[3 * p], self.disp[3 * p + 1], self.disp[3 * p + 2]];
                    }
                    let law = match mat.model {
                        MaterialModel::Linear => None,
                        MaterialModel::Svk => Some(Hyperelastic::svk(mat)),
                        MaterialModel::NeoHookean => Some(Hyperelastic::neo_hookean(mat)),
                    };
                    match law {
                        None => {
                            eps = centre_strain(*k, &x, &u, mat, *form);
                            sig = hooke(mat, &eps);
                        }
                        Some(law) => {
                            let grad = centre_gradient(*k, &x, &u);
                            (eps, sig) = green_lagrange_and_cauchy(&law, &grad)
                                .unwrap_or(([f64::NAN; 6], [f64::NAN; 6]));
                        }
                    }
                }
            }
            self.strain[6 * c..6 * c + 6].copy_from_slice(&eps);
            self.stress[6 * c..6 * c + 6].copy_from_slice(&sig);
            self.mises[c] = von_mises(&sig);
        }
    }

    fn encode(&mut self, time: f64, step: usize) {
        let g = &self.geom;
        let (np, nc) = (g.points.len(), g.cells.len());
        let compressed = self.encoding == Encoding::Zlib;
        let mut x = std::mem::take(&mut self.xml);
        x.clear();
        let _ = write!(
            x,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" \
             byte_order=\"LittleEndian\" header_type=\"UInt64\"{}>\n<UnstructuredGrid>\n",
            if compressed {
                " compressor=\"vtkZLibDataCompressor\""
            } else {
                ""
            }
        );
        x.push_str("<FieldData>\n");
        self.array_f64(&mut x, "TimeValue", 1, &[time]);
        self.array_i64(&mut x, "Step", 1, &[step as i64]);
        x.push_str("</FieldData>\n");
        let _ = writeln!(x, "<Piece NumberOfPoints=\"{np}\" NumberOfCells=\"{nc}\">");
        x.push_str("<PointData Vectors=\"displacement\" Scalars=\"gap\">\n");
        let (disp, vel, force, gap) = (
            std::mem::take(&mut self.disp),
            std::mem::take(&mut self.vel),
            std::mem::take(&mut self.force),
            std::mem::take(&mut self.gap),
        );
        self.array_f64(&mut x, "displacement", 3, &disp);
        self.array_f64(&mut x, "velocity", 3, &vel);
        self.array_f64(&mut x, "contact_force", 3, &force);
        self.array_f64(&mut x, "gap", 1, &gap);
        (self.disp, self.vel, self.force, self.gap) = (disp, vel, force, gap);
        if !self.status.is_empty() {
            let status = std::mem::take(&mut self.status);
            self.array_f64(&mut x, "contact_status", 1, &status);
            self.status = status;
        }
        x.push_str(&self.static_point_xml);
        let [(strain_name, _), (stress_name, _), _] = self.cell_arrays();
        let _ = write!(
            x,
            "</PointData>\n<CellData Tensors=\"{stress_name}\" Scalars=\"von_mises\">\n"
        );
        let (strain, stress, mises) = (
            std::mem::take(&mut self.strain),
            std::mem::take(&mut self.stress),
            std::mem::take(&mut self.mises),
        );
        self.array_f64(&mut x, strain_name, 6, &strain);
        self.array_f64(&mut x, stress_name, 6, &stress);
        self.array_f64(&mut x, "von_mises", 1, &mises);
        (self.strain, self.stress, self.mises) = (strain, stress, mises);
        x.push_str("</CellData>\n");
        x.push_str(&self.static_xml);
        x.push_str("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        self.xml = x;
    }

    /// The `<Points>` and `<Cells>` elements, encoded once for every frame.
    fn encode_static(&mut self) -> String {
        let mut x = String::from("<Points>\n");
        let pts: Vec<f64> = self.geom.points.iter().flatten().copied().collect();
        self.array_f64(&mut x, "Points", 3, &pts);
        x.push_str("</Points>\n<Cells>\n");
        let conn: Vec<i64> = self
            .geom
            .cells
            .iter()
            .flat_map(|(_, n, _)| n.iter().map(|&v| v as i64))
            .collect();
        let offs: Vec<i64> = self
            .geom
            .cells
            .iter()
            .scan(0i64, |o, (_, n, _)| {
                *o += n.len() as i64;
                Some(*o)
            })
            .collect();
        let types: Vec<u8> = self
            .geom
            .cells
            .iter()
            .map(|(k, _, _)| vtk_type(k))
            .collect();
        self.array_i64(&mut x, "connectivity", 1, &conn);
        self.array_i64(&mut x, "offsets", 1, &offs);
        self.array_raw(&mut x, "UInt8", "types", 1, types.len(), &types, |s, v| {
            for b in v {
                let _ = write!(s, "{b} ");
            }
        });
        x.push_str("</Cells>\n");
        x
    }

    fn array_f64(&mut self, x: &mut String, name: &str, comps: usize, v: &[f64]) {
        let bytes: &[u8] = bytemuck_f64(v);
        self.array_raw(x, "Float64", name, comps, v.len(), bytes, |s, _| {
            for (k, a) in v.iter().enumerate() {
                let _ = write!(s, "{a:e}");
                s.push(if (k + 1) % comps == 0 { '\n' } else { ' ' });
            }
        });
    }

    fn array_i64(&mut self, x: &mut String, name: &str, comps: usize, v: &[i64]) {
        let bytes: Vec<u8> = v.iter().flat_map(|a| a.to_le_bytes()).collect();
        self.array_raw(x, "Int64", name, comps, v.len(), &bytes, |s, _| {
            for a in v {
                let _ = write!(s, "{a} ");
            }
        });
    }

    /// One `<DataArray>`; `ascii` prints the values for the ASCII encoding.
    #[allow(clippy::too_many_arguments)]
    fn array_raw(
        &mut self,
        x: &mut String,
        ty: &str,
        name: &str,
        comps: usize,
        len: usize,
        bytes: &[u8],
        ascii: impl Fn(&mut String, &[u8]),
    ) {
        let fmt = if self.encoding == Encoding::Ascii {
            "ascii"
        } else {
            "binary"
        };
        let unit = match name {
            "displacement" | "gap" | "Points" => " units=\"m\"",
            "velocity" => " units=\"m/s\"",
            "contact_force" => " units=\"N\"",
            "stress" | "cauchy_stress" | "von_mises" => " units=\"Pa\"",
            "strain" | "green_lagrange_strain" => " units=\"1\"",
            "TimeValue" => " units=\"s\"",
            _ => "",
        };
        let _ = writeln!(
            x,
            "<DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" \
             NumberOfTuples=\"{}\" format=\"{fmt}\"{unit}>",
            len / comps.max(1)
        );
        match self.encoding {
            Encoding::Ascii => ascii(x, bytes),
            Encoding::Binary => {
                self.raw.clear();
                self.raw
                    .extend_from_slice(&(bytes.len() as u64).to_le_bytes());
                self.raw.extend_from_slice(bytes);
                B64.encode_string(&self.raw, x);
            }
            Encoding::Zlib => {
                // one block: header [nblocks, block size, last block size, compressed
                // size], base64-encoded on its own, then the compressed block
                self.zip.clear();
                if !bytes.is_empty() {
                    // one reused deflate state (a fresh one zeroes its window each time)
                    self.deflate.reset();
                    self.zip.reserve(bytes.len() / 2 + 64);
                    loop {
                        let done = self.deflate.total_in() as usize;
                        let st = self
                            .deflate
                            .compress_vec(
                                &bytes[done..],
                                &mut self.zip,
                                flate2::FlushCompress::Finish,
                            )
                            .expect("deflate into memory");
                        if st == flate2::Status::StreamEnd {
                            break;
                        }
                        self.zip.reserve(self.zip.len().max(1024));
                    }
                }
                self.raw.clear();
                let n = bytes.len() as u64;
                let head: [u64; 4] = [u64::from(n > 0), n, n, self.zip.len() as u64];
                let hl = if n > 0 { 4 } else { 3 };
                for h in &head[..hl] {
                    self.raw.extend_from_slice(&h.to_le_bytes());
                }
                B64.encode_string(&self.raw, x);
                B64.encode_string(&self.zip, x);
            }
        }
        x.push_str("\n</DataArray>\n");
    }
}

/// The part of a [`State`] a frame shows, copied out of the integrator so that the
/// frame can be encoded while the run goes on ([`FrameStream`]).
#[derive(Clone, Debug, Default)]
pub struct Snapshot {
    /// Step index.
    pub step: usize,
    /// Time (s).
    pub time: f64,
    /// Generalized coordinates (m).
    pub q: Vec<f64>,
    /// Generalized velocities (m/s).
    pub v: Vec<f64>,
    /// Contact force in dof space, `G P / h` (N).
    pub reaction: Vec<f64>,
    /// Gap per contact (m).
    pub gap: Vec<f64>,
    /// Open / stick / slip code per contact (frictional scenes; empty otherwise).
    pub status: Vec<u8>,
    /// Per contact, a dof of the other side of a contact between bodies (the master
    /// node that weighs most in the normal column), `usize::MAX` for an obstacle: the
    /// frames show the gap and the status on both sides.
    pub partner: Vec<usize>,
}

impl Snapshot {
    /// A snapshot for `n` dofs and `m` contacts (frictionless: no statuses).
    pub fn new(n: usize, m: usize) -> Self {
        Self::with_statuses(n, m, 0)
    }

    /// A snapshot for `n` dofs, `m` contacts and `statuses` contact statuses (`m` in a
    /// frictional scene, 0 otherwise).
    pub fn with_statuses(n: usize, m: usize, statuses: usize) -> Self {
        Snapshot {
            step: 0,
            time: 0.0,
            q: vec![0.0; n],
            v: vec![0.0; n],
            reaction: vec![0.0; n],
            gap: vec![0.0; m],
            status: vec![0; statuses],
            partner: vec![usize::MAX; m],
        }
    }

    /// Copies `state` in (same sizes; no allocation) and forms `G P / h` with `jac`.
    pub fn copy_from(&mut self, state: &State, jac: &ContactJacobian, h: f64) {
        self.step = state.step;
        self.time = state.time;
        self.q.copy_from_slice(&state.q);
        self.v.copy_from_slice(&state.v);
        self.gap.copy_from_slice(&state.gap);
        if self.status.len() == state.status.len() {
            for (o, s) in self.status.iter_mut().zip(&state.status) {
                *o = s.code();
            }
        }
        // the other side: the entry of the normal column most opposed to its largest one
        // (a master node's `−N_i n` against the slave's `n`)
        for (a, o) in self.partner.iter_mut().enumerate().take(jac.contacts()) {
            let (dofs, vals) = jac.col(jac.block(a).start);
            let r = vals
                .iter()
                .fold(0.0_f64, |m, &v| if v.abs() > m.abs() { v } else { m });
            *o = usize::MAX;
            let mut best = 0.0;
            for (&d, &v) in dofs.iter().zip(vals) {
                if v * r < best {
                    best = v * r;
                    *o = d;
                }
            }
        }
        self.reaction.iter_mut().for_each(|r| *r = 0.0);
        // every row of G: the normal and, with friction, the tangential impulses
        for (a, &p) in state.impulse_rows.iter().enumerate().take(jac.ncols()) {
            if p != 0.0 {
                jac.axpy(a, p / h, &mut self.reaction);
            }
        }
    }
}

/// Writes frames on a background thread, so that encoding and compressing a frame
/// overlaps the next steps instead of stopping them.
///
/// The run copies the state into one of a fixed pool of [`Snapshot`]s (allocated once)
/// and hands it over a bounded channel; the writer thread encodes it with its
/// [`FrameWriter`] and returns the snapshot to the pool. When every snapshot is in
/// flight the run waits (the time is reported), so memory stays bounded and frames are
/// written in order. A write error stops the thread; the run sees it at its next
/// frame or at [`FrameStream::finish`]. Frames already written stay valid: each
/// `.vtu` and the `.pvd` are still renamed into place one by one, and
/// [`FrameStream::sync`] leaves a `.pvd` listing every frame pushed.
///
/// std's channels and thread suffice here (a pool of two or three buffers and one
/// consumer); rayon's pool is for the assembly and the linear algebra.
pub struct FrameStream {
    work: Option<std::sync::mpsc::SyncSender<Job>>,
    free: std::sync::mpsc::Receiver<Snapshot>,
    /// The writer's answer to [`Job::Collection`].
    listed: std::sync::mpsc::Receiver<()>,
    thread: Option<std::thread::JoinHandle<Result<FrameWriter, Error>>>,
    waited: f64,
    /// Snapshots taken back by [`FrameStream::sync`], used before the pool's.
    spare: Vec<Snapshot>,
    pool: usize,
}

impl FrameStream {
    /// Starts the writer thread with `pool` snapshots of `n` dofs and `m` contacts.
    pub fn spawn(writer: FrameWriter, n: usize, m: usize, pool: usize) -> Self {
        Self::spawn_with_statuses(writer, n, m, 0, pool)
    }

    /// As [`FrameStream::spawn`], the snapshots also holding `statuses` contact statuses
    /// (a frictional scene's `contact_status` field).
    pub fn spawn_with_statuses(
        mut writer: FrameWriter,
        n: usize,
        m: usize,
        statuses: usize,
        pool: usize,
    ) -> Self {
        let pool = pool.max(1);
        // a collection request follows the frames, so one more place than snapshots
        let (work_tx, work_rx) = std::sync::mpsc::sync_channel::<Job>(pool + 1);
        let (free_tx, free_rx) = std::sync::mpsc::sync_channel::<Snapshot>(pool);
        let (listed_tx, listed_rx) = std::sync::mpsc::sync_channel::<()>(1);
        for _ in 0..pool {
            free_tx
                .send(Snapshot::with_statuses(n, m, statuses))
                .expect("the pool channel holds `pool` snapshots");
        }
        // the spawning run's subnormal mode (inherited on Linux; set, not assumed)
        let flush = crate::linalg::subnormals::current_thread();
        let thread = std::thread::Builder::new()
            .name("signorini-frames".into())
            .spawn(move || {
                crate::linalg::subnormals::apply_to_current_thread(flush);
                for job in work_rx {
                    // the run may have stopped listening (it failed); that is its report
                    match job {
                        Job::Frame(snap) => {
                            writer.write_snapshot(&snap)?;
                            let _ = free_tx.send(snap);
                        }
                        Job::Collection => {
                            writer.write_collection()?;
                            let _ = listed_tx.send(());
                        }
                    }
                }
                writer.write_collection()?;
                Ok(writer)
            })
            .expect("spawning the frame writer thread");
        FrameStream {
            work: Some(work_tx),
            free: free_rx,
            listed: listed_rx,
            thread: Some(thread),
            waited: 0.0,
            spare: Vec::with_capacity(pool),
            pool,
        }
    }

    /// Queues a frame of `state`; waits for a free snapshot if all are in flight.
    pub fn push(&mut self, state: &State, jac: &ContactJacobian, h: f64) -> Result<(), Error> {
        let t0 = std::time::Instant::now();
        let mut snap = match self.spare.pop() {
            Some(s) => s,
            None => match self.free.recv() {
                Ok(s) => s,
                Err(_) => return Err(self.failure()),
            },
        };
        self.waited += t0.elapsed().as_secs_f64();
        snap.copy_from(state, jac, h);
        // the snapshot comes back in a send error only when the writer has stopped
        let sent = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Frame(snap)).is_ok());
        if sent { Ok(()) } else { Err(self.failure()) }
    }

    /// Waits until every queued frame is on disk and listed by the `.pvd` (a
    /// checkpoint's barrier): takes every snapshot of the pool back, keeps them for the
    /// next pushes, and has the writer rewrite the `.pvd`.
    pub fn sync(&mut self) -> Result<(), Error> {
        while self.spare.len() < self.pool {
            match self.free.recv() {
                Ok(s) => self.spare.push(s),
                Err(_) => return Err(self.failure()),
            }
        }
        let asked = self
            .work
            .as_ref()
            .is_some_and(|w| w.send(Job::Collection).is_ok());
        if asked && self.listed.recv().is_ok() {
            Ok(())
        } else {
            Err(self.failure())
        }
    }

    /// Seconds the run spent waiting for a free snapshot.
    pub fn waited_seconds(&self) -> f64 {
        self.waited
    }

    /// Waits until every queued frame is written and returns the writer.
    pub fn finish(mut self) -> Result<FrameWriter, Error> {
        drop(self.work.take());
        self.join()
    }

    fn join(&mut self) -> Result<FrameWriter, Error> {
        match self.thread.take().map(|t| t.join()) {
            Some(Ok(r)) => r,
            Some(Err(p)) => std::panic::resume_unwind(p),
            None => Err(Error::Write {
                path: PathBuf::from("fields.pvd"),
                source: std::io::Error::other("the frame writer already stopped"),
            }),
        }
    }

    /// The writer thread's error (it stopped early).
    fn failure(&mut self) -> Error {
        drop(self.work.take());
        match self.join() {
            Err(e) => e,
            Ok(_) => Error::Write {
                path: PathBuf::from("fields.pvd"),
                source: std::io::Error::other("the frame writer stopped without an error"),
            },
        }
    }
}

/// What the run hands the writer thread.
enum Job {
    /// A frame to write.
    Frame(Snapshot),
    /// Rewrite the `.pvd` now (and answer).
    Collection,
}

impl Drop for FrameStream {
    fn drop(&mut self) {
        drop(self.work.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The little-endian bytes of an `f64` slice (every supported target is little-endian;
/// checked at compile time below), by bytemuck's checked cast: the crate has no
/// `unsafe` of its own.
fn bytemuck_f64(v: &[f64]) -> &[u8] {
    const _: () = assert!(cfg!(target_endian = "little"));
    bytemuck::cast_slice(v)
}

/// The `(timestep, file)` entries of a `.pvd` collection as this module writes it
/// (one `<DataSet timestep="…" … file="…"/>` a line); lines that do not parse end the
/// list.
fn pvd_entries(text: &str) -> Vec<(f64, String)> {
    let attr = |line: &str, key: &str| -> Option<String> {
        let start = line.find(&format!("{key}=\""))? + key.len() + 2;
        let end = start + line[start..].find('"')?;
        Some(line[start..end].to_string())
    };
    text.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet"))
        .map_while(|l| {
            let t = attr(l, "timestep")?.parse::<f64>().ok()?;
            Some((t, attr(l, "file")?))
        })
        .collect()
}

/// Removes the `frame_*.vtu` files a previous run left in `dir`: a shorter run would
/// otherwise leave frames its `.pvd` does not list, and renaming a new frame onto an
/// old one makes ext4 write the file out first (`auto_da_alloc`), which measured 10×
/// slower than writing a new name (0.6 vs 0.06 ms for the bar's 77 kB frame).
pub(crate) fn remove_stale_frames(dir: &Path) -> Result<(), Error> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::write(dir, e))?;
    for e in entries {
        let path = e.map_err(|e| Error::write(dir, e))?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with("frame_") && (name.ends_with(".vtu") || name.ends_with(".vtu.part")) {
            std::fs::remove_file(&path).map_err(|e| Error::write(&path, e))?;
        }
    }
    Ok(())
}

/// Writes `bytes` to `path.part` and renames it onto `path` (no fsync: a killed process
/// loses nothing the kernel has, and frames are too frequent to sync each one).
fn write_renamed(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".part");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, bytes).map_err(|e| Error::write(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::write(path, e))
}
