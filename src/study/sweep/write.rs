//! The sweep's files: the CSV of the table (its columns named with units) and the
//! Markdown table, written atomically.

use super::*;

/// The CSV of `rows`; `timings` false leaves the timing columns out (what a merged
/// table is compared with the unsharded one on).
pub fn csv(rows: &[Row], timings: bool) -> String {
    let axes: Vec<String> = rows
        .first()
        .map(|r| r.record.point.values.keys().cloned().collect())
        .unwrap_or_default();
    let mut x = String::from("id");
    for a in &axes {
        let _ = write!(x, ",{a}");
    }
    x.push_str(",status,steps,dofs,time_step");
    if timings {
        x.push_str(",wall_seconds,us_per_step,setup_seconds,peak_memory_bytes,worker");
    }
    x.push_str(
        ",memory_planned_bytes,newton_mean,newton_max,projection_mean,lcp_mean,\
         friction_sweeps_mean,caps_hit,energy_start,energy_end,peak_force,contact_duration,\
         reference",
    );
    for (m, _) in MEASURES {
        let _ = write!(x, ",{m}");
    }
    if timings {
        for (m, _) in MEASURES {
            let _ = write!(x, ",front_{m}");
        }
    }
    x.push_str(",message\n");
    let reference_id = rows
        .iter()
        .find(|r| r.is_reference)
        .map(|r| r.record.point.id);
    let f = |v: f64| {
        if v.is_nan() {
            String::new()
        } else {
            format!("{v:e}")
        }
    };
    for r in rows {
        let c = &r.record;
        let _ = write!(x, "{}", c.point.id);
        for a in &axes {
            let v = c.point.values.get(a).map_or("", |s| s.as_str());
            let _ = write!(x, ",{}", v.trim_matches('"').replace(',', ";"));
        }
        let _ = write!(x, ",{},{},{},{:e}", c.status, c.steps, c.dofs, c.dt);
        if timings {
            let _ = write!(
                x,
                ",{},{},{},{},{}",
                f(c.wall_seconds),
                f(1e6 * c.wall_seconds / c.steps.max(1) as f64),
                f(c.setup_seconds),
                c.peak_memory_bytes.map_or(String::new(), |b| b.to_string()),
                c.worker
            );
        }
        let _ = write!(
            x,
            ",{},{},{},{},{},{},{},{},{},{},{},{}",
            c.memory_planned_bytes,
            f(c.newton_mean),
            c.newton_max,
            f(c.projection_mean),
            f(c.lcp_mean),
            c.friction_sweeps_mean.map_or(String::new(), f),
            c.caps_hit,
            f(c.energy[0]),
            f(c.energy[1]),
            f(c.peak_force),
            f(c.contact_duration),
            if c.analytic.is_some() {
                "analytic".to_string()
            } else if r.is_reference {
                "itself (the finest run)".to_string()
            } else {
                reference_id.map_or("none".to_string(), |i| format!("run {i}"))
            }
        );
        for e in r.errors {
            let _ = write!(x, ",{}", f(e));
        }
        if timings {
            for b in r.front {
                let _ = write!(x, ",{}", u8::from(b));
            }
        }
        let msg = c.message.as_deref().unwrap_or("").replace(['\n', ','], " ");
        let _ = writeln!(x, ",{msg}");
    }
    x
}

/// The columns of a CSV written by [`csv`]: numbers where every non-empty cell is
/// one (empty cells NaN), text otherwise (the HDF5 table's columns).
#[cfg(feature = "hdf5")]
pub(super) fn csv_columns(text: &str) -> Vec<(String, crate::io::h5::TableColumn)> {
    use crate::io::h5::TableColumn;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    header
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let cells: Vec<&str> = rows
                .iter()
                .map(|r| r.get(k).copied().unwrap_or(""))
                .collect();
            let numbers: Option<Vec<f64>> = cells
                .iter()
                .map(|c| {
                    if c.is_empty() {
                        Some(f64::NAN)
                    } else {
                        c.parse().ok()
                    }
                })
                .collect();
            let col = match numbers {
                Some(v) if name != &"message" => TableColumn::Numbers(v),
                _ => TableColumn::Text(cells.iter().map(|c| c.to_string()).collect()),
            };
            (name.to_string(), col)
        })
        .collect()
}

/// Writes `sweep.csv`, the plot and `verdict.txt` of `rows` into `dir`; returns the
/// verdicts.
pub fn write_table(
    dir: &Path,
    rows: &[Row],
    levels: &[f64],
    stem: &str,
) -> Result<Vec<String>, Error> {
    let text = csv(rows, true);
    write_atomic(&dir.join(format!("{stem}.csv")), text.as_bytes())?;
    #[cfg(feature = "hdf5")]
    crate::io::h5::write_table(&dir.join(format!("{stem}.h5")), &csv_columns(&text))?;
    let mut schemes: Vec<String> = rows.iter().map(scheme_of).collect();
    schemes.sort();
    schemes.dedup();
    let curves: Vec<Curve> = schemes
        .iter()
        .map(|s| {
            // each scheme's own front
            let mut own: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| {
                    &scheme_of(r) == s && !r.errors[0].is_nan() && r.record.wall_seconds.is_finite()
                })
                .map(|r| (r.record.wall_seconds, r.errors[0].max(1e-15)))
                .collect();
            own.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            let mut best = f64::INFINITY;
            own.retain(|p| {
                let keep = p.1 < best;
                best = best.min(p.1);
                keep
            });
            Curve {
                name: s.clone(),
                points: own,
            }
        })
        .filter(|c| !c.points.is_empty())
        .collect();
    if !curves.is_empty() {
        lines(
            &dir.join(format!("{stem}-accuracy")),
            "accuracy reachable within a wall time (each scheme's Pareto front)",
            "wall time of the step loop (s)",
            "relative error",
            &curves,
            true,
        )?;
    }
    let v = verdicts(rows, levels);
    write_atomic(&dir.join("verdict.txt"), (v.join("\n") + "\n").as_bytes())?;
    Ok(v)
}
