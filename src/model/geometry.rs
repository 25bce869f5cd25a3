//! The geometry of a model as the writers and the orderings see it: points, cells with
//! their kind and body, materials, the map from nodal components to integrated dofs, and
//! obstacle outlines. It lives in `model` (not `io`) so that `model::ordering` can use it
//! without `model` depending on `io`.

use crate::model::solid::{CellKind, Formulation, Material};

/// One cell of the output geometry.
#[derive(Clone, Debug, PartialEq)]
pub enum GeomCell {
    /// A two-node rod element (uniaxial stress along x).
    Line,
    /// A solid or plane element.
    Solid(CellKind),
}

/// What the writers need to draw the model: points, cells, the material of each cell
/// and where each nodal displacement component lives in the integrator's dof vector.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Reference coordinates (m).
    pub points: Vec<[f64; 3]>,
    /// The input's id of each point (the mesh file's node tag or point index; the index
    /// within its body for generated meshes), written as the `node_id` point array.
    /// Empty: the point indices.
    pub node_ids: Vec<u64>,
    /// Cells: kind, nodes, body index (into `bodies`).
    pub cells: Vec<(GeomCell, Vec<usize>, usize)>,
    /// Material and formulation per body.
    pub bodies: Vec<(Material, Formulation)>,
    /// Displacement components per point (1 for rods, 2 or 3 for solids).
    pub dim: usize,
    /// `point · dim + component` → dof of the integrated system (`None` when fixed).
    pub dof_of: Vec<Option<usize>>,
    /// Rigid obstacles drawn as outlines (written once to `obstacles.vtu`).
    pub outlines: Vec<Outline>,
    /// Components moved at a prescribed velocity (eliminated, so not in `dof_of`):
    /// `(point · dim + component, w, index into prescribed_functions)`, in increasing
    /// order of the first; the frames show
    /// `u = w ∫₀ᵗ φ`, `v = w φ(t)` there.
    pub prescribed: Vec<(usize, f64, usize)>,
    /// The time functions `φ` of `prescribed`.
    pub prescribed_functions: Vec<crate::model::TimeFunction>,
    /// Each contact of the contact set, in its order: where it is and what it meets
    /// (empty for the academic examples, whose contacts are not mesh nodes).
    pub contacts: Vec<ContactPoint>,
}

/// One contact of a built model as a user names it: a node of a body against an obstacle
/// or another body's surface.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactPoint {
    /// The node (index into [`Geometry::points`]).
    pub point: usize,
    /// Its body (index into [`Geometry::bodies`]).
    pub body: usize,
    /// What it meets: an obstacle's name, or the target body's name.
    pub target: String,
    /// The scene's `[[contacts]]` entry it comes from (0 for the built-in bars).
    pub entry: usize,
}

impl Geometry {
    /// The diagonal of the points' bounding box (m); 0 without points. The run checks
    /// use it as the depth no penetration can reach in a sound solution.
    pub fn size(&self) -> f64 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.points {
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
        if self.points.is_empty() {
            return 0.0;
        }
        (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt()
    }
}

/// A displacement probe of a built model (a scene's `[[probes]]` entry, resolved): the
/// mean displacement of `points` at `times`, read by the run's probe observer through
/// [`Geometry::dof_of`] and [`Geometry::prescribed`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Probe {
    /// Name.
    pub name: String,
    /// Body name.
    pub body: String,
    /// The node set's name.
    pub nodes: String,
    /// The set's points (indices into [`Geometry::points`]).
    pub points: Vec<usize>,
    /// Increasing times (s).
    pub times: Vec<f64>,
    /// For a rod: each point's distance from the body's end of smallest `x` (m), where
    /// the impacting bar's closed form is measured from.
    pub rod_abscissa: Option<Vec<f64>>,
}

/// A rigid part drawn as line segments.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outline {
    /// Name (the scene's obstacle name).
    pub name: String,
    /// Points (m).
    pub points: Vec<[f64; 3]>,
    /// Segments between points.
    pub segments: Vec<[usize; 2]>,
}

impl Outline {
    /// A polygon of `n` segments: the circle of `radius` about `centre` in the plane
    /// spanned by the unit vectors `a` and `b`.
    pub fn circle(&mut self, centre: [f64; 3], a: [f64; 3], b: [f64; 3], radius: f64, n: usize) {
        let base = self.points.len();
        for k in 0..n {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            let (c, s) = (t.cos(), t.sin());
            self.points.push(std::array::from_fn(|i| {
                centre[i] + radius * (c * a[i] + s * b[i])
            }));
            self.segments.push([base + k, base + (k + 1) % n]);
        }
    }
    /// The segment from `p` to `q`.
    pub fn segment(&mut self, p: [f64; 3], q: [f64; 3]) {
        let base = self.points.len();
        self.points.extend([p, q]);
        self.segments.push([base, base + 1]);
    }
}
