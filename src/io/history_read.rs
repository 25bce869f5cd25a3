//! Reading a history back: `history.csv`, or the `history.csv.part` of a run still
//! being written or killed, whose last row may be cut mid-write. The one reader of the
//! file [`super::history`] writes, used by the plots (`crate::plot`) and the Python
//! package (its `history` while `step()` goes through a run, and at the end).

use super::*;

/// A history read back: its column names, in the file's order, and its complete rows
/// (one per step written, one value per column).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HistoryTable {
    /// The header's column names (none for an empty file).
    pub header: Vec<String>,
    /// The complete rows, in the file's order.
    pub rows: Vec<Vec<f64>>,
}

impl HistoryTable {
    /// The index of the column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// The table by column: `(name, values)` in the header's order.
    pub fn columns(&self) -> Vec<(String, Vec<f64>)> {
        self.header
            .iter()
            .enumerate()
            .map(|(i, h)| (h.clone(), self.rows.iter().map(|r| r[i]).collect()))
            .collect()
    }
}

/// The complete lines of a history: a row is complete when its newline was written, so
/// the row a kill cut (even one cut between two digits, which still parses) is left out.
pub fn complete_lines(text: &str) -> impl Iterator<Item = &str> {
    text.split_inclusive('\n')
        .filter(|l| l.ends_with('\n'))
        .map(|l| l.trim_end_matches(['\n', '\r']))
}

/// Reads the history file `path` (at most [`crate::limits::MAX_TEXT_BYTES`]): its
/// complete lines ([`complete_lines`]), the first the header. A row that is not one
/// number per column is refused, naming its line, except in a `.part` file, where the
/// rows end at it (the last line of a killed run's `.part` may be cut short). Numbers
/// read back to the bits written (`nan` and `inf` included).
pub fn read_history(path: &Path) -> Result<HistoryTable, Error> {
    let text = crate::limits::read_text(path, "history", crate::limits::MAX_TEXT_BYTES)?;
    let mut lines = complete_lines(&text);
    let Some(first) = lines.next() else {
        return Ok(HistoryTable::default());
    };
    let header: Vec<String> = first.split(',').map(str::to_string).collect();
    let part = path.extension().is_some_and(|e| e == "part");
    let mut rows = Vec::new();
    for (i, l) in lines.enumerate() {
        let r: Result<Vec<f64>, _> = l.split(',').map(str::parse).collect();
        match r {
            Ok(r) if r.len() == header.len() => rows.push(r),
            _ if part => break,
            _ => {
                return Err(Error::bad_file(
                    path,
                    format!("line {}", i + 2),
                    format!(
                        "`{}`: expected {} numbers separated by commas",
                        l.chars().take(120).collect::<String>(),
                        header.len()
                    ),
                ));
            }
        }
    }
    Ok(HistoryTable { header, rows })
}
