//! A sweep's grid: the points of a `[sweep]` table (the product of its axes, or the
//! refinement levels around a reference), and the scene each point runs.

use super::*;

/// Accuracy levels of the verdict when the sweep names none.
pub const DEFAULT_LEVELS: [f64; 3] = [1e-1, 1e-2, 1e-3];

/// One point of the grid.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Point {
    /// Index in the grid's order.
    pub id: usize,
    /// `name=value` per axis, joined by spaces (what identifies the point on resume).
    pub key: String,
    /// Axis name → value (TOML text).
    pub values: BTreeMap<String, String>,
    /// Refinement level (1 without the axis).
    pub refine: usize,
    /// The `--set` overrides of the point.
    pub overrides: Vec<String>,
}

/// The grid's points in order (the last axis varies fastest).
pub fn points(spec: &SweepSpec) -> Vec<Point> {
    let axes = spec.axes_list();
    let total: usize = axes.iter().map(|a| a.2.len()).product();
    (0..total)
        .map(|id| {
            let mut rem = id;
            let mut picks = vec![0; axes.len()];
            for (k, a) in axes.iter().enumerate().rev() {
                picks[k] = rem % a.2.len();
                rem /= a.2.len();
            }
            let mut values = BTreeMap::new();
            let mut key = Vec::new();
            let mut overrides = Vec::new();
            let mut refine = 1;
            for ((name, scene_key, vals), &p) in axes.iter().zip(&picks) {
                let v = &vals[p];
                key.push(format!("{name}={}", v.trim_matches('"')));
                values.insert(name.clone(), v.clone());
                match scene_key {
                    Some(k) => overrides.push(format!("{k}={v}")),
                    None => refine = v.parse().expect("refine levels are integers"),
                }
            }
            Point {
                id,
                key: key.join(" "),
                values,
                refine,
                overrides,
            }
        })
        .collect()
}

/// Where a sweep's scene comes from.
#[derive(Clone, Debug)]
pub enum Source {
    /// A scene file.
    File(PathBuf),
    /// The reference impacting bar (`meshes/bar.toml`, built in).
    Bar,
}

/// The reference bar as a scene (the text of `meshes/bar.toml`).
pub const BAR_SCENE: &str = include_str!("../../../meshes/bar.toml");

impl Source {
    /// The scene of one point: the source with `set` (the user's) then the point's
    /// overrides, its meshes refined.
    pub fn scene(&self, set: &[String], p: &Point) -> Result<Scene, Error> {
        let all: Vec<String> = set.iter().chain(&p.overrides).cloned().collect();
        let mut s = match self {
            Source::File(f) => Scene::from_file_with(f, &all).map_err(|e| e.in_file(f))?,
            Source::Bar => Scene::from_text_with(BAR_SCENE, &all)?,
        };
        if p.refine > 1 {
            refine(&mut s, p.refine).map_err(|e| match self {
                Source::File(f) => e.in_file(f),
                Source::Bar => e,
            })?;
        }
        s.output.plots = false;
        Ok(s)
    }

    /// How the source is named in the table and on resume.
    pub fn name(&self) -> String {
        match self {
            Source::File(f) => f.display().to_string(),
            Source::Bar => "bar (built in)".to_string(),
        }
    }
}

/// Multiplies every generated mesh's cell counts by `level`; a mesh file cannot be
/// refined (list files on an axis instead).
pub fn refine(s: &mut Scene, level: usize) -> Result<(), Error> {
    if s.bodies.is_empty() {
        // issue 34: the levels ran the same point twice
        return Err(Error::invalid(
            "sweep.refine",
            level,
            "the scene has no mesh to refine (an [example] scene): give no refine axis",
        ));
    }
    for (i, b) in s.bodies.iter_mut().enumerate() {
        let grow = |n: usize| {
            n.checked_mul(level)
                .ok_or_else(|| Error::invalid(&format!("bodies[{i}].mesh"), n, "overflows"))
        };
        match &mut b.mesh {
            MeshSpec::Rod { elements, .. } => *elements = grow(*elements)?,
            MeshSpec::Box { cells, .. } => {
                for c in cells.iter_mut() {
                    *c = grow(*c)?;
                }
            }
            MeshSpec::Rectangle { cells, .. } => {
                for c in cells.iter_mut() {
                    *c = grow(*c)?;
                }
            }
            MeshSpec::Arrays { .. } => {
                return Err(Error::invalid(
                    &format!("bodies[{i}].mesh"),
                    "arrays",
                    "is a mesh given as arrays, which `refine` cannot refine: give a \
                     generator or list meshes on an axis",
                ));
            }
            MeshSpec::File { path } => {
                return Err(Error::invalid(
                    &format!("bodies[{i}].mesh"),
                    path.display(),
                    "is a mesh file, which `refine` cannot refine: list the files on an \
                     axis instead (--axis 'bodies[N].mesh.path=[\"a.msh\", \"b.msh\"]')",
                ));
            }
        }
    }
    s.validate()
}
