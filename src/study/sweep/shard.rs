//! A sweep spread over Slurm array tasks or MPI ranks: which points a shard owns, the
//! grid every shard must agree on, and the merge of the shards' records into one table.

use super::*;

/// A shard of the grid: points `id` with `id % count == index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard (0-based).
    pub index: usize,
    /// Shards in all.
    pub count: usize,
}

impl Shard {
    /// Parses `i/N` (0 ≤ i < N).
    pub fn parse(s: &str) -> Result<Shard, Error> {
        let bad = || Error::invalid("--shard", s, "expected i/N with 0 ≤ i < N, e.g. 0/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count || count > MAX_POINTS {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// From Slurm's job-array variables: `SLURM_ARRAY_TASK_ID` less
    /// `SLURM_ARRAY_TASK_MIN` (0 when unset) of `SLURM_ARRAY_TASK_COUNT`; `None` outside
    /// an array job.
    pub fn from_slurm(env: impl Fn(&str) -> Option<String>) -> Result<Option<Shard>, Error> {
        let (Some(id), Some(count)) = (env("SLURM_ARRAY_TASK_ID"), env("SLURM_ARRAY_TASK_COUNT"))
        else {
            return Ok(None);
        };
        let num = |name: &str, v: &str| -> Result<usize, Error> {
            v.trim()
                .parse()
                .map_err(|_| Error::invalid(name, v, "expected a non-negative integer"))
        };
        let id = num("SLURM_ARRAY_TASK_ID", &id)?;
        let min = match env("SLURM_ARRAY_TASK_MIN") {
            Some(m) => num("SLURM_ARRAY_TASK_MIN", &m)?,
            None => 0,
        };
        let count = num("SLURM_ARRAY_TASK_COUNT", &count)?;
        let index = id.checked_sub(min).ok_or_else(|| {
            Error::invalid("SLURM_ARRAY_TASK_ID", id, "is below SLURM_ARRAY_TASK_MIN")
        })?;
        if count == 0 || index >= count {
            // named in the user's terms: they never passed a --shard (issue 34)
            return Err(Error::invalid(
                "SLURM_ARRAY_TASK_ID",
                id,
                &format!(
                    "is task {index} of an array of SLURM_ARRAY_TASK_COUNT = {count} tasks \
                     from SLURM_ARRAY_TASK_MIN = {min}: the sweep expects consecutive task \
                     ids (sbatch --array=0-{})",
                    count.saturating_sub(1)
                ),
            ));
        }
        Shard::parse(&format!("{index}/{count}")).map(Some)
    }

    /// Whether point `id` is this shard's.
    pub fn owns(&self, id: usize) -> bool {
        id % self.count == self.index
    }

    /// The shard's directory under the sweep's.
    pub fn dir(&self, sweep: &Path) -> PathBuf {
        sweep.join(format!("shard-{}-of-{}", self.index, self.count))
    }
}

/// Refuses a `grid.json` that is not `grid`'s.
pub(super) fn check_grid(path: &Path, grid: &Grid) -> Result<(), Error> {
    let text = crate::limits::read_text(path, "sweep grid", crate::limits::MAX_TEXT_BYTES)?;
    let old: Grid = serde_json::from_str(&text)
        .map_err(|e| Error::bad_file(path, "", format!("is not a sweep grid: {e}")))?;
    if &old != grid {
        return Err(Error::bad_file(
            path,
            "",
            "describes another sweep (scene, --set or axes differ): resume with the same \
             arguments, or write the new sweep into another directory",
        ));
    }
    Ok(())
}

/// `signorini sweep merge DIR`: gathers the records of `DIR/shard-*-of-N/` (every shard
/// of one grid) into `DIR/runs/`, and writes the whole grid's table into `DIR`; returns
/// the verdicts. Refuses shards of different grids and a grid with points missing.
pub fn merge(dir: &Path) -> Result<Vec<String>, Error> {
    let mut shards: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_dir()
                && p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with("shard-"))
        })
        .collect();
    shards.sort();
    if shards.is_empty() {
        return Err(Error::bad_file(
            dir,
            "",
            "holds no shard-i-of-N directory to merge",
        ));
    }
    // every shard's grid first: one grid, whose points the records must be
    let mut grid: Option<Grid> = None;
    for s in &shards {
        let gp = s.join("grid.json");
        let text = crate::limits::read_text(&gp, "sweep grid", crate::limits::MAX_TEXT_BYTES)?;
        let g: Grid = serde_json::from_str(&text)
            .map_err(|e| Error::bad_file(&gp, "", format!("is not a sweep grid: {e}")))?;
        match &grid {
            None => grid = Some(g),
            Some(first) if first != &g => {
                return Err(Error::bad_file(
                    &gp,
                    "",
                    format!(
                        "describes another sweep than {}",
                        shards[0].join("grid.json").display()
                    ),
                ));
            }
            Some(_) => {}
        }
    }
    let grid = grid.expect("at least one shard");
    let expected = points(&grid.spec);
    let mut records: BTreeMap<usize, RunRecord> = BTreeMap::new();
    for s in &shards {
        for r in read_records(s)? {
            // a record of another grid (issue 34: it became a third row of a 2-point
            // grid)
            if expected.get(r.point.id) != Some(&r.point) {
                return Err(Error::bad_file(
                    s.join("runs").join(format!("{:06}.json", r.point.id)),
                    "",
                    format!(
                        "holds run {} ({}), not a point of the grid of {}",
                        r.point.id,
                        r.point.key,
                        s.join("grid.json").display()
                    ),
                ));
            }
            records.insert(r.point.id, r);
        }
    }
    let missing: Vec<usize> = expected
        .iter()
        .filter(|p| records.get(&p.id).is_none_or(|r| &r.point != *p))
        .map(|p| p.id)
        .collect();
    if !missing.is_empty() {
        return Err(Error::bad_file(
            dir,
            "",
            format!(
                "misses {} of the grid's {} runs (first: {:?}): a shard has not finished; \
                 rerun it with --resume",
                missing.len(),
                expected.len(),
                &missing[..missing.len().min(8)]
            ),
        ));
    }
    // held while the merged table is written: a second merge (or a sweep) into the
    // same directory is refused meanwhile
    let _lock = crate::io::RunLock::acquire(dir)?;
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).map_err(|e| Error::write(&runs, e))?;
    // the records of an older sweep or merge in this directory would sit beside a new
    // grid.json
    remove_records(&runs)?;
    for r in records.values() {
        write_atomic(
            &runs.join(format!("{:06}.json", r.point.id)),
            serde_json::to_string(r)
                .expect("record serializes")
                .as_bytes(),
        )?;
    }
    write_atomic(
        &dir.join("grid.json"),
        serde_json::to_string_pretty(&grid)
            .expect("grid serializes")
            .as_bytes(),
    )?;
    let rows = table(records.into_values().collect());
    let levels = if grid.spec.levels.is_empty() {
        DEFAULT_LEVELS.to_vec()
    } else {
        grid.spec.levels.clone()
    };
    write_table(dir, &rows, &levels, "sweep")
}
