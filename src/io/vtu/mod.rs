//! Reader of VTK XML unstructured grids (`.vtu`): the pieces' points, cells (connectivity,
//! offsets, types) and point-data arrays, as [`crate::io::mesh`] turns them into a mesh.
//!
//! What it reads: `DataArray`s in every format VTK and meshio write — `ascii`, inline
//! `binary` (base64, with or without `vtkZLibDataCompressor`, `header_type` `UInt32` or
//! `UInt64`, either byte order) and `appended` (`raw` or `base64` `AppendedData`, as
//! ParaView and VTK write by default) —, of every numeric type (`Int8` … `UInt64`,
//! `Float32`, `Float64`). Other compressors (LZ4, LZMA) are refused by name.
//!
//! Ours on quick-xml rather than vtkio's: vtkio 0.7 is a pre-release that panicked on
//! malformed input (fuzzing found index panics within seconds, which a process-wide
//! panic hook had to hide) and does not read raw appended data. Here every count is
//! checked against the bytes that hold it before anything is allocated, a compressed
//! array may not claim more than zlib's largest ratio (1032:1) of its compressed size,
//! and each error names the file, the piece, the array and what is wrong.

use std::path::Path;

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

use crate::error::Error;

mod decode;
mod layout;

use decode::*;
use layout::*;

/// zlib's largest expansion (deflate's maximum ratio is 1032:1): a compressed block
/// claiming more is corrupt, and decompressing it could exhaust memory.
const MAX_ZLIB_RATIO: u64 = 1032;
/// Largest number of values in one array (2³¹: 16 GiB of f64).
const MAX_VALUES: u64 = 1 << 31;
/// Largest number of nodes a cell may list (VTK's quadratic and Lagrange cells stay well
/// below): bounds a piece's connectivity by its cell count before it is read.
const MAX_CELL_NODES: u64 = 64;

/// One piece of the grid, as its arrays hold it.
#[derive(Debug, Default)]
pub(crate) struct Piece {
    /// `NumberOfPoints`.
    pub points: usize,
    /// `NumberOfCells`.
    pub cells: usize,
    /// Point coordinates, 3 per point.
    pub xyz: Vec<f64>,
    /// Cell connectivity (0-based point indices within the piece).
    pub connectivity: Vec<f64>,
    /// End offset of each cell in `connectivity`.
    pub offsets: Vec<f64>,
    /// VTK cell type codes.
    pub types: Vec<f64>,
    /// Point-data arrays with one component: (name, one value per point).
    pub point_data: Vec<(String, Vec<f64>)>,
}

/// How the file stores binary data.
#[derive(Clone, Copy, Debug)]
struct Layout {
    big_endian: bool,
    /// Bytes per header word: 4 (`UInt32`) or 8 (`UInt64`).
    word: usize,
    compressed: bool,
}

/// Where a `DataArray` is and what it holds.
#[derive(Debug)]
struct ArrayRef {
    piece: usize,
    role: Role,
    name: String,
    /// Bytes per value and how to read one.
    kind: NumKind,
    components: usize,
    source: Source,
}

#[derive(Debug)]
enum Source {
    Ascii(String),
    Binary(String),
    Appended(usize),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Points,
    Connectivity,
    Offsets,
    Types,
    PointData,
    Ignored,
}

#[derive(Clone, Copy, Debug)]
enum NumKind {
    I(usize),
    U(usize),
    F(usize),
}

impl NumKind {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "Int8" => NumKind::I(1),
            "Int16" => NumKind::I(2),
            "Int32" => NumKind::I(4),
            "Int64" => NumKind::I(8),
            "UInt8" => NumKind::U(1),
            "UInt16" => NumKind::U(2),
            "UInt32" => NumKind::U(4),
            "UInt64" => NumKind::U(8),
            "Float32" => NumKind::F(4),
            "Float64" => NumKind::F(8),
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            NumKind::I(s) | NumKind::U(s) | NumKind::F(s) => s,
        }
    }

    /// One value from `b` (`size()` bytes).
    fn read(self, b: &[u8], big_endian: bool) -> f64 {
        let mut a = [0u8; 8];
        let n = b.len();
        if big_endian {
            a[8 - n..].copy_from_slice(b);
            a.reverse();
        } else {
            a[..n].copy_from_slice(b);
        }
        let raw = u64::from_le_bytes(a);
        match self {
            NumKind::U(_) => raw as f64,
            NumKind::I(s) => {
                let shift = 64 - 8 * s as u32;
                (((raw << shift) as i64) >> shift) as f64
            }
            NumKind::F(4) => f32::from_bits(raw as u32) as f64,
            NumKind::F(_) => f64::from_bits(raw),
        }
    }
}

fn bad(path: &Path, at: impl std::fmt::Display, what: impl std::fmt::Display) -> Error {
    Error::bad_file(path, at, what)
}

/// Reads the pieces of the unstructured grid in `bytes` (the file `path`).
pub(crate) fn read(path: &Path, bytes: &[u8]) -> Result<Vec<Piece>, Error> {
    // raw appended data is not XML: parse the markup before it, keep the data apart
    let (xml_bytes, appended) = split_appended(path, bytes)?;
    let xml = std::str::from_utf8(xml_bytes).map_err(|e| {
        bad(
            path,
            format!("byte {}", e.valid_up_to()),
            "is not UTF-8 text (a VTK XML file is text up to its AppendedData)",
        )
    })?;
    let line = |pos: u64| {
        let pos = (pos as usize).min(xml.len());
        format!(
            "line {}",
            1 + xml.as_bytes()[..pos]
                .iter()
                .filter(|&&b| b == b'\n')
                .count()
        )
    };
    let mut reader = Reader::from_str(xml);
    let mut layout = None;
    let mut pieces: Vec<Piece> = Vec::new();
    let mut arrays: Vec<ArrayRef> = Vec::new();
    let mut section = Role::Ignored;
    let mut grid = false;
    // the array whose text is being collected
    let mut open: Option<ArrayRef> = None;
    // depth of elements inside that array (VTK's `InformationKey`s), whose text is not data
    let mut skip = 0usize;
    loop {
        let pos = reader.buffer_position();
        let ev = match reader.read_event() {
            Ok(ev) => ev,
            // the markup before raw appended data ends unclosed: that is its end
            Err(_) if appended.is_some() && open.is_none() => break,
            Err(e) => {
                return Err(bad(
                    path,
                    line(reader.error_position()),
                    format!("XML error: {e}"),
                ));
            }
        };
        let (e, empty) = match ev {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) if skip > 0 => {
                skip -= 1;
                continue;
            }
            Event::Text(t) if skip == 0 => {
                push_text(&mut open, &t);
                continue;
            }
            Event::CData(t) if skip == 0 => {
                push_text(&mut open, &t);
                continue;
            }
            Event::End(e) => {
                match e.name().as_ref() {
                    "DataArray" => arrays.extend(open.take()),
                    "Points" | "Cells" | "PointData" | "CellData" | "FieldData" => {
                        section = Role::Ignored
                    }
                    _ => {}
                }
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        if open.is_some() {
            // metadata inside an array (`InformationKey`): skipped with its content
            if name_of(&e) == "DataArray" {
                return Err(bad(path, line(pos), "a DataArray inside a DataArray"));
            }
            skip += usize::from(!empty);
            continue;
        }
        match name_of(&e).as_str() {
            "VTKFile" => {
                let ty = attr(path, &e, "type")?.unwrap_or_default();
                if ty != "UnstructuredGrid" {
                    return Err(bad(
                        path,
                        line(pos),
                        format!("VTKFile type `{ty}`: expected UnstructuredGrid (a .vtu mesh)"),
                    ));
                }
                layout = Some(file_layout(path, &e, &line(pos))?);
            }
            "UnstructuredGrid" => grid = true,
            "Piece" if grid => {
                let count = |key: &str| -> Result<usize, Error> {
                    let v = attr(path, &e, key)?
                        .ok_or_else(|| bad(path, line(pos), format!("Piece has no {key}")))?;
                    v.trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&n| (n as u64) < MAX_VALUES)
                        .ok_or_else(|| {
                            bad(
                                path,
                                line(pos),
                                format!("Piece {key} `{v}`: expected a count below {MAX_VALUES}"),
                            )
                        })
                };
                pieces.push(Piece {
                    points: count("NumberOfPoints")?,
                    cells: count("NumberOfCells")?,
                    ..Piece::default()
                });
            }
            "Points" => section = Role::Points,
            "Cells" => section = Role::Connectivity,
            "PointData" => section = Role::PointData,
            "CellData" | "FieldData" => section = Role::Ignored,
            "DataArray" => {
                let Some(piece) = pieces.len().checked_sub(1) else {
                    // arrays outside a piece (FieldData of the file) are not ours
                    continue;
                };
                let a = data_array(path, &e, piece, section, &line(pos))?;
                if empty {
                    arrays.push(a);
                } else {
                    open = Some(a);
                }
            }
            _ => {}
        }
    }
    let layout = layout.ok_or_else(|| bad(path, "", "no <VTKFile> element: not a VTK XML file"))?;
    if !grid || pieces.is_empty() {
        return Err(bad(path, "", "no UnstructuredGrid Piece"));
    }
    let appended = match appended {
        Some((enc, data)) => Some(appended_regions(path, enc, data, &arrays)?),
        None => None,
    };
    for (i, a) in arrays.iter().enumerate() {
        if a.role == Role::Ignored {
            continue;
        }
        let piece = &pieces[a.piece];
        let at = format!("piece {}, DataArray `{}`", a.piece, a.name);
        // how many values the piece says it holds (connectivity: at most what its cells
        // can list)
        let expected = match a.role {
            Role::Points => Some(piece.points as u64 * 3),
            Role::Offsets | Role::Types => Some(piece.cells as u64),
            Role::PointData => Some(piece.points as u64 * a.components as u64),
            _ => None,
        };
        let at_most = expected
            .unwrap_or(piece.cells as u64 * MAX_CELL_NODES)
            .min(MAX_VALUES);
        let values = match &a.source {
            Source::Ascii(s) => ascii_values(path, &at, s, expected)?,
            Source::Binary(s) => {
                let payload = base64_segments(path, &at, s)?;
                binary_values(path, &at, &payload, layout, a.kind, (expected, at_most))?
            }
            Source::Appended(_) => {
                let regions = appended.as_ref().ok_or_else(|| {
                    bad(
                        path,
                        &at,
                        "format=\"appended\" but the file has no AppendedData",
                    )
                })?;
                binary_values(path, &at, &regions[i], layout, a.kind, (expected, at_most))?
            }
        };
        if let Some(n) = expected
            && values.len() as u64 != n
        {
            return Err(bad(
                path,
                &at,
                format!("{} values, expected {n}", values.len()),
            ));
        }
        let p = &mut pieces[a.piece];
        match a.role {
            Role::Points => p.xyz = values,
            Role::Connectivity => p.connectivity = values,
            Role::Offsets => p.offsets = values,
            Role::Types => p.types = values,
            Role::PointData if a.components == 1 => p.point_data.push((a.name.clone(), values)),
            _ => {}
        }
    }
    for (i, p) in pieces.iter().enumerate() {
        if p.xyz.len() != 3 * p.points {
            return Err(bad(path, format!("piece {i}"), "has no Points DataArray"));
        }
        if p.cells > 0 && (p.offsets.is_empty() || p.types.is_empty()) {
            return Err(bad(
                path,
                format!("piece {i}"),
                "Cells needs `connectivity`, `offsets` and `types` DataArrays",
            ));
        }
    }
    Ok(pieces)
}
