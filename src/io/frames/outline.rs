//! Geometry written beside the frames: the outlines of obstacles (planes, spheres,
//! cylinders) for ParaView, a rod drawn as a line of cells, and the orthonormal frame of
//! a normal.

use super::*;

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
                    model: crate::model::solid::MaterialModel::LINEAR,
                },
                Formulation::Solid,
            )],
            dim: 1,
            dof_of: (0..=n).map(Some).collect(),
            ..Geometry::default()
        }
    }
}
