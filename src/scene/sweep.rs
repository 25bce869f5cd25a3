//! The `[sweep]` table of a scene ([`SweepSpec`]): the axes of a speed–accuracy grid
//! and how to run it, as scene data (read with the scene, validated with it). The sweep
//! itself, which runs the points and writes the table, is `study::sweep`; this module
//! needs nothing from it, so the scene layer does not import the studies above it.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::Error;

/// Largest grid a sweep expands (points).
pub const MAX_POINTS: usize = 100_000;

/// The `[sweep]` table of a scene, or the same from `signorini sweep`'s flags: the
/// axes of the grid (an empty axis keeps the scene's value) and how to run it.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Schemes (`scheme.kind` values).
    #[serde(default)]
    pub scheme: Vec<String>,
    /// Time steps (s).
    #[serde(default)]
    pub dt: Vec<f64>,
    /// Mesh refinement levels: every generated mesh's cell counts times the level.
    #[serde(default)]
    pub refine: Vec<usize>,
    /// θ values.
    #[serde(default)]
    pub theta: Vec<f64>,
    /// Projection metrics (`mass`, `euclidean`).
    #[serde(default)]
    pub metric: Vec<String>,
    /// Friction solvers (`scheme.friction.solver` values).
    #[serde(default)]
    pub friction_solver: Vec<String>,
    /// Friction tolerances.
    #[serde(default)]
    pub friction_tol: Vec<f64>,
    /// Any other scene key (dotted path with indices, as `--set`) and its values.
    #[serde(default)]
    pub axes: BTreeMap<String, Vec<toml::Value>>,
    /// Runs per point; the wall time is their median (default 1).
    #[serde(default)]
    pub repeat: Option<usize>,
    /// Accuracy levels of the verdict (relative errors; default 10 %, 1 %, 0.1 %).
    #[serde(default)]
    pub levels: Vec<f64>,
}

impl SweepSpec {
    /// `self`'s axes where it has values, `base`'s elsewhere (flags over the table).
    pub fn over(self, base: &SweepSpec) -> SweepSpec {
        fn pick<T: Clone>(a: Vec<T>, b: &[T]) -> Vec<T> {
            if a.is_empty() { b.to_vec() } else { a }
        }
        let mut axes = base.axes.clone();
        axes.extend(self.axes);
        SweepSpec {
            scheme: pick(self.scheme, &base.scheme),
            dt: pick(self.dt, &base.dt),
            refine: pick(self.refine, &base.refine),
            theta: pick(self.theta, &base.theta),
            metric: pick(self.metric, &base.metric),
            friction_solver: pick(self.friction_solver, &base.friction_solver),
            friction_tol: pick(self.friction_tol, &base.friction_tol),
            axes,
            repeat: self.repeat.or(base.repeat),
            levels: pick(self.levels, &base.levels),
        }
    }

    /// The named axes in grid order (outermost first): (column name, scene key, values
    /// as TOML text).
    pub(crate) fn axes_list(&self) -> Vec<(String, Option<String>, Vec<String>)> {
        let quote = |v: &[String]| v.iter().map(|s| format!("{s:?}")).collect::<Vec<_>>();
        let num = |v: &[f64]| v.iter().map(|x| format!("{x:e}")).collect::<Vec<_>>();
        let mut a = vec![
            (
                "refine".to_string(),
                None,
                self.refine.iter().map(|r| r.to_string()).collect(),
            ),
            ("dt".to_string(), Some("time.dt".to_string()), num(&self.dt)),
            (
                "scheme".to_string(),
                Some("scheme.kind".to_string()),
                quote(&self.scheme),
            ),
            (
                "theta".to_string(),
                Some("scheme.theta".to_string()),
                num(&self.theta),
            ),
            (
                "metric".to_string(),
                Some("scheme.metric".to_string()),
                quote(&self.metric),
            ),
            (
                "friction_solver".to_string(),
                Some("scheme.friction.solver".to_string()),
                quote(&self.friction_solver),
            ),
            (
                "friction_tol".to_string(),
                Some("scheme.friction.tol".to_string()),
                num(&self.friction_tol),
            ),
        ];
        for (k, v) in &self.axes {
            a.push((
                k.clone(),
                Some(k.clone()),
                v.iter().map(|x| x.to_string()).collect(),
            ));
        }
        a.retain(|(_, _, v)| !v.is_empty());
        a
    }

    /// Checks counts and values that do not need a scene.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |what: &str, v: &[f64]| -> Result<(), Error> {
            for (i, &x) in v.iter().enumerate() {
                if !(x.is_finite() && x > 0.0) {
                    return Err(Error::invalid(
                        &format!("sweep.{what}[{i}]"),
                        x,
                        "must be finite and positive",
                    ));
                }
            }
            Ok(())
        };
        positive("dt", &self.dt)?;
        positive("friction_tol", &self.friction_tol)?;
        positive("levels", &self.levels)?;
        for (i, &r) in self.refine.iter().enumerate() {
            if r == 0 || r > 64 {
                return Err(Error::invalid(
                    &format!("sweep.refine[{i}]"),
                    r,
                    "must be in [1, 64]",
                ));
            }
        }
        if let Some(r) = self.repeat
            && !(1..=100).contains(&r)
        {
            return Err(Error::invalid("sweep.repeat", r, "must be in [1, 100]"));
        }
        // one axis per scene key: a flag (`--dt`) and an axis (`time.dt`) on the same
        // key labelled runs by the one that did not apply (issue 34)
        let mut seen: BTreeMap<String, String> = BTreeMap::new();
        for (name, key, _) in self.axes_list() {
            let Some(key) = key else { continue };
            let k = scene_key(&key);
            if let Some(first) = seen.insert(k.clone(), name.clone()) {
                return Err(Error::invalid(
                    &format!("sweep.{name}"),
                    &k,
                    &format!(
                        "is the scene key of the axis `{first}` too: give its values on \
                         one axis"
                    ),
                ));
            }
        }
        let mut n: usize = 1;
        for (name, _, v) in self.axes_list() {
            n = n
                .checked_mul(v.len())
                .filter(|&n| n <= MAX_POINTS)
                .ok_or_else(|| {
                    Error::invalid(
                        &format!("sweep.{name}"),
                        v.len(),
                        &format!("makes the grid larger than {MAX_POINTS} points"),
                    )
                })?;
        }
        Ok(())
    }
}

/// A scene key as written on an axis or in `--set`, without its blanks
/// (`bodies[0] .x` and `bodies[0].x` are one key).
pub(crate) fn scene_key(key: &str) -> String {
    key.chars().filter(|c| !c.is_whitespace()).collect()
}
