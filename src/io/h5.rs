//! HDF5 output (cargo feature `hdf5`, on the system libhdf5 through hdf5-metno; DESIGN.md
//! §6): one file per run, `fields.vtkhdf`, holding
//!
//! - `/VTKHDF`: the VTKHDF 2.x transient unstructured grid that VTK ≥ 9.3
//!   (`vtkHDFReader`) and ParaView ≥ 5.12 read with every time step. The mesh is
//!   written once (`NumberOf*` have one entry, every `Steps/*Offsets` of the geometry is
//!   0) and each frame appends its point and cell arrays (same names and units as the
//!   `.vtu` frames) to extendible datasets, with `Steps/Values` (time),
//!   `Steps/PointDataOffsets/<name>` and `Steps/CellDataOffsets/<name>` pointing at it
//!   and `Steps@NSteps` updated. `Type` is a fixed-length ASCII string so that older
//!   readers accept the file.
//! - `/history`: the per-step history with the names of `history.csv`: one 1-D
//!   dataset per scalar column (`step`, `time`, `kinetic_energy`, …) and one 2-D dataset
//!   `[rows, m]` per contact quantity (`gap`, `velocity`, `impulse`, `projection`;
//!   column `c` is the CSV's `gap_c`, …); in a frictional scene also
//!   `tangent_impulse` and `slip_velocity` `[rows, m·t]` (column `c·t + j` is the CSV's
//!   `tangent_impulse_c_j`), `status` `[rows, m]` (0 open, 1 stick, 2 slip, 3 closed without friction),
//!   `friction_iterations` and `friction_residual`. Attributes: `scheme`, `dt`, `theta`
//!   and `parameters` (the run's parameters as JSON).
//!
//! Rows are buffered and appended in blocks (at every field frame, every 4096 rows and at
//! the end), then the file is flushed, so a killed run keeps every completed frame and
//! the history up to it. The file is written in place (HDF5 has no atomic rename of a
//! growing file); a run that finishes renames nothing.

use std::path::{Path, PathBuf};

use hdf5::types::{FixedAscii, VarLenUnicode};
use ndarray::{ArrayView1, ArrayView2, s};

use crate::error::Error;
use crate::integrators::{State, StepStats};

fn h5err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("HDF5: {e}")),
    }
}

/// The run's HDF5 file, shared by the field and history writers.
#[derive(Clone)]
pub struct RunFile {
    file: hdf5::File,
    path: PathBuf,
}

impl RunFile {
    /// Creates (truncates) `dir/fields.vtkhdf`.
    pub fn create(dir: &Path) -> Result<Self, Error> {
        let path = dir.join("fields.vtkhdf");
        let file = hdf5::File::create(&path).map_err(|e| h5err(&path, e))?;
        Ok(RunFile { file, path })
    }
    /// Opens the `dir/fields.vtkhdf` of a checkpointed run, to cut its datasets to the
    /// checkpoint and append to them ([`VtkHdf::create`], [`History::create`] with
    /// `reopen`).
    pub fn open(dir: &Path) -> Result<Self, Error> {
        let path = dir.join("fields.vtkhdf");
        let file = hdf5::File::open_rw(&path).map_err(|e| h5err(&path, e))?;
        Ok(RunFile { file, path })
    }
    /// Path of the file.
    pub fn path(&self) -> &Path {
        &self.path
    }
    fn flush(&self) -> Result<(), Error> {
        self.file.flush().map_err(|e| h5err(&self.path, e))
    }
}

/// An extendible dataset of rows of `cols` values (`cols = 0`: 1-D).
struct Growing {
    ds: hdf5::Dataset,
    cols: usize,
    rows: usize,
}

impl Growing {
    fn create<T: hdf5::H5Type>(
        g: &hdf5::Group,
        name: &str,
        cols: usize,
        chunk_rows: usize,
    ) -> hdf5::Result<Self> {
        let ds = if cols == 0 {
            g.new_dataset::<T>()
                .chunk(chunk_rows.max(1))
                .shape(0..)
                .create(name)?
        } else {
            g.new_dataset::<T>()
                .chunk((chunk_rows.max(1), cols))
                .shape((0.., cols))
                .create(name)?
        };
        Ok(Growing { ds, cols, rows: 0 })
    }
    /// [`Growing::create`], or with `reopen = Some(rows)` the dataset of a checkpointed
    /// run cut to its first `rows` rows (rows written after the checkpoint are dropped:
    /// the resumed run writes them again).
    fn make<T: hdf5::H5Type>(
        g: &hdf5::Group,
        name: &str,
        cols: usize,
        chunk_rows: usize,
        reopen: Option<usize>,
    ) -> hdf5::Result<Self> {
        let Some(rows) = reopen else {
            return Self::create::<T>(g, name, cols, chunk_rows);
        };
        let ds = g.dataset(name)?;
        let have = ds.shape().first().copied().unwrap_or(0);
        if have < rows {
            return Err(hdf5::Error::from(format!(
                "{name} holds {have} rows, fewer than the {rows} of the checkpoint"
            )));
        }
        if cols == 0 {
            ds.resize(rows)?;
        } else {
            ds.resize((rows, cols))?;
        }
        Ok(Growing { ds, cols, rows })
    }

    /// Appends `data` (`k · cols` values, or `k` for 1-D).
    fn append<T: hdf5::H5Type>(&mut self, data: &[T]) -> hdf5::Result<()> {
        let k = data.len().checked_div(self.cols).unwrap_or(data.len());
        if k == 0 {
            return Ok(());
        }
        let (a, b) = (self.rows, self.rows + k);
        if self.cols == 0 {
            self.ds.resize(b)?;
            self.ds.write_slice(ArrayView1::from(data), s![a..b])?;
        } else {
            self.ds.resize((b, self.cols))?;
            let v = ArrayView2::from_shape((k, self.cols), data).expect("whole rows");
            self.ds.write_slice(v, s![a..b, ..])?;
        }
        self.rows = b;
        Ok(())
    }
}

/// The per-step geometry offsets of `/VTKHDF/Steps`.
const GEOMETRY_OFFSETS: [&str; 5] = [
    "PartOffsets",
    "NumberOfParts",
    "PointOffsets",
    "CellOffsets",
    "ConnectivityIdOffsets",
];

/// The `/VTKHDF` transient grid.
pub struct VtkHdf {
    run: RunFile,
    steps: hdf5::Group,
    values: Growing,
    geometry_offsets: Vec<Growing>,
    point: Vec<(Growing, Growing)>,
    cell: Vec<(Growing, Growing)>,
    np: usize,
    nc: usize,
    frames: usize,
    node_id_offsets: Growing,
}

impl VtkHdf {
    /// Writes the static mesh and prepares the transient arrays: `point` and `cell`
    /// list (name, components). `node_id` is a static point array: written once, every
    /// step's offset points at it.
    /// With `reopen = Some(frames)`, opens the grid of a checkpointed run instead, its
    /// transient arrays cut to the first `frames` frames.
    #[allow(clippy::too_many_arguments)]
    pub fn create(
        run: &RunFile,
        node_id: &[i64],
        points: &[[f64; 3]],
        connectivity: &[i64],
        offsets: &[i64],
        types: &[u8],
        point: &[(&str, usize)],
        cell: &[(&str, usize)],
        reopen: Option<usize>,
    ) -> Result<Self, Error> {
        let path = run.path.clone();
        let (np, nc) = (points.len(), types.len());
        let r = (|| -> hdf5::Result<VtkHdf> {
            // the groups: opened in a checkpointed run's file, else created with the
            // static mesh
            let (pd, cd, steps, pdo, cdo) = match reopen {
                Some(frames) => {
                    let root = run.file.group("VTKHDF")?;
                    let steps = root.group("Steps")?;
                    steps.attr("NSteps")?.write_scalar(&(frames as i64))?;
                    let (pdo, cdo) = (
                        steps.group("PointDataOffsets")?,
                        steps.group("CellDataOffsets")?,
                    );
                    (
                        root.group("PointData")?,
                        root.group("CellData")?,
                        steps,
                        pdo,
                        cdo,
                    )
                }
                None => {
                    let root = run.file.create_group("VTKHDF")?;
                    Self::write_static(&root, node_id, points, connectivity, offsets, types)?;
                    let steps = root.create_group("Steps")?;
                    steps
                        .new_attr::<i64>()
                        .create("NSteps")?
                        .write_scalar(&0i64)?;
                    let (pdo, cdo) = (
                        steps.create_group("PointDataOffsets")?,
                        steps.create_group("CellDataOffsets")?,
                    );
                    steps.create_group("FieldDataOffsets")?;
                    steps.create_group("FieldDataSizes")?;
                    (
                        root.group("PointData")?,
                        root.group("CellData")?,
                        steps,
                        pdo,
                        cdo,
                    )
                }
            };
            // the transient arrays, cut to the checkpoint's frames when reopened
            let keep = |per_frame: usize| reopen.map(|f| f * per_frame);
            let values = Growing::make::<f64>(&steps, "Values", 0, 256, keep(1))?;
            let geometry_offsets = GEOMETRY_OFFSETS
                .iter()
                .map(|n| Growing::make::<i64>(&steps, n, 0, 256, keep(1)))
                .collect::<hdf5::Result<Vec<_>>>()?;
            let node_id_offsets = Growing::make::<i64>(&pdo, "node_id", 0, 256, keep(1))?;
            let arrays = |g: &hdf5::Group, o: &hdf5::Group, list: &[(&str, usize)], rows: usize| {
                list.iter()
                    .map(|&(name, comps)| {
                        let cols = if comps == 1 { 0 } else { comps };
                        let chunk = rows.clamp(1, 1 << 16);
                        Ok((
                            Growing::make::<f64>(g, name, cols, chunk, keep(rows))?,
                            Growing::make::<i64>(o, name, 0, 256, keep(1))?,
                        ))
                    })
                    .collect::<hdf5::Result<Vec<_>>>()
            };
            Ok(VtkHdf {
                run: run.clone(),
                values,
                geometry_offsets,
                point: arrays(&pd, &pdo, point, np)?,
                node_id_offsets,
                cell: arrays(&cd, &cdo, cell, nc)?,
                steps,
                np,
                nc,
                frames: reopen.unwrap_or(0),
            })
        })();
        r.map_err(|e| h5err(&path, e))
    }

    /// The version, type, mesh and the static `node_id` array of a new `/VTKHDF`.
    fn write_static(
        root: &hdf5::Group,
        node_id: &[i64],
        points: &[[f64; 3]],
        connectivity: &[i64],
        offsets: &[i64],
        types: &[u8],
    ) -> hdf5::Result<()> {
        root.new_attr::<i64>()
            .shape(2)
            .create("Version")?
            .write_raw(&[2i64, 2])?;
        let ty = FixedAscii::<16>::from_ascii("UnstructuredGrid").expect("ASCII");
        root.new_attr::<FixedAscii<16>>()
            .create("Type")?
            .write_scalar(&ty)?;
        let (np, nc) = (points.len(), types.len());
        let one = |name: &str, v: i64| -> hdf5::Result<()> {
            root.new_dataset::<i64>()
                .shape(1)
                .create(name)?
                .write_raw(&[v])
        };
        one("NumberOfPoints", np as i64)?;
        one("NumberOfCells", nc as i64)?;
        one("NumberOfConnectivityIds", connectivity.len() as i64)?;
        let flat: Vec<f64> = points.iter().flatten().copied().collect();
        root.new_dataset::<f64>()
            .shape((np, 3))
            .create("Points")?
            .write_raw(&flat)?;
        root.new_dataset::<i64>()
            .shape(connectivity.len())
            .create("Connectivity")?
            .write_raw(connectivity)?;
        let mut offs = Vec::with_capacity(offsets.len() + 1);
        offs.push(0i64);
        offs.extend_from_slice(offsets);
        root.new_dataset::<i64>()
            .shape(offs.len())
            .create("Offsets")?
            .write_raw(&offs)?;
        root.new_dataset::<u8>()
            .shape(nc)
            .create("Types")?
            .write_raw(types)?;
        root.create_group("FieldData")?;
        root.create_group("PointData")?
            .new_dataset::<i64>()
            .shape(np)
            .create("node_id")?
            .write_raw(node_id)?;
        root.create_group("CellData")?;
        Ok(())
    }

    /// Appends one frame at `time`: `point[i]` and `cell[i]` hold the arrays in the order
    /// given to [`VtkHdf::create`].
    pub fn append(&mut self, time: f64, point: &[&[f64]], cell: &[&[f64]]) -> Result<(), Error> {
        let k = self.frames as i64;
        let r = (|| -> hdf5::Result<()> {
            for ((data, offs), v) in self.point.iter_mut().zip(point) {
                offs.append(&[k * self.np as i64])?;
                data.append(v)?;
            }
            self.node_id_offsets.append(&[0])?;
            for ((data, offs), v) in self.cell.iter_mut().zip(cell) {
                offs.append(&[k * self.nc as i64])?;
                data.append(v)?;
            }
            // one part per step, and the geometry of step 0 for every step
            for (i, g) in self.geometry_offsets.iter_mut().enumerate() {
                g.append(&[i64::from(i == 1)])?;
            }
            self.values.append(&[time])
        })();
        r.map_err(|e| h5err(&self.run.path, e))?;
        // the step's data and extents reach the file before the step count that
        // announces them: a SIGKILL between the two leaves a count the data can honour
        // (without this flush the count was seen ahead of the displacement extent once
        // in ~30 killed runs under load)
        self.run.flush()?;
        let r = self
            .steps
            .attr("NSteps")
            .and_then(|a| a.write_scalar(&(k + 1)));
        r.map_err(|e| h5err(&self.run.path, e))?;
        self.frames += 1;
        self.run.flush()
    }
}

/// The `/history` group, appended in blocks.
pub struct History {
    run: RunFile,
    scalars: Vec<(&'static str, Growing)>,
    contact: Vec<(&'static str, Growing)>,
    m: usize,
    rows_s: Vec<f64>,
    rows_i: Vec<i64>,
    rows_c: Vec<f64>,
    /// Frictional scenes: `tangent_impulse`, `slip_velocity` (`[rows, m·td]`), `status`
    /// (`[rows, m]`, 0 open, 1 stick, 2 slip, 3 closed without friction) and the friction sweeps and residual.
    friction: Option<FrictionHistory>,
    buffered: usize,
}

struct FrictionHistory {
    td: usize,
    impulse: Growing,
    slip: Growing,
    status: Growing,
    iterations: Growing,
    residual: Growing,
    rows_t: Vec<f64>,
    rows_st: Vec<i64>,
    rows_f: Vec<(i64, f64)>,
}

const FLOAT_COLUMNS: [&str; 3] = ["time", "kinetic_energy", "potential_energy"];
const INT_COLUMNS: [&str; 3] = [
    "newton_iterations",
    "projection_iterations",
    "index_set_iterations",
];
const CONTACT_COLUMNS: [&str; 4] = ["gap", "velocity", "impulse", "projection"];

impl History {
    /// Rows buffered before a block is appended.
    const BLOCK: usize = 4096;

    /// Creates `/history` for `m` contacts (with `td` tangents each in a frictional
    /// scene, 0 otherwise) with the run's parameters as attributes.
    /// With `reopen = Some(rows)`, opens the `/history` of a checkpointed run instead,
    /// cut to its first `rows` rows.
    #[allow(clippy::too_many_arguments)]
    pub fn create(
        run: &RunFile,
        m: usize,
        td: usize,
        scheme: &str,
        dt: f64,
        theta: f64,
        parameters: &serde_json::Value,
        reopen: Option<usize>,
    ) -> Result<Self, Error> {
        let r = (|| -> hdf5::Result<History> {
            let g = if reopen.is_some() {
                run.file.group("history")?
            } else {
                let g = run.file.create_group("history")?;
                let text = |s: &str| s.parse::<VarLenUnicode>().expect("no NUL in JSON");
                g.new_attr::<VarLenUnicode>()
                    .create("scheme")?
                    .write_scalar(&text(scheme))?;
                g.new_attr::<VarLenUnicode>()
                    .create("parameters")?
                    .write_scalar(&text(&parameters.to_string()))?;
                g.new_attr::<f64>().create("dt")?.write_scalar(&dt)?;
                g.new_attr::<f64>().create("theta")?.write_scalar(&theta)?;
                g
            };
            let mut scalars = vec![("step", Growing::make::<i64>(&g, "step", 0, 4096, reopen)?)];
            for c in FLOAT_COLUMNS {
                scalars.push((c, Growing::make::<f64>(&g, c, 0, 4096, reopen)?));
            }
            scalars.push((
                "max_violation",
                Growing::make::<f64>(&g, "max_violation", 0, 4096, reopen)?,
            ));
            for c in INT_COLUMNS {
                scalars.push((c, Growing::make::<i64>(&g, c, 0, 4096, reopen)?));
            }
            let rows = (4096 / m.max(1)).max(16);
            let contact = CONTACT_COLUMNS
                .iter()
                .map(|&c| {
                    Ok((
                        c,
                        if m == 0 {
                            Growing::make::<f64>(&g, c, 0, 16, reopen)?
                        } else {
                            Growing::make::<f64>(&g, c, m, rows, reopen)?
                        },
                    ))
                })
                .collect::<hdf5::Result<Vec<_>>>()?;
            let friction = if td > 0 && m > 0 {
                Some(FrictionHistory {
                    td,
                    impulse: Growing::make::<f64>(&g, "tangent_impulse", m * td, rows, reopen)?,
                    slip: Growing::make::<f64>(&g, "slip_velocity", m * td, rows, reopen)?,
                    status: Growing::make::<i64>(&g, "status", m, rows, reopen)?,
                    iterations: Growing::make::<i64>(&g, "friction_iterations", 0, 4096, reopen)?,
                    residual: Growing::make::<f64>(&g, "friction_residual", 0, 4096, reopen)?,
                    rows_t: Vec::with_capacity(2 * m * td * Self::BLOCK),
                    rows_st: Vec::with_capacity(m * Self::BLOCK),
                    rows_f: Vec::with_capacity(Self::BLOCK),
                })
            } else {
                None
            };
            Ok(History {
                run: run.clone(),
                scalars,
                contact,
                m,
                friction,
                rows_s: Vec::with_capacity(5 * Self::BLOCK),
                rows_i: Vec::with_capacity(4 * Self::BLOCK),
                rows_c: Vec::with_capacity(4 * m * Self::BLOCK),
                buffered: 0,
            })
        })();
        r.map_err(|e| h5err(&run.path, e))
    }

    /// Buffers one row (the same quantities as a `history.csv` row).
    pub fn row(&mut self, s: &State, st: &StepStats, ke: f64, pe: f64) -> Result<(), Error> {
        self.rows_i.extend([
            s.step as i64,
            st.newton_iterations as i64,
            st.projection_iterations as i64,
            st.index_set_iterations as i64,
        ]);
        self.rows_s.extend([s.time, ke, pe, st.max_violation]);
        for q in [&s.gap, &s.local_velocity, &s.impulse, &s.projection] {
            self.rows_c.extend_from_slice(q);
        }
        if let Some(f) = self.friction.as_mut() {
            f.rows_t.extend_from_slice(&s.tangent_impulse);
            f.rows_t.extend_from_slice(&s.tangent_velocity);
            f.rows_st.extend(s.status.iter().map(|c| c.code() as i64));
            f.rows_f
                .push((st.friction_iterations as i64, st.friction_residual));
        }
        self.buffered += 1;
        if self.buffered >= Self::BLOCK {
            self.flush()?;
        }
        Ok(())
    }

    /// Appends the buffered rows and flushes the file.
    pub fn flush(&mut self) -> Result<(), Error> {
        if self.buffered == 0 {
            return Ok(());
        }
        let n = self.buffered;
        let r = (|| -> hdf5::Result<()> {
            // scalars: column-major copies of the row buffers
            let mut col_i = vec![0i64; n];
            let mut col_f = vec![0.0; n];
            let mut fi = 0;
            let mut ii = 0;
            for (name, ds) in &mut self.scalars {
                let is_int = *name == "step" || INT_COLUMNS.contains(name);
                if is_int {
                    let k = if *name == "step" { 0 } else { 1 + ii };
                    for (r, c) in col_i.iter_mut().enumerate() {
                        *c = self.rows_i[4 * r + k];
                    }
                    ds.append(&col_i)?;
                    if *name != "step" {
                        ii += 1;
                    }
                } else {
                    for (r, c) in col_f.iter_mut().enumerate() {
                        *c = self.rows_s[4 * r + fi];
                    }
                    ds.append(&col_f)?;
                    fi += 1;
                }
            }
            let m = self.m;
            if m > 0 {
                let mut block = vec![0.0; n * m];
                for (q, (_, ds)) in self.contact.iter_mut().enumerate() {
                    for r in 0..n {
                        let src = &self.rows_c[(4 * r + q) * m..(4 * r + q + 1) * m];
                        block[r * m..(r + 1) * m].copy_from_slice(src);
                    }
                    ds.append(&block)?;
                }
            }
            if let Some(f) = self.friction.as_mut() {
                let w = m * f.td;
                let mut block = vec![0.0; n * w];
                for (q, ds) in [&mut f.impulse, &mut f.slip].into_iter().enumerate() {
                    for r in 0..n {
                        let src = &f.rows_t[(2 * r + q) * w..(2 * r + q + 1) * w];
                        block[r * w..(r + 1) * w].copy_from_slice(src);
                    }
                    ds.append(&block)?;
                }
                f.status.append(&f.rows_st)?;
                let its: Vec<i64> = f.rows_f.iter().map(|x| x.0).collect();
                let res: Vec<f64> = f.rows_f.iter().map(|x| x.1).collect();
                f.iterations.append(&its)?;
                f.residual.append(&res)?;
                f.rows_t.clear();
                f.rows_st.clear();
                f.rows_f.clear();
            }
            Ok(())
        })();
        r.map_err(|e| h5err(&self.run.path, e))?;
        self.rows_s.clear();
        self.rows_i.clear();
        self.rows_c.clear();
        self.buffered = 0;
        self.run.flush()
    }
}

/// A column of [`write_table`].
pub enum TableColumn {
    /// Numbers (NaN where a cell is empty).
    Numbers(Vec<f64>),
    /// Text.
    Text(Vec<String>),
}

/// Writes a table as one HDF5 file (`path`, written as `path.part` and renamed): the
/// group `/table` with one 1-D dataset per column, in order (attribute `columns`: the
/// names joined by commas). `signorini sweep`'s `sweep.h5`.
pub fn write_table(path: &Path, columns: &[(String, TableColumn)]) -> Result<(), Error> {
    let mut part = path.as_os_str().to_owned();
    part.push(".part");
    let part = PathBuf::from(part);
    let write = || -> hdf5::Result<()> {
        let file = hdf5::File::create(&part)?;
        let g = file.create_group("table")?;
        for (name, col) in columns {
            match col {
                TableColumn::Numbers(v) => {
                    g.new_dataset_builder()
                        .with_data(v.as_slice())
                        .create(name.as_str())?;
                }
                TableColumn::Text(v) => {
                    let v: Vec<VarLenUnicode> = v
                        .iter()
                        .map(|s| s.replace('\0', " ").parse().expect("no NUL left"))
                        .collect();
                    g.new_dataset_builder()
                        .with_data(v.as_slice())
                        .create(name.as_str())?;
                }
            }
        }
        let names: Vec<&str> = columns.iter().map(|c| c.0.as_str()).collect();
        let joined: VarLenUnicode = names.join(",").parse().expect("no NUL in names");
        g.new_attr::<VarLenUnicode>()
            .create("columns")?
            .write_scalar(&joined)?;
        file.flush()?;
        Ok(())
    };
    write().map_err(|e| h5err(&part, e))?;
    std::fs::rename(&part, path).map_err(|e| Error::write(path, e))
}
