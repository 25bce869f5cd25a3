//! The sweep's table and its verdicts: one row per point, the measures against the
//! reference, and which points are on the speed–accuracy front.

use super::*;

/// The table of `records` (any order; sorted by point id).
pub fn table(mut records: Vec<RunRecord>) -> Vec<Row> {
    records.sort_by_key(|r| r.point.id);
    let reference = reference_run(&records);
    let refr = reference.map(|i| records[i].clone());
    let mut rows: Vec<Row> = records
        .into_iter()
        .enumerate()
        .map(|(i, r)| {
            let mut e = [f64::NAN; 10];
            // max |u − u_ref| / max |u_ref| over every probe, time and component
            let probe_error = |u: &[f64], v: &[f64]| {
                let scale = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                (scale > 0.0 && !u.is_empty() && u.len() == v.len()).then(|| {
                    u.iter()
                        .zip(v)
                        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
                        / scale
                })
            };
            let probe_analytic = r
                .probes_analytic
                .as_deref()
                .and_then(|a| probe_error(&r.probes, a));
            if r.status == "ok" {
                if let Some(a) = r.analytic {
                    e[1] = a[0].abs();
                    e[2] = a[1].abs();
                    e[3] = a[2].abs();
                }
                let same_span = refr
                    .as_ref()
                    .is_some_and(|f| (r.t_end - f.t_end).abs() <= 1e-12 * f.t_end);
                if let Some(f) = refr.as_ref().filter(|_| Some(i) != reference && !same_span) {
                    // runs of different lengths (an axis on time.t_end): the impulse
                    // compared by time over the shorter span, sample by sample of this
                    // run; the final energy and the peak force are not comparable (NaN)
                    // (issue 34: they were compared sample by sample, error 0.63 for
                    // the same trajectory)
                    let span = r.t_end.min(f.t_end);
                    let total = trace_at(&f.impulse, f.t_end, span);
                    let n = r.impulse.len();
                    if total > 0.0 && n > 0 && !f.impulse.is_empty() {
                        e[4] = r
                            .impulse
                            .iter()
                            .enumerate()
                            .map(|(j, a)| (j, a, r.t_end * (j + 1) as f64 / n as f64))
                            .filter(|&(_, _, t)| t <= span * (1.0 + 1e-12))
                            .map(|(_, a, t)| (a - trace_at(&f.impulse, f.t_end, t)).abs())
                            .fold(0.0, f64::max)
                            / total;
                    }
                }
                if let Some(f) = refr.as_ref().filter(|_| Some(i) != reference && same_span) {
                    let total = f.impulse.last().copied().unwrap_or(0.0);
                    if total > 0.0 && r.impulse.len() == f.impulse.len() {
                        e[4] = r
                            .impulse
                            .iter()
                            .zip(&f.impulse)
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max)
                            / total;
                        e[9] = impulse_in_time(&r.impulse, &f.impulse) / total;
                    }
                    if f.peak_force > 0.0 {
                        e[5] = (r.peak_force / f.peak_force - 1.0).abs();
                    }
                    let scale = f.energy[0].abs().max(f.energy[1].abs());
                    if scale > 0.0 {
                        e[6] = (r.energy[1] - f.energy[1]).abs() / scale;
                    }
                }
                e[7] = r.max_violation;
                e[8] = match (
                    probe_analytic,
                    refr.as_ref().filter(|_| Some(i) != reference),
                ) {
                    (Some(x), _) => x,
                    (None, Some(f)) => probe_error(&r.probes, &f.probes).unwrap_or(f64::NAN),
                    (None, None) => f64::NAN,
                };
                e[0] = if r.analytic.is_some() {
                    let probes = probe_analytic.unwrap_or(0.0);
                    e[1].max(e[2]).max(e[3]).max(probes)
                } else {
                    [e[4], e[6], e[8]]
                        .into_iter()
                        .filter(|x| !x.is_nan())
                        .fold(f64::NAN, f64::max)
                };
            }
            Row {
                record: r,
                errors: e,
                front: [false; 10],
                is_reference: Some(i) == reference,
            }
        })
        .collect();
    for m in 0..MEASURES.len() {
        let mut idx: Vec<usize> = (0..rows.len())
            .filter(|&i| !rows[i].errors[m].is_nan() && rows[i].record.wall_seconds.is_finite())
            .collect();
        idx.sort_by(|&a, &b| {
            rows[a]
                .record
                .wall_seconds
                .total_cmp(&rows[b].record.wall_seconds)
                .then(rows[a].errors[m].total_cmp(&rows[b].errors[m]))
        });
        let mut best = f64::INFINITY;
        for i in idx {
            if rows[i].errors[m] < best {
                best = rows[i].errors[m];
                rows[i].front[m] = true;
            }
        }
    }
    rows
}

/// `∫₀ᵀ |P − P_ref| dt / T` of two cumulative impulse traces sampled at the same
/// `T (i + 1) / n` (0 at t = 0), by the trapezoidal rule over the samples: the sweep's
/// reading of the error in time that `signorini study accuracy` integrates exactly over
/// the steps ([`impulse_difference_in_time`]); a shift below the sampling interval
/// counts by its share of it.
pub(super) fn impulse_in_time(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    if n == 0 {
        return f64::NAN;
    }
    let (mut prev, mut sum) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(b) {
        let d = (x - y).abs();
        sum += 0.5 * (prev + d);
        prev = d;
    }
    sum / n as f64
}

/// The scheme of a row (its `scheme` axis value, else `scene`).
pub(super) fn scheme_of(r: &Row) -> String {
    r.record
        .point
        .values
        .get("scheme")
        .map_or("scene's scheme".to_string(), |s| {
            s.trim_matches('"').to_string()
        })
}

/// One verdict line per scheme: the cheapest run reaching each level of accuracy, and
/// the best accuracy reached; then which scheme reaches each level first.
pub fn verdicts(rows: &[Row], levels: &[f64]) -> Vec<String> {
    let mut out = Vec::new();
    let against = if rows.iter().any(|r| r.record.analytic.is_some()) {
        "the analytic reference".to_string()
    } else {
        match rows.iter().find(|r| r.is_reference) {
            Some(r) => format!(
                "the finest run (#{}: {})",
                r.record.point.id, r.record.point.key
            ),
            None => "nothing (no run ended)".to_string(),
        }
    };
    out.push(format!(
        "sweep: {} runs, accuracy (relative error) against {against}",
        rows.len()
    ));
    let failed = rows.iter().filter(|r| r.record.status != "ok").count();
    if failed > 0 {
        out.push(format!(
            "sweep: {failed} runs failed (see the message column)"
        ));
    }
    let mut schemes: Vec<String> = rows.iter().map(scheme_of).collect();
    schemes.dedup();
    schemes.sort();
    schemes.dedup();
    let describe = |r: &Row| {
        let key = &r.record.point.key;
        format!(
            "{} in {:.3e} s ({})",
            pct(r.errors[0]),
            r.record.wall_seconds,
            if key.is_empty() { "the scene" } else { key }
        )
    };
    for s in &schemes {
        let mine: Vec<&Row> = rows
            .iter()
            .filter(|r| &scheme_of(r) == s && !r.errors[0].is_nan())
            .collect();
        let mut parts = Vec::new();
        for &l in levels {
            let best = mine
                .iter()
                .filter(|r| r.errors[0] <= l)
                .min_by(|a, b| a.record.wall_seconds.total_cmp(&b.record.wall_seconds));
            parts.push(match best {
                Some(r) => format!("error ≤ {l:.0e}: {}", describe(r)),
                None => format!("error ≤ {l:.0e} not reached"),
            });
        }
        match mine
            .iter()
            .min_by(|a, b| a.errors[0].total_cmp(&b.errors[0]))
        {
            Some(b) => out.push(format!(
                "sweep {s}: {}; best {}",
                parts.join("; "),
                describe(b)
            )),
            None => out.push(format!("sweep {s}: no measured run")),
        }
    }
    out.extend(space_against_time(rows, &against));
    for &l in levels {
        let mut by: Vec<(&Row, f64)> = Vec::new();
        for s in &schemes {
            if let Some(r) = rows
                .iter()
                .filter(|r| &scheme_of(r) == s && r.errors[0] <= l)
                .min_by(|a, b| a.record.wall_seconds.total_cmp(&b.record.wall_seconds))
            {
                by.push((r, r.record.wall_seconds));
            }
        }
        by.sort_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((r, w)) = by.first() {
            let next = by
                .get(1)
                .map(|(q, v)| format!(", {:.1}× faster than {}", v / w, scheme_of(q)))
                .unwrap_or_default();
            out.push(format!(
                "sweep: cheapest to error ≤ {l:.0e}: {} ({:.3e} s{next})",
                scheme_of(r),
                w
            ));
        }
    }
    out
}

/// How far above its own time estimate a run's error must be for the mesh to dominate.
pub const SPACE_DOMINATES: f64 = 2.0;

/// One line per run that chose its steps (`time.accuracy`), where its error can hold a
/// mesh error (against an analytic reference, or a finer mesh of a `refine` axis): the
/// error measured beside the run's own estimate of its time error. The estimate covers
/// the step on the run's mesh only (`run::accuracy::SCOPE`): an error more than
/// [`SPACE_DOMINATES`] times above it is the mesh's, one within it the step's, and
/// between the two both count (the reference's own error is in the difference too).
pub fn space_against_time(rows: &[Row], against: &str) -> Vec<String> {
    let analytic = rows.iter().any(|r| r.record.analytic.is_some());
    let mut levels: Vec<usize> = rows.iter().map(|r| r.record.point.refine).collect();
    levels.sort_unstable();
    levels.dedup();
    if !analytic && levels.len() < 2 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for r in rows
        .iter()
        .filter(|r| (analytic || !r.is_reference) && !r.errors[0].is_nan())
    {
        let (Some(tol), Some(est)) = (r.record.accuracy, r.record.accuracy_estimated) else {
            continue;
        };
        let e = r.errors[0];
        let verdict = if e > SPACE_DOMINATES * est.max(1e-300) {
            "the mesh's error dominates: refine the mesh, a tighter TOL will not help"
        } else if e <= est {
            "the step's error dominates: the mesh is fine enough for this TOL"
        } else {
            "both count"
        };
        out.push(format!(
            "space against time: refine={} TOL {tol:.0e}: error {} against {against}, its own \
             time estimate {}: {verdict}",
            r.record.point.refine,
            pct(e),
            pct(est)
        ));
    }
    out
}

/// A relative error or level as `3.06e-4` (`n/a` when not measured).
pub(super) fn pct(x: f64) -> String {
    if x.is_nan() {
        "n/a".to_string()
    } else {
        format!("{x:.2e}")
    }
}

#[cfg(test)]
mod tests {
    /// A unit impulse sampled ten intervals late differs in time by ten sampling
    /// intervals (of 512 over the span): 10/512 of the span.
    #[test]
    fn the_sampled_impulse_in_time_counts_a_shift_by_its_length() {
        let n = 512;
        let a: Vec<f64> = (0..n).map(|i| if i >= 100 { 1.0 } else { 0.0 }).collect();
        let b: Vec<f64> = (0..n).map(|i| if i >= 110 { 1.0 } else { 0.0 }).collect();
        let d = super::impulse_in_time(&a, &b);
        assert!((d - 10.0 / n as f64).abs() <= 1e-15, "{d}");
        assert_eq!(super::impulse_in_time(&a, &a), 0.0);
    }
}
