//! VTK meshes: `.vtu` through our XML reader (`io::vtu`) and legacy `.vtk` (ASCII and
//! binary 5.1) through our own parser.

use super::*;

pub(super) fn vtk_kind(t: u8) -> (usize, Result<CellKind, String>) {
    if let Some(k) = CellKind::from_vtk(t) {
        return (k.dim(), Ok(k));
    }
    match t {
        1 | 2 => (0, Err(format!("VTK type {t} (vertex)"))),
        3 | 4 => (1, Err(format!("VTK type {t} (line)"))),
        6..=8 => (2, Err(format!("VTK type {t} (polygon/pixel)"))),
        11 | 13 | 14 => (3, Err(format!("VTK type {t} (voxel/wedge/pyramid)"))),
        _ => (3, Err(format!("VTK type {t} (quadratic or unknown)"))),
    }
}

pub(super) fn read_vtu(path: &Path, bytes: &[u8]) -> Result<RawMesh, Error> {
    let pieces = crate::io::vtu::read(path, bytes)?;
    let mut raw = RawMesh::default();
    for (pi, p) in pieces.into_iter().enumerate() {
        let base = raw.points.len();
        raw.points
            .extend(p.xyz.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let index = |what: &str, c: usize, v: f64| -> Result<usize, Error> {
            if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
                Ok(v as usize)
            } else {
                Err(bad(
                    path,
                    format!("piece {pi}, cell {c}: {what} {v} is not a non-negative integer"),
                ))
            }
        };
        // VTK's offsets are the cells' end positions; some writers lead with a 0
        let offs: &[f64] = if p.offsets.len() == p.cells + 1 && p.offsets.first() == Some(&0.0) {
            &p.offsets[1..]
        } else {
            &p.offsets
        };
        if offs.len() != p.types.len() {
            return Err(bad(
                path,
                format!(
                    "piece {pi}: {} cell offsets but {} cell types",
                    offs.len(),
                    p.types.len()
                ),
            ));
        }
        let mut start = 0usize;
        for (c, (&t, &end)) in p.types.iter().zip(offs).enumerate() {
            let end = index("offset", c, end)?;
            if end < start || end > p.connectivity.len() {
                return Err(bad(
                    path,
                    format!(
                        "piece {pi}, cell {c}: offset {end} is outside [{start}, {}] (offsets \
                         must grow and stay within the connectivity)",
                        p.connectivity.len()
                    ),
                ));
            }
            let t = index("type", c, t)?;
            let (d, kind) = vtk_kind(u8::try_from(t).unwrap_or(u8::MAX));
            let mut ns = Vec::with_capacity(end - start);
            for &v in &p.connectivity[start..end] {
                ns.push(base.saturating_add(index("point index", c, v)?));
            }
            raw.cells.push((d, kind, ns));
            start = end;
        }
        for (name, vals) in p.point_data {
            let set = vals
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(i, _)| base + i);
            raw.sets.entry(name).or_default().extend(set);
        }
    }
    Ok(raw)
}

/// Legacy `.vtk`, ASCII or BINARY (big-endian), versions up to 5.1 (meshio's default):
/// POINTS, CELLS (classic list or OFFSETS/CONNECTIVITY), CELL_TYPES, and POINT_DATA
/// SCALARS or FIELD arrays (read as node-set flags).
pub(super) fn read_legacy_vtk(path: &Path, bytes: &[u8]) -> Result<RawMesh, Error> {
    let mut r = Reader {
        b: bytes,
        pos: 0,
        binary: false,
        path,
    };
    let header = r.line()?;
    if !header.starts_with("# vtk DataFile") {
        return Err(bad(path, "not a legacy VTK file (first line)"));
    }
    r.line()?; // title
    r.binary = match r.line()?.trim() {
        "BINARY" => true,
        "ASCII" => false,
        other => {
            return Err(bad(
                path,
                format!("expected ASCII or BINARY, found `{other}`"),
            ));
        }
    };
    let ds = r.line()?;
    if ds.trim() != "DATASET UNSTRUCTURED_GRID" {
        return Err(bad(
            path,
            format!("only UNSTRUCTURED_GRID is supported, found `{}`", ds.trim()),
        ));
    }
    let mut raw = RawMesh::default();
    let mut conn: Vec<u64> = Vec::new();
    let mut offsets: Vec<u64> = Vec::new();
    let mut types: Vec<u8> = Vec::new();
    let mut npoints = 0usize;
    while let Some(line) = r.next_keyword_line()? {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w[0] {
            "POINTS" => {
                npoints = r.count(&w, 1)?;
                let n3 = npoints
                    .checked_mul(3)
                    .ok_or_else(|| r.err("POINTS count overflows"))?;
                let v = r.values(n3, w.get(2).copied().unwrap_or("float"))?;
                raw.points = v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
            }
            "CELLS" => {
                let n = r.count(&w, 1)?;
                let size = r.count(&w, 2)?;
                // version 5: OFFSETS <type> (n values) then CONNECTIVITY <type> (size values)
                let save = r.pos;
                let next = r.next_keyword_line()?.unwrap_or_default();
                if next.starts_with("OFFSETS") {
                    let t = next
                        .split_whitespace()
                        .nth(1)
                        .unwrap_or("vtktypeint64")
                        .to_string();
                    offsets = r.indices(n, &t, "OFFSETS")?;
                    let c = r.next_keyword_line()?.unwrap_or_default();
                    if !c.starts_with("CONNECTIVITY") {
                        return Err(bad(path, "OFFSETS not followed by CONNECTIVITY"));
                    }
                    let t = c
                        .split_whitespace()
                        .nth(1)
                        .unwrap_or("vtktypeint64")
                        .to_string();
                    conn = r.indices(size, &t, "CONNECTIVITY")?;
                } else {
                    r.pos = save;
                    let at = r.where_();
                    let list = r.indices(size, "int", "CELLS")?;
                    let mut k = 0;
                    offsets.push(0);
                    for c in 0..n {
                        let m = list.get(k).map(|&m| m as usize);
                        let Some(cell) = m.and_then(|m| list.get(k + 1..k.checked_add(1 + m)?))
                        else {
                            return Err(bad_at(
                                path,
                                at,
                                format!(
                                    "CELLS {n} {size}: cell {c} runs past the list's {size} \
                                     values (each cell is its node count then its nodes)"
                                ),
                            ));
                        };
                        conn.extend_from_slice(cell);
                        offsets.push(conn.len() as u64);
                        k += 1 + cell.len();
                    }
                    if k != list.len() {
                        return Err(bad_at(
                            path,
                            at,
                            format!("CELLS {n} {size}: the {n} cells use {k} of the {size} values"),
                        ));
                    }
                }
            }
            "CELL_TYPES" => {
                let n = r.count(&w, 1)?;
                types = r
                    .indices(n, "int", "CELL_TYPES")?
                    .iter()
                    .map(|&x| u8::try_from(x).unwrap_or(u8::MAX))
                    .collect();
            }
            "POINT_DATA" | "CELL_DATA" => {
                let on_points = w[0] == "POINT_DATA";
                let n = r.count(&w, 1)?;
                loop {
                    let save = r.pos;
                    let Some(l) = r.next_keyword_line()? else {
                        break;
                    };
                    let v: Vec<&str> = l.split_whitespace().collect();
                    match v[0] {
                        "SCALARS" => {
                            let ncomp: usize = match v.get(3) {
                                None => 1,
                                Some(s) => s
                                    .parse()
                                    .ok()
                                    .filter(|&c| (1..=4).contains(&c))
                                    .ok_or_else(|| {
                                        r.err(format!(
                                            "SCALARS {}: component count `{s}` is not in 1..=4",
                                            v.get(1).unwrap_or(&"")
                                        ))
                                    })?,
                            };
                            let lt = r.next_keyword_line()?.unwrap_or_default();
                            if !lt.starts_with("LOOKUP_TABLE") {
                                return Err(bad(path, "SCALARS without LOOKUP_TABLE"));
                            }
                            let name = *v
                                .get(1)
                                .ok_or_else(|| r.err("SCALARS without an array name"))?;
                            let total = n
                                .checked_mul(ncomp)
                                .ok_or_else(|| r.err("SCALARS size overflows"))?;
                            let vals = r.values(total, v.get(2).copied().unwrap_or("float"))?;
                            if on_points && ncomp == 1 {
                                add_flag_set(&mut raw, name, &vals);
                            }
                        }
                        "FIELD" => {
                            let arrays = r.count(&v, 2)?;
                            for _ in 0..arrays {
                                let a = r.next_keyword_line()?.unwrap_or_default();
                                let f: Vec<&str> = a.split_whitespace().collect();
                                let (ncomp, ntup) = (r.count(&f, 1)?, r.count(&f, 2)?);
                                let total = ncomp
                                    .checked_mul(ntup)
                                    .ok_or_else(|| r.err("FIELD array size overflows"))?;
                                let vals = r.values(total, f.get(3).copied().unwrap_or("float"))?;
                                if on_points && ncomp == 1 && ntup == n {
                                    let name = *f
                                        .first()
                                        .ok_or_else(|| r.err("FIELD array without a name"))?;
                                    add_flag_set(&mut raw, name, &vals);
                                }
                            }
                        }
                        "VECTORS" | "NORMALS" => {
                            let n3 = n
                                .checked_mul(3)
                                .ok_or_else(|| r.err("VECTORS count overflows"))?;
                            r.values(n3, v.get(2).copied().unwrap_or("float"))?;
                        }
                        _ => {
                            r.pos = save;
                            break;
                        }
                    }
                }
            }
            "METADATA" => {
                // skip until a blank line
                while let Ok(l) = r.line() {
                    if l.trim().is_empty() {
                        break;
                    }
                }
            }
            other => {
                return Err(r.err(format!(
                    "unexpected section `{other}` (expected POINTS, CELLS, CELL_TYPES, \
                     POINT_DATA, CELL_DATA or METADATA)"
                )));
            }
        }
    }
    if raw.points.len() != npoints || npoints == 0 {
        return Err(bad(path, "no POINTS section (or POINTS 0)"));
    }
    let offs: Vec<u64> = if offsets.first() == Some(&0) {
        offsets[1..].to_vec()
    } else {
        offsets
    };
    if offs.len() != types.len() {
        return Err(bad(
            path,
            format!("{} cells but {} CELL_TYPES", offs.len(), types.len()),
        ));
    }
    let mut start = 0usize;
    for (&t, &end) in types.iter().zip(&offs) {
        let end = end as usize;
        if end > conn.len() || end < start {
            return Err(bad(path, "cell offsets exceed the connectivity"));
        }
        let (d, kind) = vtk_kind(t);
        raw.cells.push((
            d,
            kind,
            conn[start..end].iter().map(|&v| v as usize).collect(),
        ));
        start = end;
    }
    Ok(raw)
}

pub(super) fn add_flag_set(raw: &mut RawMesh, name: &str, vals: &[f64]) {
    let set = vals
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(i, _)| i);
    raw.sets.entry(name.to_string()).or_default().extend(set);
}

pub(super) struct Reader<'a> {
    b: &'a [u8],
    pos: usize,
    binary: bool,
    path: &'a Path,
}

impl Reader<'_> {
    /// `line L` of the current position.
    fn where_(&self) -> String {
        format!("line {}", line_of(self.b, self.pos.saturating_sub(1)))
    }

    /// An error at the current line.
    fn err(&self, what: impl std::fmt::Display) -> Error {
        bad_at(self.path, self.where_(), what)
    }

    /// `n` values read as indices or counts: whole numbers in `[0, 2⁵³]`.
    fn indices(&mut self, n: usize, ty: &str, what: &str) -> Result<Vec<u64>, Error> {
        let at = self.where_();
        let v = self.values(n, ty)?;
        v.iter()
            .map(|&x| {
                if x >= 0.0 && x.fract() == 0.0 && x <= 9.007_199_254_740_992e15 {
                    Ok(x as u64)
                } else {
                    Err(bad_at(
                        self.path,
                        &at,
                        format!("{what}: {x} is not a valid index (expected a whole number ≥ 0)"),
                    ))
                }
            })
            .collect()
    }

    fn line(&mut self) -> Result<String, Error> {
        if self.pos >= self.b.len() {
            return Err(self.err("truncated: the file ends where more was expected"));
        }
        let end = self.b[self.pos..]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(self.b.len(), |e| self.pos + e);
        let s = String::from_utf8_lossy(&self.b[self.pos..end]).into_owned();
        self.pos = (end + 1).min(self.b.len());
        Ok(s)
    }

    /// Next non-blank line, or None at the end of the file.
    fn next_keyword_line(&mut self) -> Result<Option<String>, Error> {
        while self.pos < self.b.len() {
            let l = self.line()?;
            if !l.trim().is_empty() {
                return Ok(Some(l.trim().to_string()));
            }
        }
        Ok(None)
    }

    fn count(&self, w: &[&str], k: usize) -> Result<usize, Error> {
        w.get(k).and_then(|s| s.parse().ok()).ok_or_else(|| {
            self.err(format!(
                "`{}`: count {} is not a whole number",
                w.join(" "),
                w.get(k).unwrap_or(&"(missing)")
            ))
        })
    }

    fn values(&mut self, n: usize, ty: &str) -> Result<Vec<f64>, Error> {
        let left = (self.b.len() - self.pos) as u64;
        if !self.binary {
            // each ASCII value takes at least two bytes (a digit and a separator)
            let n = crate::limits::check_count(
                self.path,
                &self.where_(),
                "value",
                n as u64,
                2,
                left + 1,
            )?;
            let mut out = Vec::with_capacity(n);
            while out.len() < n {
                let l = self.line()?;
                for t in l.split_whitespace() {
                    out.push(
                        t.parse::<f64>()
                            .map_err(|_| self.err(format!("`{t}` is not a number")))?,
                    );
                }
            }
            if out.len() > n {
                return Err(self.err(format!(
                    "{} values on the lines of a block of {n}",
                    out.len()
                )));
            }
            return Ok(out);
        }
        let size = match ty {
            "double" | "vtktypeint64" | "long" | "vtktypeuint64" | "unsigned_long" => 8,
            "float" | "int" | "vtktypeint32" | "unsigned_int" | "vtktypeuint32" => 4,
            "short" | "unsigned_short" => 2,
            "char" | "unsigned_char" | "bit" => 1,
            other => return Err(self.err(format!("unsupported data type `{other}`"))),
        };
        crate::limits::check_count(
            self.path,
            &self.where_(),
            "value",
            n as u64,
            size as u64,
            left,
        )
        .map_err(|_| {
            self.err(format!(
                "truncated: {n} binary values of {size} bytes from byte {}, but the file \
                     ends at byte {}",
                self.pos,
                self.b.len()
            ))
        })?;
        let end = self.pos + n * size;
        let out = self.b[self.pos..end]
            .chunks(size)
            .map(|c| match (ty, size) {
                ("double", _) => f64::from_be_bytes(c.try_into().expect("8 bytes")),
                ("float", _) => f32::from_be_bytes(c.try_into().expect("4 bytes")) as f64,
                (t, 8) if t.contains("uint") || t.starts_with("unsigned") => {
                    u64::from_be_bytes(c.try_into().expect("8")) as f64
                }
                (_, 8) => i64::from_be_bytes(c.try_into().expect("8 bytes")) as f64,
                (t, 4) if t.contains("uint") || t.starts_with("unsigned") => {
                    u32::from_be_bytes(c.try_into().expect("4")) as f64
                }
                (_, 4) => i32::from_be_bytes(c.try_into().expect("4 bytes")) as f64,
                (t, 2) if t.starts_with("unsigned") => {
                    u16::from_be_bytes(c.try_into().expect("2")) as f64
                }
                (_, 2) => i16::from_be_bytes(c.try_into().expect("2 bytes")) as f64,
                (t, _) if t.starts_with("unsigned") || t == "bit" => c[0] as f64,
                _ => c[0] as i8 as f64,
            })
            .collect();
        self.pos = end;
        Ok(out)
    }
}
