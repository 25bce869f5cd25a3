//! `/VTKHDF`: the transient unstructured grid (the mesh written once, each frame's point
//! and cell arrays appended with their step offsets), as the parent's module doc lays out.

use super::*;

/// The per-step geometry offsets of `/VTKHDF/Steps`.
pub(super) const GEOMETRY_OFFSETS: [&str; 5] = [
    "PartOffsets",
    "NumberOfParts",
    "PointOffsets",
    "CellOffsets",
    "ConnectivityIdOffsets",
];

/// The `/VTKHDF` transient grid.
pub struct VtkHdf {
    pub(super) run: RunFile,
    pub(super) steps: hdf5::Group,
    pub(super) values: Growing,
    pub(super) geometry_offsets: Vec<Growing>,
    pub(super) point: Vec<(Growing, Growing)>,
    pub(super) cell: Vec<(Growing, Growing)>,
    pub(super) np: usize,
    pub(super) nc: usize,
    pub(super) frames: usize,
    pub(super) node_id_offsets: Growing,
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
    pub(super) fn write_static(
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
