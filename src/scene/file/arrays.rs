//! Tables of numbers held flat: a mesh's points, its cells of one kind and a per-node
//! field, as a scene holds them ([`Rows`]), and the memory of a mesh given as arrays,
//! known from their shapes before anything is copied or built ([`arrays_memory`]).
//!
//! A scene file writes these tables as lists of rows (`[[x, y, z], …]`); code that holds
//! them already (the Python package's numpy arrays) hands them over as one flat buffer
//! each ([`Rows::from_flat`]), with no text and no allocation per row:
//!
//! ```
//! use signorini::scene::file::Rows;
//! let points = Rows::from_flat(vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0], 3).unwrap();
//! assert_eq!(points.len(), 2);
//! assert_eq!(points.row(1), &[1.0, 0.0, 0.0]);
//! assert_eq!(points.width(), Some(3));
//! ```

use std::fmt;
use std::marker::PhantomData;

use serde::de::{DeserializeSeed, SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::Error;
use crate::limits::{MemoryEstimate, mesh_memory};

/// Rows of values in one buffer, row after row: one allocation for a table of millions
/// of rows, where a list of lists would allocate each row.
///
/// The rows usually have one length (`width`). A scene file may hold rows of different
/// lengths, which the scene's checks refuse row by row with the row's key
/// (`mesh.points[1]`: "needs 3 coordinates"); such rows are kept as written, their ends
/// recorded. Serialized as a list of rows, as a scene file writes it.
#[derive(Clone, PartialEq)]
pub struct Rows<T> {
    data: Vec<T>,
    rows: usize,
    width: usize,
    /// The end of each row in `data` when the rows differ in length (`width` then
    /// means nothing).
    ends: Option<Vec<usize>>,
}

impl<T> Default for Rows<T> {
    fn default() -> Self {
        Rows {
            data: Vec::new(),
            rows: 0,
            width: 0,
            ends: None,
        }
    }
}

impl<T> Rows<T> {
    /// Rows of `width` values each from their values row after row (a C-ordered
    /// `(rows, width)` array). Refused when `data` is not a whole number of rows, or when
    /// `width` is 0 and `data` is not empty.
    pub fn from_flat(data: Vec<T>, width: usize) -> Result<Self, Error> {
        if width == 0 {
            return if data.is_empty() {
                Ok(Rows::default())
            } else {
                Err(Error::invalid(
                    "rows",
                    format!("{} values", data.len()),
                    "rows of 0 values hold none",
                ))
            };
        }
        if !data.len().is_multiple_of(width) {
            return Err(Error::invalid(
                "rows",
                format!("{} values", data.len()),
                &format!("is not a whole number of rows of {width} values"),
            ));
        }
        Ok(Rows {
            rows: data.len() / width,
            data,
            width,
            ends: None,
        })
    }

    /// Rows copied from a list of rows (of any lengths).
    pub fn from_rows<R: AsRef<[T]>>(rows: impl IntoIterator<Item = R>) -> Self
    where
        T: Clone,
    {
        let mut b = Builder::default();
        for r in rows {
            b.data.extend_from_slice(r.as_ref());
            b.end_row();
        }
        b.finish()
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.rows
    }

    /// Whether there is no row.
    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    /// The length of every row, `None` when the rows differ in length (or there is none).
    pub fn width(&self) -> Option<usize> {
        (self.ends.is_none() && self.rows > 0).then_some(self.width)
    }

    /// Row `i`.
    ///
    /// # Panics
    /// When `i >= self.len()`.
    pub fn row(&self, i: usize) -> &[T] {
        assert!(i < self.rows, "row {i} of {} rows", self.rows);
        match &self.ends {
            None => &self.data[i * self.width..(i + 1) * self.width],
            Some(ends) => &self.data[if i == 0 { 0 } else { ends[i - 1] }..ends[i]],
        }
    }

    /// The rows in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[T]> + '_ {
        (0..self.rows).map(move |i| self.row(i))
    }

    /// Every value, row after row.
    pub fn as_flat(&self) -> &[T] {
        &self.data
    }
}

impl<T: fmt::Debug> fmt::Debug for Rows<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<T: Serialize> Serialize for Rows<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.rows))?;
        for r in self.iter() {
            seq.serialize_element(r)?;
        }
        seq.end()
    }
}

/// Rows being read: values appended to one buffer, the ends recorded only once a row's
/// length differs from the first's.
struct Builder<T> {
    data: Vec<T>,
    rows: usize,
    width: usize,
    ends: Option<Vec<usize>>,
}

impl<T> Default for Builder<T> {
    fn default() -> Self {
        Builder {
            data: Vec::new(),
            rows: 0,
            width: 0,
            ends: None,
        }
    }
}

impl<T> Builder<T> {
    /// Closes the row whose values were appended since the last one.
    fn end_row(&mut self) {
        let end = self.data.len();
        if self.rows == 0 {
            self.width = end;
        } else if let Some(ends) = &mut self.ends {
            ends.push(end);
        } else if end != (self.rows + 1) * self.width {
            let mut ends: Vec<usize> = (1..=self.rows).map(|i| i * self.width).collect();
            ends.push(end);
            self.ends = Some(ends);
        }
        self.rows += 1;
    }

    fn finish(self) -> Rows<T> {
        Rows {
            data: self.data,
            rows: self.rows,
            width: self.width,
            ends: self.ends,
        }
    }
}

/// One row, its values appended to the builder's buffer.
struct RowSeed<'a, T>(&'a mut Vec<T>);

impl<'de, T: Deserialize<'de>> DeserializeSeed<'de> for RowSeed<'_, T> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, T: Deserialize<'de>> Visitor<'de> for RowSeed<'_, T> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a row: a list of numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while let Some(x) = seq.next_element()? {
            self.0.push(x);
        }
        Ok(())
    }
}

struct RowsVisitor<T>(PhantomData<T>);

impl<'de, T: Deserialize<'de>> Visitor<'de> for RowsVisitor<T> {
    type Value = Rows<T>;
    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a list of rows, each a list of numbers")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Rows<T>, A::Error> {
        let mut b = Builder::default();
        while seq.next_element_seed(RowSeed(&mut b.data))?.is_some() {
            b.end_row();
        }
        Ok(b.finish())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Rows<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_seq(RowsVisitor(PhantomData))
    }
}

/// The memory of a body's mesh given as arrays, from their shapes alone: `points`
/// points of `width` coordinates, `cells` as (count, nodes a cell) per cell kind, for a
/// body of dimension `dim` (1, 2 or 3). Counts the arrays as the scene holds them, the
/// mesh built from them and the assembled model of [`mesh_memory`]. The Python package
/// checks it against the memory limit before it copies a numpy array (issue 48: a
/// 10⁷-point mesh under a 256 MiB limit was refused only after 38 s and 7.2 GB).
pub fn arrays_memory(
    points: usize,
    width: usize,
    cells: &[(usize, usize)],
    dim: usize,
) -> MemoryEstimate {
    let n_cells = cells.iter().fold(0u64, |a, c| a.saturating_add(c.0 as u64));
    let per_cell = cells.iter().map(|c| c.1).max().unwrap_or(8);
    let mut m = mesh_memory(points as u64, n_cells, per_cell as u64, dim as u64);
    let values = cells.iter().fold(
        (points as u64).saturating_mul(width as u64),
        |a, &(n, k)| a.saturating_add((n as u64).saturating_mul(k as u64)),
    );
    m.add("the arrays", values, 8);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_read_back_as_written() {
        let r: Rows<f64> = serde_json::from_str("[[1, 2, 3], [4, 5, 6]]").unwrap();
        assert_eq!(r.width(), Some(3));
        assert_eq!(r.as_flat(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            "[[1.0,2.0,3.0],[4.0,5.0,6.0]]"
        );
        assert_eq!(
            r,
            Rows::from_flat(vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], 3).unwrap()
        );
        // rows of different lengths are kept as written, for the checks to name
        let r: Rows<usize> = serde_json::from_str("[[1, 2], [3], [4, 5, 6], []]").unwrap();
        assert_eq!(r.width(), None);
        let rows: Vec<&[usize]> = r.iter().collect();
        assert_eq!(rows, [&[1, 2][..], &[3], &[4, 5, 6], &[]]);
        assert_eq!(
            r,
            Rows::from_rows([vec![1, 2], vec![3], vec![4, 5, 6], vec![]])
        );
        let r: Rows<usize> = serde_json::from_str("[]").unwrap();
        assert!(r.is_empty() && r.width().is_none());
        assert!(Rows::from_flat(vec![1.0; 7], 3).is_err());
        assert!(Rows::from_flat(vec![1.0; 3], 0).is_err());
        assert!(serde_json::from_str::<Rows<usize>>("[[1, -2]]").is_err());
    }

    #[test]
    fn the_arrays_memory_counts_what_a_run_builds() {
        // 10⁷ points of a hex8 mesh: the assembled model alone is far past 256 MiB
        let m = arrays_memory(10_000_000, 3, &[(1_250_000, 8)], 3);
        assert!(m.total() > 100 << 30, "{}", m.total());
        assert!(
            m.parts()
                .iter()
                .any(|(w, b)| w == "the arrays" && *b == 320_000_000)
        );
    }
}
