//! Readers shared by the output tests: `.vtu` frames through vtkio (an independent
//! reader) and `.pvd` collections.
#![allow(dead_code)]

pub mod bad;
pub mod blocks;
pub mod free;
pub mod scratch;
pub mod sweeps;

use std::collections::HashMap;

/// `max |a − b|` over the largest `|a|`: how far two runs' values part, relative to
/// their scale.
pub fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = a.iter().fold(0.0_f64, |m, x| m.max(x.abs())).max(1e-300);
    a.iter()
        .zip(b)
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}
use std::path::Path;

/// One frame as vtkio reads it: points, VTK cell types, point and cell arrays.
pub struct Frame {
    pub points: Vec<f64>,
    pub types: Vec<u8>,
    pub point: HashMap<String, Vec<f64>>,
    pub cell: HashMap<String, Vec<f64>>,
}

pub fn read_frame(path: &Path) -> Frame {
    use vtkio::model::{Attribute, DataSet};
    let vtk = vtkio::Vtk::import(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    let p = pieces
        .into_iter()
        .next()
        .unwrap()
        .into_loaded_piece_data(None)
        .unwrap();
    let arrays = |attrs: Vec<Attribute>| {
        attrs
            .into_iter()
            .filter_map(|a| match a {
                Attribute::DataArray(d) => Some((d.name.clone(), d.data.cast_into::<f64>()?)),
                _ => None,
            })
            .collect::<HashMap<_, _>>()
    };
    Frame {
        points: p.points.cast_into().unwrap(),
        types: p.cells.types.iter().map(|t| *t as u8).collect(),
        point: arrays(p.data.point),
        cell: arrays(p.data.cell),
    }
}

/// (time, file) of every `<DataSet>` in a `.pvd`.
pub fn read_pvd(path: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| l.contains("<DataSet"))
        .map(|l| {
            let attr = |k: &str| {
                let s = &l[l.find(&format!("{k}=\"")).unwrap() + k.len() + 2..];
                s[..s.find('"').unwrap()].to_string()
            };
            (attr("timestep").parse().unwrap(), attr("file"))
        })
        .collect()
}
