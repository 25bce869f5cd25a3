//! `/history`: the per-step history, one dataset per scalar column and one 2-D dataset
//! per contact quantity, buffered and appended in blocks; and `write_table` (the sweep's `sweep.h5`).

use super::*;

/// The `/history` group, appended in blocks.
pub struct History {
    pub(super) run: RunFile,
    pub(super) scalars: Vec<(&'static str, Growing)>,
    pub(super) contact: Vec<(&'static str, Growing)>,
    pub(super) m: usize,
    pub(super) rows_s: Vec<f64>,
    pub(super) rows_i: Vec<i64>,
    pub(super) rows_c: Vec<f64>,
    /// Frictional scenes: `tangent_impulse`, `slip_velocity` (`[rows, m·td]`), `status`
    /// (`[rows, m]`, 0 open, 1 stick, 2 slip, 3 closed without friction) and the friction sweeps and residual.
    pub(super) friction: Option<FrictionHistory>,
    /// Solid scenes: `centre`, `momentum`, `angular_momentum` of each body
    /// (`[rows, bodies · 3]`, x y z per body).
    pub(super) bodies: Option<BodyHistory>,
    pub(super) buffered: usize,
}

pub(super) struct BodyHistory {
    pub(super) count: usize,
    pub(super) sets: [Growing; 3],
    /// Per row: the centres, then the momenta, then the angular momenta (3 per body each).
    pub(super) rows: Vec<f64>,
}

pub(super) struct FrictionHistory {
    pub(super) td: usize,
    pub(super) impulse: Growing,
    pub(super) slip: Growing,
    pub(super) status: Growing,
    pub(super) iterations: Growing,
    pub(super) residual: Growing,
    pub(super) rows_t: Vec<f64>,
    pub(super) rows_st: Vec<i64>,
    pub(super) rows_f: Vec<(i64, f64)>,
}

/// The float columns after `step`, before `max_violation`: `dt` is each row's own step
/// (constant but for a run that chooses its steps, `time.accuracy`).
pub(super) const FLOAT_COLUMNS: [&str; 4] = ["time", "dt", "kinetic_energy", "potential_energy"];

/// Floats buffered per row: [`FLOAT_COLUMNS`] and `max_violation`.
const FLOATS: usize = FLOAT_COLUMNS.len() + 1;

pub(super) const INT_COLUMNS: [&str; 3] = [
    "newton_iterations",
    "projection_iterations",
    "index_set_iterations",
];
pub(super) const CONTACT_COLUMNS: [&str; 4] = ["gap", "velocity", "impulse", "projection"];

impl History {
    /// Rows buffered before a block is appended.
    pub(super) const BLOCK: usize = 4096;

    /// Creates `/history` for `m` contacts (with `td` tangents each in a frictional
    /// scene, 0 otherwise) and `nb` bodies measured per row (0: none) with the run's
    /// parameters as attributes.
    /// With `reopen = Some(rows)`, opens the `/history` of a checkpointed run instead,
    /// cut to its first `rows` rows.
    pub fn create(
        run: &RunFile,
        (m, td, nb): (usize, usize, usize),
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
            let bodies = if nb > 0 {
                let rows = (4096 / (3 * nb)).max(16);
                let set = |name| Growing::make::<f64>(&g, name, 3 * nb, rows, reopen);
                Some(BodyHistory {
                    count: nb,
                    sets: [set("centre")?, set("momentum")?, set("angular_momentum")?],
                    rows: Vec::with_capacity(9 * nb * Self::BLOCK),
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
                bodies,
                rows_s: Vec::with_capacity(FLOATS * Self::BLOCK),
                rows_i: Vec::with_capacity(4 * Self::BLOCK),
                rows_c: Vec::with_capacity(4 * m * Self::BLOCK),
                buffered: 0,
            })
        })();
        r.map_err(|e| h5err(&run.path, e))
    }

    /// Buffers one row (the same quantities as a `history.csv` row).
    pub fn row(
        &mut self,
        s: &State,
        st: &StepStats,
        ke: f64,
        pe: f64,
        bodies: &[crate::model::BodyState],
    ) -> Result<(), Error> {
        if let Some(b) = self.bodies.as_mut() {
            for get in [
                |x: &crate::model::BodyState| x.centre,
                |x: &crate::model::BodyState| x.momentum,
                |x: &crate::model::BodyState| x.angular_momentum,
            ] {
                for k in 0..b.count {
                    b.rows
                        .extend_from_slice(&bodies.get(k).map_or([f64::NAN; 3], get));
                }
            }
        }
        self.rows_i.extend([
            s.step as i64,
            st.newton_iterations as i64,
            st.projection_iterations as i64,
            st.index_set_iterations as i64,
        ]);
        self.rows_s
            .extend([s.time, st.dt, ke, pe, st.max_violation]);
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
                        *c = self.rows_s[FLOATS * r + fi];
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
            if let Some(b) = self.bodies.as_mut() {
                let w = 3 * b.count;
                let mut block = vec![0.0; n * w];
                for (q, ds) in b.sets.iter_mut().enumerate() {
                    for r in 0..n {
                        let src = &b.rows[(3 * r + q) * w..(3 * r + q + 1) * w];
                        block[r * w..(r + 1) * w].copy_from_slice(src);
                    }
                    ds.append(&block)?;
                }
                b.rows.clear();
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
        let file = super::options().create(&part)?;
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
