//! Scene files (TOML): bodies, obstacles, contacts, loads, initial conditions, scheme,
//! time and output, validated with the path of any unknown or bad key.
//!
//! ```toml
//! [time]
//! dt = 1e-6
//! t_end = 1e-3
//!
//! [scheme]                     # every field optional (SchemeParams defaults)
//! kind = "combined-projection"
//!
//! [[bodies]]
//! name = "bar"
//! mesh = { generator = "box", cell = "hex8", cells = [100, 1, 1], size = [1.0, 0.0177, 0.0177] }
//! material = { young = 210e9, poisson = 0.0, density = 7800.0 }
//! velocity = [-0.1, 0.0, 0.0]
//!
//! [[obstacles]]
//! name = "wall"
//! type = "plane"
//! point = [0.0, 0.0, 0.0]
//! normal = [1.0, 0.0, 0.0]
//!
//! [[contacts]]
//! body = "bar"
//! nodes = "x0"                 # a node set of the body's mesh
//! obstacle = "wall"
//! restitution = 0.0
//! friction = 0.0               # Coulomb μ; > 0 adds tangential rows and the friction solver
//!
//! [[forces]]                   # optional: a force on a node set, split over its nodes
//! body = "bar"
//! nodes = "x1"
//! total = [-10.0]              # N, one component per dimension
//! time = [[0.0, 0.0], [1e-3, 1.0]]   # factor on `total`: piecewise linear, constant outside
//! ```
//!
//! Mesh generators: `box` (hex8 or tet4), `rectangle` (quad4 or tri3), `rod` (the
//! 1-D bar of eq. 71; node set `x0` is node 0). Meshes read from files come with the
//! mesh readers.

use crate::integrators::Problem;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::contact::plane::NodesOnPlane;
use crate::contact::sphere::{RoundObstacle, Side};
use crate::contact::{Composite, ContactSet};
use crate::error::{Error, require_positive};
use crate::integrators::SchemeParams;
use crate::io::frames::{GeomCell, Geometry, Outline, orthonormal};
use crate::model::generate::{box_mesh, rectangle_mesh};
use crate::model::geometry::Probe;
use crate::model::hyperelastic::{HyperBody, Hyperelastic};
use crate::model::rod::Rod;
use crate::model::solid::{
    CellKind, Formulation, Material, MaterialModel, Mesh, assemble_with_contacts,
};
use crate::model::system::HyperelasticPart;
use crate::model::{LinearSystem, MassKind};
use crate::scene::Model;

/// A whole scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Time stepping.
    pub time: TimeSpec,
    /// Scheme and its parameters.
    #[serde(default)]
    pub scheme: SchemeParams,
    /// Deformable bodies.
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// One of the paper's academic examples instead of bodies (see
    /// [`crate::scene::example`]).
    #[serde(default)]
    pub example: Option<crate::scene::example::ExampleSpec>,
    /// Rigid obstacles.
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Node-set-versus-obstacle contacts.
    #[serde(default)]
    pub contacts: Vec<ContactSpec>,
    /// Body forces.
    #[serde(default)]
    pub loads: Loads,
    /// Forces on node sets with a time function.
    #[serde(default)]
    pub forces: Vec<ForceSpec>,
    /// Prescribed velocities of node sets with a time function.
    #[serde(default)]
    pub prescribed: Vec<PrescribedSpec>,
    /// Displacement probes: the displacement of node sets at named times, reported in
    /// `summary.json` and compared by `signorini sweep`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<ProbeSpec>,
    /// Output options.
    #[serde(default)]
    pub output: crate::io::OutputOptions,
    /// Directory that relative mesh paths start from (the scene file's directory).
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// The scene file, when read from one (checkpoints name it).
    #[serde(skip)]
    pub file: Option<PathBuf>,
    /// Analytic reference to compare with (the impacting bar).
    #[serde(default)]
    pub reference: Option<Reference>,
    /// The grid `signorini sweep` runs this scene over (ignored by `run`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<crate::scene::sweep::SweepSpec>,
}

/// `[reference]`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// The impacting bar of sec. 6.2: contact force summed over all contacts.
    pub impacting_bar: crate::analytic::ImpactingBar,
}

/// `[time]`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Time step (s).
    pub dt: f64,
    /// End time (s).
    pub t_end: f64,
}

/// `[[bodies]]`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name used by contacts.
    pub name: String,
    /// Mesh source.
    pub mesh: MeshSpec,
    /// Solid (3-D), plane strain or plane stress; ignored by `rod`.
    #[serde(default = "default_formulation")]
    pub formulation: Formulation,
    /// Material.
    pub material: Material,
    /// Mass matrix kind.
    #[serde(default = "default_mass")]
    pub mass: MassKind,
    /// Rayleigh damping `C = αM + βK`.
    #[serde(default)]
    pub damping: Option<Rayleigh>,
    /// Uniform initial velocity (one value per component).
    #[serde(default)]
    pub velocity: Option<Vec<f64>>,
    /// Node sets held fixed (u = 0).
    #[serde(default)]
    pub fixed: Vec<String>,
}

fn default_formulation() -> Formulation {
    Formulation::Solid
}
fn default_mass() -> MassKind {
    MassKind::Consistent
}

/// Rayleigh coefficients.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rayleigh {
    /// Mass-proportional coefficient α (1/s).
    pub alpha: f64,
    /// Stiffness-proportional coefficient β (s).
    pub beta: f64,
}

/// Where a body's mesh comes from.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "generator", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MeshSpec {
    /// A box of hex8 or tet4 cells.
    Box {
        /// hex8 or tet4.
        cell: CellKind,
        /// Cells along x, y, z.
        cells: [usize; 3],
        /// Side lengths (m).
        size: [f64; 3],
        /// Lower corner (m).
        #[serde(default)]
        origin: [f64; 3],
    },
    /// A rectangle of quad4 or tri3 cells.
    Rectangle {
        /// quad4 or tri3.
        cell: CellKind,
        /// Cells along x, y.
        cells: [usize; 2],
        /// Side lengths (m).
        size: [f64; 2],
        /// Lower corner (m).
        #[serde(default)]
        origin: [f64; 2],
    },
    /// A mesh file (`.msh` 4.1/2.2, `.vtu`, legacy `.vtk`), relative to the scene file.
    File {
        /// The path.
        path: PathBuf,
    },
    /// The P1 rod of eq. 71 along x from the origin, with cross-section `area`.
    Rod {
        /// Elements.
        elements: usize,
        /// Length (m).
        length: f64,
        /// Cross-section (m²).
        area: f64,
        /// Abscissa of node 0 (m; default 0): where a second rod starts.
        #[serde(default)]
        origin: f64,
    },
}

/// `[[obstacles]]`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub enum ObstacleSpec {
    /// The half-space `n·(x − p) ≥ 0`.
    Plane {
        /// Name used by contacts.
        name: String,
        /// A point of the plane.
        point: Vec<f64>,
        /// Normal towards the admissible side.
        normal: Vec<f64>,
    },
    /// A sphere (circle in 2-D).
    Sphere {
        /// Name used by contacts.
        name: String,
        /// Centre.
        center: Vec<f64>,
        /// Radius (m).
        radius: f64,
        /// `outside` (an obstacle, default) or `inside` (a container).
        #[serde(default = "outside")]
        side: Side,
    },
    /// An infinite cylinder (3-D).
    Cylinder {
        /// Name used by contacts.
        name: String,
        /// A point of the axis.
        point: Vec<f64>,
        /// Axis direction.
        axis: Vec<f64>,
        /// Radius (m).
        radius: f64,
        /// `outside` (default) or `inside`.
        #[serde(default = "outside")]
        side: Side,
    },
}

fn outside() -> Side {
    Side::Outside
}

impl ObstacleSpec {
    /// Checks the geometry in a scene of dimension `dim`, whether or not a contact uses
    /// the obstacle: finite points, non-zero normals and axes, positive radii.
    fn validate(&self, dim: usize) -> Result<(), Error> {
        let vector = |key: &str, v: &[f64], n: usize, nonzero: bool| -> Result<(), Error> {
            if v.len() != n || v.iter().any(|x| !x.is_finite()) {
                return Err(Error::invalid(
                    key,
                    format!("{v:?}"),
                    &format!("needs {n} finite components"),
                ));
            }
            if nonzero && v.iter().map(|x| x * x).sum::<f64>().sqrt() < 1e-300 {
                return Err(Error::invalid(
                    key,
                    format!("{v:?}"),
                    "must not be the zero vector (it gives the direction)",
                ));
            }
            Ok(())
        };
        match self {
            ObstacleSpec::Plane { point, normal, .. } => {
                vector("point", point, dim, false)?;
                vector("normal", normal, dim, true)
            }
            ObstacleSpec::Sphere { center, radius, .. } => {
                vector("center", center, dim, false)?;
                require_positive("radius", *radius).map(|_| ())
            }
            ObstacleSpec::Cylinder {
                point,
                axis,
                radius,
                ..
            } => {
                if dim != 3 {
                    return Err(Error::invalid(
                        "type",
                        "cylinder",
                        &format!(
                            "is a 3-D obstacle; this scene is {dim}-D (use a sphere: a circle in 2-D)"
                        ),
                    ));
                }
                vector("point", point, 3, false)?;
                vector("axis", axis, 3, true)?;
                require_positive("radius", *radius).map(|_| ())
            }
        }
    }

    fn name(&self) -> &str {
        match self {
            ObstacleSpec::Plane { name, .. }
            | ObstacleSpec::Sphere { name, .. }
            | ObstacleSpec::Cylinder { name, .. } => name,
        }
    }
}

/// `[[contacts]]`: candidate nodes of a body against an obstacle or against the surface
/// of another body (exactly one of `obstacle` and `target`).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Body name (the slave side of a contact between bodies).
    pub body: String,
    /// Obstacle name.
    #[serde(default)]
    pub obstacle: Option<String>,
    /// Another body's surface ([`crate::contact::bodies`]).
    #[serde(default)]
    pub target: Option<TargetSpec>,
    /// A node set of the body's mesh; `"boundary"` (computed from the cells when the
    /// mesh has no set of that name); or `"all"`. Combine with `within`.
    pub nodes: String,
    /// Keep only the nodes whose initial gap to the obstacle (or distance to the target
    /// surface) is at most this (m).
    #[serde(default)]
    pub within: Option<f64>,
    /// The deepest a node may start inside the obstacle or the target body (m; default
    /// 1e-9 of the contact body's size, the round-off of coincident meshes). A scene
    /// whose nodes start deeper is refused (issue 34): the scheme would push them out in
    /// one step, or, past the search distance of a contact between bodies, never see
    /// them. Raise it for curved non-matching meshes whose chords cut into each other.
    #[serde(default)]
    pub overlap_tolerance: Option<f64>,
    /// Newton restitution coefficient.
    #[serde(default)]
    pub restitution: f64,
    /// Coulomb friction coefficient μ (default 0: frictionless, no friction solver).
    #[serde(default)]
    pub friction: f64,
}

/// Refuses contact `c` when one of its nodes starts inside `against` deeper than its
/// `overlap_tolerance` ([`ContactSpec::overlap_tolerance`]), naming the deepest node by
/// its file tag, its depth and how many start inside.
fn check_starting_gaps(
    set: &dyn ContactSet,
    ndof: usize,
    c: &ContactSpec,
    mesh: &Mesh,
    nodes: &[usize],
    against: &str,
) -> Result<(), Error> {
    let size = mesh_size(mesh);
    let tol = match c.overlap_tolerance {
        Some(t) => crate::error::require_in("overlap_tolerance", t, 0.0, f64::MAX)?,
        None => 1e-9 * size,
    };
    let mut gap = vec![0.0; set.len()];
    set.starting_gaps(&vec![0.0; ndof], &mut gap);
    let inside = gap.iter().filter(|&&g| g < -tol).count();
    let Some((k, &g)) = gap
        .iter()
        .enumerate()
        .filter(|(_, g)| **g < -tol)
        .min_by(|a, b| a.1.total_cmp(b.1))
    else {
        return Ok(());
    };
    let node = nodes
        .get(k)
        .map_or_else(|| format!("contact {k}"), |&v| mesh.node_label(v));
    Err(Error::invalid(
        "nodes",
        &c.nodes,
        &format!(
            "{node} of body \"{}\" starts {:.3e} m inside {against} ({inside} node(s) start \
             inside; the deepest is named), expected at most overlap_tolerance = {tol:.3e} m: \
             move the bodies apart, or raise overlap_tolerance where curved non-matching \
             meshes cut into each other",
            c.body, -g
        ),
    ))
}

/// The diagonal of a mesh's bounding box (m).
fn mesh_size(mesh: &Mesh) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &mesh.points {
        for j in 0..3 {
            lo[j] = lo[j].min(p[j]);
            hi[j] = hi[j].max(p[j]);
        }
    }
    (0..3)
        .map(|j| (hi[j] - lo[j]).max(0.0).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// `target = { body, surface, … }` of a contact between bodies.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetSpec {
    /// The master body.
    pub body: String,
    /// A node set of the master body's mesh (or `boundary`): its boundary facets whose
    /// nodes all lie in the set form the master surface.
    pub surface: String,
    /// `node-to-surface` (default) or `node-to-node`.
    #[serde(default)]
    pub pairing: Pairing,
    /// Search distance (m): facets farther than this from a node are not looked at,
    /// and the candidate lists are rebuilt when a node has moved half of it (default:
    /// half the smallest edge of the master facets; node-to-node: the largest
    /// normal distance accepted between paired nodes).
    #[serde(default)]
    pub search: Option<f64>,
    /// Candidate facets kept per node (default [`crate::contact::bodies::DEFAULT_CAPACITY`]).
    #[serde(default)]
    pub capacity: Option<usize>,
}

/// How the nodes of a contact between bodies meet the target.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Pairing {
    /// Each node against the nearest facet of the target surface, found again as the
    /// bodies move (nonlinear in `q`, except a rod's end against a rod's end).
    #[default]
    NodeToSurface,
    /// Each node with the coincident node of the target surface (matching meshes), along
    /// the surface's normal there: constant `G`, factor-once fast path.
    NodeToNode,
}

/// `[[forces]]`: a force on a node set, split evenly over its nodes, scaled by a
/// piecewise-linear function of time.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceSpec {
    /// Body name.
    pub body: String,
    /// A node set of the body's mesh (as for `[[contacts]]`: a set, `boundary` or `all`).
    pub nodes: String,
    /// The total force over the set (N), one component per space dimension.
    pub total: Vec<f64>,
    /// `[[t, factor], …]`: the factor multiplying `total` at time `t`, linear between the
    /// points and constant outside them (default: 1 at all times).
    #[serde(default, deserialize_with = "time_points")]
    pub time: Option<Vec<[f64; 2]>>,
}

/// `[[t, factor], …]` with exactly two numbers a point: serde's fixed-size arrays take
/// the first two of a longer list and drop the rest silently (issue 34).
fn time_points<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Vec<[f64; 2]>>, D::Error> {
    let v: Option<Vec<Vec<f64>>> = Option::deserialize(d)?;
    v.map(|points| {
        points
            .into_iter()
            .enumerate()
            .map(|(i, p)| match p[..] {
                [t, f] => Ok([t, f]),
                _ => Err(serde::de::Error::custom(format!(
                    "time point {i} has {} number(s), expected 2: [t, factor]",
                    p.len()
                ))),
            })
            .collect()
    })
    .transpose()
}

/// `[[prescribed]]`: node-set dofs moved at a prescribed velocity `velocity · φ(t)`
/// (displacement `velocity · ∫₀ᵗ φ`), eliminated from the system (θ-method schemes).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrescribedSpec {
    /// Body name.
    pub body: String,
    /// A node set of the body's mesh (a set, `boundary` or `all`).
    pub nodes: String,
    /// Velocity (m/s), one component per space dimension.
    pub velocity: Vec<f64>,
    /// The components prescribed (0 = x, 1 = y, 2 = z; default all).
    #[serde(default)]
    pub components: Option<Vec<usize>>,
    /// `[[t, factor], …]` multiplying `velocity` (default 1 at all times).
    #[serde(default, deserialize_with = "time_points")]
    pub time: Option<Vec<[f64; 2]>>,
}

/// `[[probes]]`: the mean displacement of a node set of one body at named times.
///
/// The θ-method's displacement is linear within a step (`q_{k+1} = q_k + h(θ v_{k+1} +
/// (1−θ) v_k)`, eq. 18), so a time between two steps is read by linear interpolation
/// between them; a time at a step is read exactly.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSpec {
    /// The probe's name (unique; the summary's and the sweep's label).
    pub name: String,
    /// Body name.
    pub body: String,
    /// A node set of the body's mesh (a set, `boundary` or `all`): the probe reads the
    /// mean displacement of its nodes (one node: that node's displacement).
    pub nodes: String,
    /// The times (s), increasing, within `[0, time.t_end]`.
    pub times: Vec<f64>,
}

/// Most times one probe may name (each costs one displacement vector in the summary
/// and in a checkpoint).
pub const MAX_PROBE_TIMES: usize = 100_000;

/// `[loads]`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Uniform acceleration field (m/s²), e.g. `[0, 0, -9.81]`.
    #[serde(default)]
    pub gravity: Option<Vec<f64>>,
}

/// What [`Scene::build`] reports about the model, for `signorini check`.
#[derive(Clone, Debug, Serialize)]
pub struct ModelReport {
    /// Degrees of freedom after Dirichlet elimination.
    pub dofs: usize,
    /// Cells over all bodies.
    pub cells: usize,
    /// Candidate contacts.
    pub contacts: usize,
    /// Whether every gap is linear in q (G constant).
    pub linear_contacts: bool,
    /// Largest friction coefficient over the contacts (0: frictionless).
    pub max_friction: f64,
    /// Whether Rayleigh damping is present.
    pub damping: bool,
    /// Whether a body force is applied.
    pub gravity: bool,
    /// Dofs removed by `fixed` node sets.
    pub fixed_dofs: usize,
    /// Whether the structure is linear (no body with a large-deformation law).
    pub linear_structure: bool,
    /// One line per contact between bodies: the sides, the pairing and the search.
    pub interfaces: Vec<String>,
}

impl Scene {
    /// Reads and validates a scene file; errors name the file and the key path (or the
    /// line and column of a TOML syntax error).
    pub fn from_file(path: &Path) -> Result<Scene, Error> {
        let text = crate::limits::read_text(path, "scene", crate::limits::MAX_SCENE_BYTES)?;
        let mut scene = Self::from_toml(&text).map_err(|e| e.in_file(path))?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        scene.file = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::from_file`] with `KEY=VALUE` overrides applied to the file's TOML before
    /// it is read as a scene (`signorini run --set`): `KEY` is a dotted path with array
    /// indices (`scheme.newton.modified`, `bodies[0].material.model`), tables on the path
    /// are created, and `VALUE` is a TOML value (`true`, `1e-5`, `"svk"`). The scene is
    /// then validated as usual, so a misspelt key is refused with its path.
    pub fn from_file_with(path: &Path, overrides: &[String]) -> Result<Scene, Error> {
        if overrides.is_empty() {
            return Self::from_file(path);
        }
        let text = crate::limits::read_text(path, "scene", crate::limits::MAX_SCENE_BYTES)?;
        let mut scene = Self::from_text_with(&text, overrides).map_err(|e| e.in_file(path))?;
        scene.base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        scene.file = Some(path.to_path_buf());
        Ok(scene)
    }

    /// [`Scene::from_toml`] with the `KEY=VALUE` overrides of [`Scene::from_file_with`]
    /// (relative mesh paths then start from the working directory).
    pub fn from_text_with(text: &str, overrides: &[String]) -> Result<Scene, Error> {
        // syntax errors are located in the text itself
        let mut table: toml::Table = match toml::from_str(text) {
            Ok(t) if !overrides.is_empty() => t,
            _ => return Self::from_toml(text),
        };
        for o in overrides {
            apply_override(&mut table, o)?;
        }
        let text = toml::to_string(&table)
            .map_err(|e| Error::invalid("--set", "(scene)", &format!("does not serialize: {e}")))?;
        Self::from_toml(&text)
    }

    /// This scene with the `KEY=VALUE` overrides of [`Scene::from_file_with`] applied,
    /// keeping its file and base directory (the Python package's keyword arguments).
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Scene, Error> {
        if overrides.is_empty() {
            return Ok(self.clone());
        }
        let text = toml::to_string(self)
            .map_err(|e| Error::invalid("--set", "(scene)", &format!("does not serialize: {e}")))?;
        let mut scene = Self::from_text_with(&text, overrides)?;
        scene.base_dir = self.base_dir.clone();
        scene.file = self.file.clone();
        Ok(scene)
    }

    /// Parses and validates scene text.
    pub fn from_toml(text: &str) -> Result<Scene, Error> {
        let at = |span: Option<std::ops::Range<usize>>| match span {
            Some(r) => {
                let before = &text[..r.start.min(text.len())];
                let line = 1 + before.matches('\n').count();
                let col = 1 + before.len() - before.rfind('\n').map_or(0, |i| i + 1);
                format!("line {line}, column {col}")
            }
            None => "scene".to_string(),
        };
        let de = toml::Deserializer::parse(text)
            .map_err(|e| Error::invalid(&at(e.span()), "(TOML syntax)", first_line(e.message())))?;
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let field = if path == "." || path.is_empty() {
                at(inner.span())
            } else {
                path
            };
            Error::invalid(&field, "(key)", first_line(inner.message()))
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Range checks that serde cannot express.
    pub fn validate(&self) -> Result<(), Error> {
        crate::limits::step_count(self.time.t_end, self.time.dt, "time.t_end", "time.dt")?;
        self.scheme.validate().map_err(|e| prefix("scheme", e))?;
        self.output.validate().map_err(|e| prefix("output", e))?;
        if self.example.is_some() {
            // the examples carry their own loads (the paper's f = −2, the oscillator's
            // forcing); tables that would be silently ignored are refused, by name
            let extra = [
                (!self.bodies.is_empty(), "bodies"),
                (!self.obstacles.is_empty(), "obstacles"),
                (!self.contacts.is_empty(), "contacts"),
                (!self.forces.is_empty(), "forces"),
                (!self.prescribed.is_empty(), "prescribed"),
                (!self.probes.is_empty(), "probes"),
                (self.loads.gravity.is_some(), "loads"),
                (self.reference.is_some(), "reference"),
            ];
            if let Some((_, key)) = extra.iter().find(|(present, _)| *present) {
                return Err(Error::invalid(
                    key,
                    "in an [example] scene",
                    "an example scene holds only [example], [time], [scheme] and [output]: \
                     its loads are the example's own parameters (`signorini example --help`)",
                ));
            }
            return Ok(());
        }
        if self.bodies.is_empty() {
            return Err(Error::invalid(
                "bodies",
                "[]",
                "a scene needs at least one body (or an [example])",
            ));
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if b.name.trim().is_empty() {
                return Err(Error::invalid(
                    &format!("bodies[{i}].name"),
                    "\"\"",
                    "a body needs a name",
                ));
            }
            if let Some(j) = self.bodies[..i].iter().position(|o| o.name == b.name) {
                return Err(Error::invalid(
                    &format!("bodies[{i}].name"),
                    &b.name,
                    &format!("bodies[{j}] has that name already; names must be unique"),
                ));
            }
            b.material
                .validate()
                .map_err(|e| prefix(&format!("bodies[{i}].material"), e))?;
            let rod = matches!(b.mesh, MeshSpec::Rod { .. });
            if b.material.model != MaterialModel::Linear
                && (rod
                    || matches!(
                        b.formulation,
                        Formulation::PlaneStress { .. } | Formulation::Axisymmetric
                    ))
            {
                return Err(Error::invalid(
                    &format!("bodies[{i}].material.model"),
                    b.material.model.name(),
                    "large-deformation laws take solid bodies (tet4, hex8) and plane-strain \
                     bodies (tri3, quad4); rods, plane-stress and axisymmetric bodies are \
                     linear only (model = \"linear\")",
                ));
            }
            if let Some(r) = b.damping {
                crate::error::require_in(
                    &format!("bodies[{i}].damping.alpha"),
                    r.alpha,
                    0.0,
                    f64::MAX,
                )?;
                crate::error::require_in(
                    &format!("bodies[{i}].damping.beta"),
                    r.beta,
                    0.0,
                    f64::MAX,
                )?;
            }
        }
        let dim = self.bodies[0].dim();
        for (j, o) in self.obstacles.iter().enumerate() {
            if let Some(k) = self.obstacles[..j]
                .iter()
                .position(|p| p.name() == o.name())
            {
                return Err(Error::invalid(
                    &format!("obstacles[{j}].name"),
                    o.name(),
                    &format!("obstacles[{k}] has that name already; names must be unique"),
                ));
            }
            // say where the dimension comes from: a 3-D mesh given a 2-D formulation
            // reads as an obstacle's fault otherwise (issue 34)
            let origin = match self.bodies[0].mesh {
                MeshSpec::Rod { .. } => "bodies[0] is a rod".to_string(),
                _ => format!(
                    "bodies[0] has formulation = \"{}\"",
                    self.bodies[0].formulation.name()
                ),
            };
            o.validate(dim).map_err(|e| {
                prefix(
                    &format!("obstacles[{j}]"),
                    e.context(&format!("a {dim}-D scene: {origin}")),
                )
            })?;
        }
        if let Some(g) = &self.loads.gravity
            && (g.len() != dim || g.iter().any(|x| !x.is_finite()))
        {
            return Err(Error::invalid(
                "loads.gravity",
                format!("{g:?}"),
                &format!("needs {dim} finite components (m/s²)"),
            ));
        }
        self.validate_axisymmetric()?;
        for (i, c) in self.contacts.iter().enumerate() {
            if !self.bodies.iter().any(|b| b.name == c.body) {
                return Err(Error::invalid(
                    &format!("contacts[{i}].body"),
                    &c.body,
                    "names no body",
                ));
            }
            match (&c.obstacle, &c.target) {
                (Some(o), None) => {
                    if !self.obstacles.iter().any(|x| x.name() == o) {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].obstacle"),
                            o,
                            "names no obstacle",
                        ));
                    }
                }
                (None, Some(t)) => {
                    if !self.bodies.iter().any(|b| b.name == t.body) {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.body"),
                            &t.body,
                            "names no body",
                        ));
                    }
                    if t.body == c.body {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.body"),
                            &t.body,
                            "is the contact's own body: self-contact is not modelled",
                        ));
                    }
                    if let Some(sd) = t.search {
                        require_positive(&format!("contacts[{i}].target.search"), sd)?;
                    }
                    if let Some(k) = t.capacity
                        && !(1..=4096).contains(&k)
                    {
                        return Err(Error::invalid(
                            &format!("contacts[{i}].target.capacity"),
                            k,
                            "must lie in 1..=4096",
                        ));
                    }
                }
                (Some(_), Some(_)) => {
                    return Err(Error::invalid(
                        &format!("contacts[{i}]"),
                        "obstacle and target",
                        "give one: `obstacle` (a rigid obstacle) or `target` (another body)",
                    ));
                }
                (None, None) => {
                    return Err(Error::invalid(
                        &format!("contacts[{i}]"),
                        "neither obstacle nor target",
                        "give `obstacle = \"name\"` or `target = { body = \"name\", surface = \"set\" }`",
                    ));
                }
            }
            crate::contact::check_restitution(
                &format!("contacts[{i}].restitution"),
                c.restitution,
            )?;
            crate::contact::check_friction(&format!("contacts[{i}].friction"), c.friction)?;
        }
        for (i, p) in self.prescribed.iter().enumerate() {
            let at = format!("prescribed[{i}]");
            let b = self.driven_body(&at, &p.body, ("velocity", &p.velocity, "m/s"), &p.time)?;
            if let Some(c) = &p.components
                && (c.is_empty() || c.iter().any(|&k| k >= b.dim()))
            {
                return Err(Error::invalid(
                    &format!("prescribed[{i}].components"),
                    format!("{c:?}"),
                    &format!("expected components in 0..{}", b.dim()),
                ));
            }
        }
        for (i, f) in self.forces.iter().enumerate() {
            let at = format!("forces[{i}]");
            self.driven_body(&at, &f.body, ("total", &f.total, "N"), &f.time)?;
        }
        self.validate_probes()
    }

    /// Checks the `[[probes]]`: unique non-empty names, existing bodies, increasing
    /// finite times within `[0, time.t_end]`, at most [`MAX_PROBE_TIMES`] each.
    fn validate_probes(&self) -> Result<(), Error> {
        for (i, p) in self.probes.iter().enumerate() {
            let key = |k: &str| format!("probes[{i}].{k}");
            if p.name.trim().is_empty() {
                return Err(Error::invalid(&key("name"), "\"\"", "a probe needs a name"));
            }
            if let Some(j) = self.probes[..i].iter().position(|o| o.name == p.name) {
                return Err(Error::invalid(
                    &key("name"),
                    &p.name,
                    &format!("probes[{j}] has that name already; names must be unique"),
                ));
            }
            if !self.bodies.iter().any(|b| b.name == p.body) {
                return Err(Error::invalid(&key("body"), &p.body, "names no body"));
            }
            if p.times.is_empty() || p.times.len() > MAX_PROBE_TIMES {
                return Err(Error::invalid(
                    &key("times"),
                    format!("{} times", p.times.len()),
                    &format!("expected 1 to {MAX_PROBE_TIMES} times"),
                ));
            }
            for (k, &t) in p.times.iter().enumerate() {
                if !(0.0..=self.time.t_end).contains(&t) {
                    return Err(Error::invalid(
                        &format!("probes[{i}].times[{k}]"),
                        t,
                        &format!("expected a time in [0, time.t_end = {}] s", self.time.t_end),
                    ));
                }
                if k > 0 && t <= p.times[k - 1] {
                    return Err(Error::invalid(
                        &format!("probes[{i}].times[{k}]"),
                        t,
                        &format!(
                            "times must increase (times[{}] = {})",
                            k - 1,
                            p.times[k - 1]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Checks a `[[forces]]` or `[[prescribed]]` entry at `at`: its body exists, its
    /// vector has one finite component per dimension, its time function is valid.
    fn driven_body(
        &self,
        at: &str,
        body: &str,
        (key, v, unit): (&str, &[f64], &str),
        time: &Option<Vec<[f64; 2]>>,
    ) -> Result<&BodySpec, Error> {
        let Some(b) = self.bodies.iter().find(|b| b.name == body) else {
            return Err(Error::invalid(&format!("{at}.body"), body, "names no body"));
        };
        if v.len() != b.dim() || v.iter().any(|x| !x.is_finite()) {
            return Err(Error::invalid(
                &format!("{at}.{key}"),
                format!("{v:?}"),
                &format!("needs {} finite components ({unit})", b.dim()),
            ));
        }
        time_function(&format!("{at}.time"), time)?;
        Ok(b)
    }

    /// Number of steps.
    pub fn steps(&self) -> usize {
        crate::limits::step_count(self.time.t_end, self.time.dt, "time.t_end", "time.dt")
            .unwrap_or(0)
    }

    /// The mesh files the scene reads, as written (relative to [`Scene::base_dir`]
    /// unless absolute), once each.
    pub fn mesh_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = Vec::new();
        for b in &self.bodies {
            if let MeshSpec::File { path } = &b.mesh
                && !files.contains(path)
            {
                files.push(path.clone());
            }
        }
        files
    }

    /// Meshes and assembles every body, eliminates fixed dofs, and builds the contacts.
    pub fn build(&self) -> Result<(Model, ModelReport), Error> {
        if let Some(x) = &self.example {
            let model = x.build()?;
            let report = ModelReport {
                dofs: model.problem.system.ndof(),
                cells: 0,
                contacts: model.problem.contacts.len(),
                linear_contacts: model.problem.contacts.is_linear(),
                max_friction: model
                    .problem
                    .contacts
                    .laws()
                    .iter()
                    .map(|l| l.friction)
                    .fold(0.0, f64::max),
                damping: model.problem.system.damping.is_some(),
                gravity: model.problem.system.force.iter().any(|&f| f != 0.0)
                    || matches!(x, super::example::ExampleSpec::SliderCrank { mechanism, .. }
                        if mechanism.gravity > 0.0),
                fixed_dofs: 0,
                linear_structure: model.problem.system.nonlinear.is_empty(),
                interfaces: Vec::new(),
            };
            return Ok((model, report));
        }
        self.validate()?;
        let mut systems = Vec::new();
        let mut v0 = Vec::new();
        let mut fixed = Vec::new();
        let mut cells = 0;
        let dim = self.bodies[0].dim();
        let mut geometry = Geometry {
            dim,
            ..Geometry::default()
        };
        // each contact's nodes, found once with its body's mesh: they take no mass under
        // the redistributed mass, then become the contact set below
        let mut nodes_of: Vec<Vec<usize>> = vec![Vec::new(); self.contacts.len()];
        // every mesh first: a contact between bodies needs both sides' meshes
        let mut all_meshes = Vec::with_capacity(self.bodies.len());
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            if b.dim() != dim {
                return Err(at(Error::invalid(
                    "formulation",
                    b.dim(),
                    "all bodies need one dimension",
                )));
            }
            let mesh = b.mesh(&self.base_dir).map_err(at)?;
            // the mesh against the formulation before anything reads its cells as such
            if !matches!(b.mesh, MeshSpec::Rod { .. }) {
                crate::model::solid::check_mesh(&mesh, b.formulation).map_err(at)?;
            }
            all_meshes.push(mesh);
        }
        // the probes' node sets, before any assembly: a misspelt set is refused at once
        let point_base = starts(all_meshes.iter().map(|m| m.points.len()));
        let probes = self.probes(&all_meshes, &point_base)?;
        // the master surface of each contact between bodies (facets over its body's
        // node numbers, outward)
        let mut facets_of: Vec<Vec<Vec<usize>>> = vec![Vec::new(); self.contacts.len()];
        let mut axis_facets = vec![0; self.contacts.len()];
        for (ci, c) in self.contacts.iter().enumerate() {
            if let Some(t) = &c.target {
                let ti = self.body_index(&t.body);
                (facets_of[ci], axis_facets[ci]) =
                    target_facets(&all_meshes[ti], &self.bodies[ti], t)
                        .map_err(|e| prefix(&format!("contacts[{ci}].target"), e))?;
            }
        }
        for (bi, b) in self.bodies.iter().enumerate() {
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            let mesh = &all_meshes[bi];
            cells += mesh.cells.len().max(match b.mesh {
                MeshSpec::Rod { elements, .. } => elements,
                _ => 0,
            });
            // contact nodes of this body (for the redistributed mass): the same nodes
            // as the contacts below, `boundary`, `all` and `within` included
            let mut contact_nodes = Vec::new();
            // (obstacle, node) → the contact that first listed it
            let mut first_of = std::collections::HashMap::new();
            for (ci, c) in self
                .contacts
                .iter()
                .enumerate()
                .filter(|(_, c)| c.body == b.name)
            {
                nodes_of[ci] = self
                    .contact_nodes(mesh, c, dim, &facets_of[ci], &all_meshes)
                    .map_err(|e| prefix(&format!("contacts[{ci}]"), e))?;
                let other = match (&c.obstacle, &c.target) {
                    (Some(o), _) => format!("obstacle \"{o}\""),
                    (_, Some(t)) => format!("body \"{}\"", t.body),
                    _ => unreachable!("validated"),
                };
                for &v in &nodes_of[ci] {
                    // the same constraint twice makes two equal rows of G: a singular
                    // contact problem that the solvers report only as a breakdown
                    if let Some(first) = first_of.insert((other.clone(), v), ci) {
                        return Err(prefix(
                            &format!("contacts[{ci}]"),
                            Error::invalid(
                                "nodes",
                                mesh.node_label(v),
                                &format!(
                                    "already meets {other} through contacts[{first}]; \
                                     list each node once per obstacle or body",
                                ),
                            ),
                        ));
                    }
                }
                contact_nodes.extend_from_slice(&nodes_of[ci]);
            }
            // the master surfaces on this body take no mass either (both sides of an
            // interface, as Khenous–Laborde–Renard redistribute it)
            for (ci, c) in self.contacts.iter().enumerate() {
                if c.target.as_ref().is_some_and(|t| t.body == b.name) {
                    contact_nodes.extend(facets_of[ci].iter().flatten().copied());
                }
            }
            contact_nodes.sort_unstable();
            contact_nodes.dedup();
            let mut sys = match &b.mesh {
                MeshSpec::Rod {
                    elements,
                    length,
                    area,
                    ..
                } => Rod {
                    length: *length,
                    area: *area,
                    young: b.material.young,
                    density: b.material.density,
                    elements: *elements,
                    mass: b.mass,
                }
                .assemble()
                .map_err(at)?,
                _ => {
                    assemble_with_contacts(mesh, &b.material, b.formulation, b.mass, &contact_nodes)
                        .map_err(at)?
                }
            };
            if let Some(r) = b.damping {
                sys = sys.with_rayleigh(r.alpha, r.beta).map_err(at)?;
            }
            if let Some(g) = &self.loads.gravity {
                sys.add_gravity(g).map_err(|e| prefix("loads", e))?;
            }
            let n = sys.ndof();
            let vel = b.velocity.clone().unwrap_or_else(|| vec![0.0; dim]);
            if vel.len() != dim || vel.iter().any(|x| !x.is_finite()) {
                return Err(at(Error::invalid(
                    "velocity",
                    format!("{vel:?}"),
                    &format!("needs {dim} finite values"),
                )));
            }
            v0.extend((0..n).map(|i| vel[i % dim]));
            let mut fx = vec![false; n];
            for name in &b.fixed {
                let set = node_set(mesh, name).map_err(|e| at(prefix("fixed", e)))?;
                for &v in &set {
                    for i in 0..dim {
                        fx[v * dim + i] = true;
                    }
                }
            }
            fixed.extend(fx);
            let base = geometry.points.len();
            match &b.mesh {
                MeshSpec::Rod { elements, .. } => {
                    geometry.cells.extend(
                        (0..*elements).map(|e| (GeomCell::Line, vec![base + e, base + e + 1], bi)),
                    );
                }
                _ => geometry.cells.extend(mesh.cells.iter().map(|(k, c)| {
                    (
                        GeomCell::Solid(*k),
                        c.iter().map(|v| base + v).collect(),
                        bi,
                    )
                })),
            }
            geometry.node_ids.extend(
                (0..mesh.points.len()).map(|k| mesh.node_ids.get(k).copied().unwrap_or(k as u64)),
            );
            geometry.points.extend_from_slice(&mesh.points);
            geometry.bodies.push((b.material, b.formulation));
            systems.push(sys);
        }
        let meshes = all_meshes;
        let offsets = starts(systems.iter().map(LinearSystem::ndof));
        let full = LinearSystem::block_diagonal(systems)?;
        let fixed_dofs = fixed.iter().filter(|&&f| f).count();
        // prescribed velocities: eliminated with their coupling blocks
        let mut prescribed = vec![None; full.ndof()];
        let mut functions = Vec::new();
        for (pi, p) in self.prescribed.iter().enumerate() {
            let at = |e: Error| prefix(&format!("prescribed[{pi}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == p.body)
                .expect("validated");
            let dim = self.bodies[bi].dim();
            let nodes = node_set(&meshes[bi], &p.nodes).map_err(at)?;
            let comps: Vec<usize> = p.components.clone().unwrap_or_else(|| (0..dim).collect());
            functions.push(time_function(&format!("prescribed[{pi}].time"), &p.time)?);
            for &v in &nodes {
                for &c in &comps {
                    let d = offsets[bi] + v * dim + c;
                    if fixed[d] || prescribed[d].is_some() {
                        return Err(at(Error::invalid(
                            "nodes",
                            format!("{} component {c}", meshes[bi].node_label(v)),
                            "is already fixed or prescribed",
                        )));
                    }
                    prescribed[d] = Some((p.velocity[c], functions.len() - 1));
                }
            }
        }
        geometry.prescribed = (0..full.ndof())
            .filter_map(|d| match prescribed[d] {
                Some((w, f)) if !fixed[d] => Some((d, w, f)),
                _ => None,
            })
            .collect();
        geometry.prescribed_functions = functions.clone();
        let (mut system, map) = full.restrict_prescribed(&fixed, &prescribed, functions);
        // large-deformation bodies: their internal forces on the kept dofs
        for (bi, b) in self.bodies.iter().enumerate() {
            let law = match b.material.model {
                MaterialModel::Linear => continue,
                MaterialModel::Svk => Hyperelastic::svk(&b.material),
                MaterialModel::NeoHookean => Hyperelastic::neo_hookean(&b.material),
            };
            let at = |e: Error| prefix(&format!("bodies[{bi}] ({})", b.name), e);
            let mesh = &meshes[bi];
            let n = b.dim() * mesh.points.len();
            let dofs: Vec<Option<usize>> = (0..n).map(|i| map[offsets[bi] + i]).collect();
            if let Some(i) = (0..n).find(|&i| prescribed[offsets[bi] + i].is_some()) {
                return Err(at(Error::invalid(
                    "material.model",
                    b.material.model.name(),
                    &format!(
                        "takes no prescribed velocities yet (node {} is in a [[prescribed]] \
                         set); hold it with `fixed`, or use model = \"linear\"",
                        i / b.dim()
                    ),
                )));
            }
            let body = HyperBody::new(mesh, law).map_err(|e| at(prefix("mesh", e)))?;
            let part =
                HyperelasticPart::new(&b.name, body, dofs, mesh.cell_ids.clone()).map_err(at)?;
            system.add_nonlinear_part(std::sync::Arc::new(part));
        }
        geometry.dof_of = map.clone();
        let v0: Vec<f64> = v0
            .iter()
            .zip(&map)
            .filter(|(_, m)| m.is_some())
            .map(|(v, _)| *v)
            .collect();
        // forces on node sets (after the elimination: loads on fixed dofs are dropped,
        // the supports carry them)
        for (fi, f) in self.forces.iter().enumerate() {
            let at = |e: Error| prefix(&format!("forces[{fi}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == f.body)
                .expect("validated");
            let mesh = &meshes[bi];
            let nodes = node_set(mesh, &f.nodes).map_err(at)?;
            if nodes.is_empty() {
                return Err(at(Error::invalid(
                    "nodes",
                    &f.nodes,
                    "the node set is empty",
                )));
            }
            let dim = self.bodies[bi].dim();
            let share = 1.0 / nodes.len() as f64;
            let (mut dofs, mut values) = (Vec::new(), Vec::new());
            for &v in &nodes {
                for (i, &t) in f.total.iter().enumerate() {
                    if let Some(d) = map[offsets[bi] + v * dim + i] {
                        dofs.push(d);
                        values.push(t * share);
                    }
                }
            }
            let time = time_function(&format!("forces[{fi}].time"), &f.time)?;
            system
                .loads
                .push(crate::model::NodalLoad { dofs, values, time });
        }
        // contacts
        let mut sets: Vec<Box<dyn ContactSet>> = Vec::new();
        let mut interfaces = Vec::new();
        for (ci, c) in self.contacts.iter().enumerate() {
            let at = |e: Error| prefix(&format!("contacts[{ci}]"), e);
            let bi = self
                .bodies
                .iter()
                .position(|b| b.name == c.body)
                .expect("validated");
            let mesh = &meshes[bi];
            let nodes = std::mem::take(&mut nodes_of[ci]);
            if let Some(t) = &c.target {
                let ti = self.body_index(&t.body);
                let node_dofs = |body: usize, v: usize| -> [Option<usize>; 3] {
                    let mut d = [None; 3];
                    for (i, di) in d.iter_mut().enumerate().take(dim) {
                        *di = map[offsets[body] + v * dim + i];
                    }
                    d
                };
                let set = crate::contact::bodies::build(
                    crate::contact::bodies::Interface {
                        dim,
                        slave: &nodes,
                        slave_points: &mesh.points,
                        slave_dofs: &|v| node_dofs(bi, v),
                        facets: &facets_of[ci],
                        master_points: &meshes[ti].points,
                        master_dofs: &|v| node_dofs(ti, v),
                        names: Some((&c.body, &t.body, &|v| mesh.node_label(v))),
                    },
                    t.pairing == Pairing::NodeToNode,
                    (c.restitution, c.friction),
                    t.search,
                    t.capacity
                        .unwrap_or(crate::contact::bodies::DEFAULT_CAPACITY),
                )
                .map_err(at)?;
                check_starting_gaps(
                    set.0.as_ref(),
                    system.ndof(),
                    c,
                    mesh,
                    &nodes,
                    &format!("body \"{}\" (surface `{}`)", t.body, t.surface),
                )
                .map_err(at)?;
                interfaces.push(format!(
                    "contacts[{ci}]: {} nodes of \"{}\" against {}{}",
                    set.0.len(),
                    c.body,
                    set.1,
                    match axis_facets[ci] {
                        0 => String::new(),
                        k => format!(
                            " ({k} facet(s) of \"{}\" on the axis r = 0 left out: not \
                             surfaces of the revolved solid)",
                            t.body
                        ),
                    }
                ));
                sets.push(set.0);
                continue;
            }
            let obstacle = self.obstacle(c);
            let mut dofs = Vec::new();
            let mut refs = Vec::new();
            for &v in &nodes {
                let d: Option<Vec<usize>> =
                    (0..dim).map(|i| map[offsets[bi] + v * dim + i]).collect();
                let Some(d) = d else {
                    return Err(at(Error::invalid(
                        "nodes",
                        mesh.node_label(v),
                        "is fixed and cannot be a contact node",
                    )));
                };
                dofs.push(d);
                refs.push(mesh.points[v][..dim].to_vec());
            }
            let set = self
                .obstacle_set(obstacle, dofs, refs, (c.restitution, c.friction))
                .map_err(at)?;
            check_starting_gaps(
                set.as_ref(),
                system.ndof(),
                c,
                mesh,
                &nodes,
                &format!("obstacle \"{}\"", obstacle.name()),
            )
            .map_err(at)?;
            sets.push(set);
        }
        geometry.outlines = self
            .obstacles
            .iter()
            .map(|o| outline(o, &geometry.points, dim))
            .collect();
        let contacts: Box<dyn ContactSet> = if sets.len() == 1 {
            sets.pop().expect("one set")
        } else {
            Box::new(Composite::new(sets))
        };
        let report = ModelReport {
            dofs: system.ndof(),
            cells,
            contacts: contacts.len(),
            linear_contacts: contacts.is_linear(),
            max_friction: contacts
                .laws()
                .iter()
                .map(|l| l.friction)
                .fold(0.0, f64::max),
            damping: system.damping.is_some(),
            gravity: self.loads.gravity.is_some(),
            fixed_dofs,
            linear_structure: system.nonlinear.is_empty(),
            interfaces,
        };
        let n = system.ndof();
        if crate::model::ordering::worth_ordering(&geometry) {
            system.ordering = Some(crate::model::ordering::nested_dissection(&geometry, n));
        }
        Ok((
            Model {
                problem: Problem {
                    system,
                    contacts,
                    q0: vec![0.0; n],
                    v0,
                },
                geometry,
                probes,
            },
            report,
        ))
    }

    /// The `[[probes]]` on the built meshes: each set's points in the geometry, and a
    /// rod's abscissae from its end of smallest `x`.
    fn probes(&self, meshes: &[Mesh], point_base: &[usize]) -> Result<Vec<Probe>, Error> {
        let mut out = Vec::with_capacity(self.probes.len());
        for (i, p) in self.probes.iter().enumerate() {
            let bi = self.body_index(&p.body);
            let mesh = &meshes[bi];
            let nodes = node_set(mesh, &p.nodes).map_err(|e| prefix(&format!("probes[{i}]"), e))?;
            if nodes.is_empty() {
                return Err(Error::invalid(
                    &format!("probes[{i}].nodes"),
                    &p.nodes,
                    "the node set is empty",
                ));
            }
            let rod_abscissa = matches!(self.bodies[bi].mesh, MeshSpec::Rod { .. }).then(|| {
                let x0 = mesh
                    .points
                    .iter()
                    .map(|x| x[0])
                    .fold(f64::INFINITY, f64::min);
                nodes.iter().map(|&v| mesh.points[v][0] - x0).collect()
            });
            out.push(Probe {
                name: p.name.clone(),
                body: p.body.clone(),
                nodes: p.nodes.clone(),
                points: nodes.iter().map(|&v| point_base[bi] + v).collect(),
                times: p.times.clone(),
                rod_abscissa,
            });
        }
        Ok(out)
    }

    /// The nodes of contact `c` on `mesh`: its node set (`boundary` and `all`
    /// included), kept where the initial gap to the obstacle is at most `within`.
    fn contact_nodes(
        &self,
        mesh: &Mesh,
        c: &ContactSpec,
        dim: usize,
        facets: &[Vec<usize>],
        meshes: &[Mesh],
    ) -> Result<Vec<usize>, Error> {
        let nodes = node_set(mesh, &c.nodes)?;
        let Some(d) = c.within else {
            return Ok(nodes);
        };
        require_positive("within", d)?;
        if let Some(t) = &c.target {
            // the distance to the nearest facet's box (a lower bound of the distance to
            // the surface: keeps every node within `d`, and a few more)
            let master = &meshes[self.body_index(&t.body)];
            let dist = crate::contact::bodies::box_distances(
                nodes.iter().map(|&v| mesh.points[v]),
                facets,
                &master.points,
            );
            let kept: Vec<usize> = nodes
                .iter()
                .zip(&dist)
                .filter(|(_, x)| **x <= d)
                .map(|(&v, _)| v)
                .collect();
            if kept.is_empty() {
                return Err(Error::invalid(
                    "within",
                    crate::error::num(d),
                    &format!(
                        "no node of `{}` lies that close to the target surface (the nearest \
                         is {:.3e} m away)",
                        c.nodes,
                        dist.iter().copied().fold(f64::INFINITY, f64::min)
                    ),
                ));
            }
            return Ok(kept);
        }
        let obstacle = self.obstacle(c);
        // the gaps at the reference positions, through the obstacle's own gap function
        // (node-local dofs: q = 0 there)
        let dofs: Vec<Vec<usize>> = (0..nodes.len())
            .map(|k| (0..dim).map(|i| k * dim + i).collect())
            .collect();
        let refs: Vec<Vec<f64>> = nodes
            .iter()
            .map(|&v| mesh.points[v][..dim].to_vec())
            .collect();
        let set = self.obstacle_set(obstacle, dofs, refs, (c.restitution, c.friction))?;
        let mut jac = crate::contact::ContactJacobian::for_set(set.as_ref());
        let mut gap = vec![0.0; set.len()];
        set.evaluate(&vec![0.0; nodes.len() * dim], &mut gap, &mut jac);
        let kept: Vec<usize> = nodes
            .iter()
            .zip(&gap)
            .filter(|(_, g)| **g <= d)
            .map(|(&v, _)| v)
            .collect();
        if kept.is_empty() {
            return Err(Error::invalid(
                "within",
                crate::error::num(d),
                &format!(
                    "no node of `{}` lies that close to the obstacle (the nearest is {:.3e} m away)",
                    c.nodes,
                    gap.iter().copied().fold(f64::INFINITY, f64::min)
                ),
            ));
        }
        Ok(kept)
    }

    /// An axisymmetric scene is a solid of revolution about the y axis: every body
    /// axisymmetric (a plane-strain body beside one is an extrusion, which the revolved
    /// solid cannot touch), gravity along the axis, planes normal to it and spheres
    /// centred on it (issue 34: gravity along r and a plane-strain neighbour were
    /// accepted).
    fn validate_axisymmetric(&self) -> Result<(), Error> {
        let axi = |b: &BodySpec| matches!(b.formulation, Formulation::Axisymmetric);
        let Some(first) = self.bodies.iter().position(axi) else {
            return Ok(());
        };
        if let Some((i, b)) = self.bodies.iter().enumerate().find(|(_, b)| !axi(b)) {
            return Err(Error::invalid(
                &format!("bodies[{i}].formulation"),
                b.formulation.name(),
                &format!(
                    "must be axisymmetric like bodies[{first}] (\"{}\"): a scene is one \
                     solid of revolution, and a {} body is no part of it",
                    self.bodies[first].name,
                    b.formulation.name()
                ),
            ));
        }
        if let Some(g) = &self.loads.gravity
            && g.first().is_some_and(|&gr| gr != 0.0)
        {
            return Err(Error::invalid(
                "loads.gravity",
                format!("{g:?}"),
                "must lie along the axis of revolution (y) in an axisymmetric scene: \
                 gravity along r would pull every ring outward alike, which no body of \
                 revolution feels; give [0.0, g]",
            ));
        }
        for (j, o) in self.obstacles.iter().enumerate() {
            let (key, value, bad, what) = match o {
                ObstacleSpec::Plane { normal, .. } => (
                    "normal",
                    format!("{normal:?}"),
                    normal.first().is_some_and(|&n| n != 0.0),
                    "a plane of revolution is normal to the axis: give [0.0, ±1.0]",
                ),
                ObstacleSpec::Sphere { center, .. } => (
                    "center",
                    format!("{center:?}"),
                    center.first().is_some_and(|&c| c != 0.0),
                    "a sphere of revolution is centred on the axis: give [0.0, y]",
                ),
                ObstacleSpec::Cylinder { .. } => (
                    "type",
                    "cylinder".to_string(),
                    true,
                    "a cylinder is a 3-D obstacle; an axisymmetric scene takes planes and \
                     spheres",
                ),
            };
            if bad {
                return Err(Error::invalid(
                    &format!("obstacles[{j}].{key}"),
                    value,
                    &format!("(obstacle \"{}\") {what}", o.name()),
                ));
            }
        }
        Ok(())
    }

    /// The index of the body named `name` (validated to exist).
    fn body_index(&self, name: &str) -> usize {
        self.bodies
            .iter()
            .position(|b| b.name == name)
            .expect("validated body name")
    }

    /// The obstacle of contact `c` (validated to exist).
    fn obstacle(&self, c: &ContactSpec) -> &ObstacleSpec {
        self.obstacles
            .iter()
            .find(|o| Some(o.name()) == c.obstacle.as_deref())
            .expect("validated obstacle name")
    }

    fn obstacle_set(
        &self,
        o: &ObstacleSpec,
        dofs: Vec<Vec<usize>>,
        refs: Vec<Vec<f64>>,
        (e, mu): (f64, f64),
    ) -> Result<Box<dyn ContactSet>, Error> {
        Ok(match o {
            ObstacleSpec::Plane { point, normal, .. } => {
                let norm = normal.iter().map(|x| x * x).sum::<f64>().sqrt();
                let offset = point.iter().zip(normal).map(|(p, n)| p * n).sum::<f64>();
                if point.len() != normal.len() {
                    return Err(Error::invalid(
                        "point",
                        format!("{point:?}"),
                        "needs as many components as normal",
                    ));
                }
                let _ = norm;
                Box::new(
                    NodesOnPlane::new(dofs, refs, normal.clone(), offset, e)?.with_friction(mu)?,
                )
            }
            ObstacleSpec::Sphere {
                center,
                radius,
                side,
                ..
            } => Box::new(
                RoundObstacle::general(dofs, refs, center.clone(), None, *radius, *side, e)?
                    .with_friction(mu)?,
            ),
            ObstacleSpec::Cylinder {
                point,
                axis,
                radius,
                side,
                ..
            } => Box::new(
                RoundObstacle::general(
                    dofs,
                    refs,
                    point.clone(),
                    Some(axis.clone()),
                    *radius,
                    *side,
                    e,
                )?
                .with_friction(mu)?,
            ),
        })
    }
}

impl BodySpec {
    fn dim(&self) -> usize {
        match self.mesh {
            MeshSpec::Rod { .. } => 1,
            _ => self.formulation.dim(),
        }
    }

    fn mesh(&self, base: &Path) -> Result<Mesh, Error> {
        match &self.mesh {
            MeshSpec::File { path } => {
                let m = crate::io::mesh::read_mesh(&base.join(path))?;
                // measured against the memory limit before it is assembled (issue 34: a
                // 40³ hex8 file under a 96 MiB limit was refused only after its assembly,
                // at a peak of 1.1 GiB)
                let per_cell = m.cells.iter().map(|(_, c)| c.len()).max().unwrap_or(1);
                crate::limits::mesh_memory(
                    m.points.len() as u64,
                    m.cells.len() as u64,
                    per_cell as u64,
                    self.dim() as u64,
                )
                .check("mesh.path", path.display())?;
                Ok(m)
            }
            MeshSpec::Box {
                cell,
                cells,
                size,
                origin,
            } => {
                generator_checks("box", *cell, cells, size, origin)?;
                let mut m = box_mesh(*cell, *cells, *size);
                for p in &mut m.points {
                    for i in 0..3 {
                        p[i] += origin[i];
                    }
                }
                Ok(m)
            }
            MeshSpec::Rectangle {
                cell,
                cells,
                size,
                origin,
            } => {
                generator_checks("rectangle", *cell, cells, size, origin)?;
                let mut m = rectangle_mesh(*cell, *cells, *size);
                for p in &mut m.points {
                    p[0] += origin[0];
                    p[1] += origin[1];
                }
                Ok(m)
            }
            MeshSpec::Rod {
                elements,
                length,
                origin,
                ..
            } => {
                crate::error::require_finite("mesh.origin", *origin)?;
                if *elements == 0 {
                    return Err(Error::invalid("mesh.elements", 0, "must be at least 1"));
                }
                require_positive("mesh.length", *length)?;
                let n = *elements as u64;
                crate::limits::mesh_memory(n + 1, n, 2, 1).check("mesh.elements", n)?;
                let mut m = Mesh::default();
                let n = *elements;
                for i in 0..=n {
                    m.points
                        .push([origin + *length * i as f64 / n.max(1) as f64, 0.0, 0.0]);
                }
                m.node_sets =
                    BTreeMap::from([("x0".to_string(), vec![0]), ("x1".to_string(), vec![n])]);
                Ok(m)
            }
        }
    }
}

/// The outline of obstacle `o` for ParaView, sized to the bodies' bounding box: a
/// plane as a square (3-D) or a segment (2-D) around the box centre's projection, a
/// sphere as three great circles (one circle in 2-D), a cylinder as its two end
/// circles and eight generators over the box's extent along the axis.
fn outline(o: &ObstacleSpec, points: &[[f64; 3]], dim: usize) -> Outline {
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let centre: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
    let size = (0..3)
        .map(|i| (hi[i] - lo[i]).powi(2))
        .sum::<f64>()
        .sqrt()
        .max(1e-3);
    let v3 = |v: &[f64]| -> [f64; 3] { std::array::from_fn(|i| v.get(i).copied().unwrap_or(0.0)) };
    let unit = |v: [f64; 3]| {
        let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.map(|x| x / l)
    };
    let dot = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| a[i] * b[i]).sum::<f64>();
    let mut out = Outline {
        name: o.name().to_string(),
        ..Outline::default()
    };
    match o {
        ObstacleSpec::Plane { point, normal, .. } => {
            let (p, n) = (v3(point), unit(v3(normal)));
            let d = dot(n, std::array::from_fn(|i| centre[i] - p[i]));
            let c: [f64; 3] = std::array::from_fn(|i| centre[i] - d * n[i]);
            let (a, b) = if dim == 2 {
                ([-n[1], n[0], 0.0], [0.0, 0.0, 0.0])
            } else {
                orthonormal(n)
            };
            let h = 0.75 * size;
            let corner = |s: f64, t: f64| -> [f64; 3] {
                std::array::from_fn(|i| c[i] + h * (s * a[i] + t * b[i]))
            };
            if dim == 2 {
                out.segment(corner(-1.0, 0.0), corner(1.0, 0.0));
            } else {
                for (s0, t0, s1, t1) in [
                    (-1.0, -1.0, 1.0, -1.0),
                    (1.0, -1.0, 1.0, 1.0),
                    (1.0, 1.0, -1.0, 1.0),
                    (-1.0, 1.0, -1.0, -1.0),
                ] {
                    out.segment(corner(s0, t0), corner(s1, t1));
                }
            }
        }
        ObstacleSpec::Sphere { center, radius, .. } => {
            let c = v3(center);
            let e = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            out.circle(c, e[0], e[1], *radius, 96);
            if dim == 3 {
                out.circle(c, e[1], e[2], *radius, 96);
                out.circle(c, e[0], e[2], *radius, 96);
            }
        }
        ObstacleSpec::Cylinder {
            point,
            axis,
            radius,
            ..
        } => {
            let (p, n) = (v3(point), unit(v3(axis)));
            let (a, b) = orthonormal(n);
            let t = dot(n, std::array::from_fn(|i| centre[i] - p[i]));
            let half = 0.75 * size;
            for s in [-1.0, 1.0] {
                let c: [f64; 3] = std::array::from_fn(|i| p[i] + (t + s * half) * n[i]);
                out.circle(c, a, b, *radius, 96);
            }
            for k in 0..8 {
                let th = std::f64::consts::PI * k as f64 / 4.0;
                let r: [f64; 3] =
                    std::array::from_fn(|i| radius * (th.cos() * a[i] + th.sin() * b[i]));
                out.segment(
                    std::array::from_fn(|i| p[i] + r[i] + (t - half) * n[i]),
                    std::array::from_fn(|i| p[i] + r[i] + (t + half) * n[i]),
                );
            }
        }
    }
    out
}

/// Checks a generator's request before anything is generated: the cell kind is one it
/// makes, the counts are positive and their products fit the memory limit, the sizes
/// are positive and finite, the origin is finite.
fn generator_checks(
    generator: &str,
    cell: CellKind,
    cells: &[usize],
    size: &[f64],
    origin: &[f64],
) -> Result<(), Error> {
    let (kinds, per_box): (&[CellKind], u64) = match (generator, cell) {
        ("box", CellKind::Tet4) => (&[CellKind::Hex8, CellKind::Tet4], 6),
        ("box", _) => (&[CellKind::Hex8, CellKind::Tet4], 1),
        (_, CellKind::Tri3) => (&[CellKind::Quad4, CellKind::Tri3], 2),
        _ => (&[CellKind::Quad4, CellKind::Tri3], 1),
    };
    if !kinds.contains(&cell) {
        return Err(Error::invalid(
            "mesh.cell",
            cell.name(),
            &format!(
                "the `{generator}` generator makes {} cells",
                kinds
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join(" or ")
            ),
        ));
    }
    if cells.contains(&0) {
        return Err(Error::invalid(
            "mesh.cells",
            format!("{cells:?}"),
            "needs counts of at least 1",
        ));
    }
    for (i, s) in size.iter().enumerate() {
        require_positive(&format!("mesh.size[{i}]"), *s)?;
    }
    for (i, o) in origin.iter().enumerate() {
        crate::error::require_finite(&format!("mesh.origin[{i}]"), *o)?;
    }
    let prod = |extra: u64| {
        cells
            .iter()
            .try_fold(1u64, |a, &c| a.checked_mul(c as u64 + extra))
            .unwrap_or(u64::MAX)
    };
    let n_cells = prod(0).saturating_mul(per_box);
    let dim = cells.len() as u64;
    crate::limits::mesh_memory(prod(1), n_cells, cell.nodes() as u64, dim)
        .check("mesh.cells", format!("{cells:?}"))
}

/// Where each of consecutive blocks of `sizes` starts (the exclusive prefix sums): the
/// bodies' first point and first dof.
fn starts(sizes: impl Iterator<Item = usize>) -> Vec<usize> {
    sizes
        .scan(0, |acc, n| {
            let start = *acc;
            *acc += n;
            Some(start)
        })
        .collect()
}

/// The time function of a `[[forces]]` / `[[prescribed]]` entry (1 when absent).
fn time_function(
    field: &str,
    t: &Option<Vec<[f64; 2]>>,
) -> Result<crate::model::TimeFunction, Error> {
    match t {
        Some(t) => crate::model::TimeFunction::new(field, t.iter().map(|p| (p[0], p[1])).collect()),
        None => Ok(crate::model::TimeFunction::one()),
    }
}

/// The nodes of the set `name` of `mesh`: a named set, `boundary` (computed from the
/// cells when the mesh has no set of that name) or `all`.
fn node_set(mesh: &crate::model::solid::Mesh, name: &str) -> Result<Vec<usize>, Error> {
    // an empty set fixes, drives, loads or probes nothing (issue 34: `fixed` and
    // `prescribed` accepted one silently)
    let set = node_set_any(mesh, name)?;
    if set.is_empty() {
        return Err(Error::invalid(
            "nodes",
            name,
            "the node set is empty: it names no node of the mesh",
        ));
    }
    Ok(set)
}

/// The nodes of set `name` of `mesh` (`all`, `boundary` computed when the mesh has no
/// set of that name), possibly none.
fn node_set_any(mesh: &crate::model::solid::Mesh, name: &str) -> Result<Vec<usize>, Error> {
    if name == "all" {
        Ok((0..mesh.points.len()).collect())
    } else if name == "boundary" && !mesh.node_sets.contains_key("boundary") {
        Ok(mesh.boundary_nodes())
    } else {
        mesh.node_sets.get(name).cloned().ok_or_else(|| {
            Error::invalid(
                "nodes",
                name,
                &format!(
                    "no such node set; the mesh has {} (and `boundary`, `all`)",
                    {
                        let mut names: Vec<_> =
                            mesh.node_sets.keys().map(|k| format!("`{k}`")).collect();
                        names.sort();
                        if names.is_empty() {
                            "none".to_string()
                        } else {
                            names.join(", ")
                        }
                    }
                ),
            )
        })
    }
}

/// The master surface of a contact between bodies: the boundary facets of `target`'s
/// surface set on `mesh` (a rod's ends in the set, each with its outward direction),
/// and how many facets on the axis were left out.
///
/// An axisymmetric body's mesh is its half section `x = r ≥ 0`: its edges on the axis
/// `r = 0` bound the section, not the revolved solid, and are never contact facets
/// (issue 33: a `surface = "boundary"` that kept them paired a pole with an axis edge
/// at gap 0 while 2 µm apart). An edge whose nodes both lie within 1e-9 of the
/// section's width from the axis is left out; `check` reports the count.
fn target_facets(
    mesh: &Mesh,
    body: &BodySpec,
    t: &TargetSpec,
) -> Result<(Vec<Vec<usize>>, usize), Error> {
    let set = node_set(mesh, &t.surface).map_err(|e| prefix("surface", e))?;
    let mut facets = if let MeshSpec::Rod { .. } = body.mesh {
        // a rod's facets are its end nodes; the direction is recovered by `bodies::build`
        // from the neighbouring node
        let last = mesh.points.len() - 1;
        set.iter()
            .filter(|&&v| v == 0 || v == last)
            .map(|&v| vec![v])
            .collect()
    } else {
        mesh.boundary_facets(&set)
    };
    let mut on_axis = 0;
    if matches!(body.formulation, Formulation::Axisymmetric) {
        let width = mesh.points.iter().fold(0.0f64, |w, p| w.max(p[0].abs()));
        let tol = 1e-9 * width;
        let before = facets.len();
        facets.retain(|f| !f.iter().all(|&v| mesh.points[v][0].abs() <= tol));
        on_axis = before - facets.len();
    }
    if facets.is_empty() {
        return Err(Error::invalid(
            "surface",
            &t.surface,
            &format!(
                "holds no boundary facet of body \"{}\" (a facet counts when all its nodes \
                 are in the set{})",
                t.body,
                if on_axis > 0 {
                    format!(
                        "; its {on_axis} facet(s) on the axis r = 0 are not surfaces of the revolved solid"
                    )
                } else {
                    String::new()
                }
            ),
        ));
    }
    Ok((facets, on_axis))
}

/// The first line of a parser's message (toml's messages carry a source excerpt after it).
/// Sets `KEY=VALUE` in a scene's TOML table ([`Scene::from_file_with`]).
fn apply_override(table: &mut toml::Table, o: &str) -> Result<(), Error> {
    let bad = |why: &str| Error::invalid("--set", o, why);
    let (key, value) = o
        .split_once('=')
        .ok_or_else(|| bad("expected KEY=VALUE, e.g. scheme.newton.modified=true"))?;
    // exactly one value: `2e-6\n[evil]\nx = 1` parses as a document with more in it,
    // which was dropped (issue 34)
    let value: toml::Value = toml::from_str::<toml::Table>(&format!("v = {}", value.trim()))
        .ok()
        .filter(|t| t.len() == 1)
        .and_then(|mut t| t.remove("v"))
        .ok_or_else(|| {
            bad("VALUE is not one TOML value (quote strings: model=\"svk\"; no line breaks)")
        })?;
    // segments: names, each with optional [index]
    let mut path: Vec<(&str, Option<usize>)> = Vec::new();
    for seg in key.trim().split('.') {
        let (name, index) = match seg.split_once('[') {
            Some((n, rest)) => {
                let i = rest
                    .strip_suffix(']')
                    .and_then(|i| i.parse::<usize>().ok())
                    .ok_or_else(|| bad("an index is written name[0]"))?;
                (n, Some(i))
            }
            None => (seg, None),
        };
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(bad(
                "KEY is a dotted path of names, e.g. bodies[0].material.model",
            ));
        }
        path.push((name, index));
    }
    let (last, parents) = path.split_last().expect("at least one segment");
    let mut cur = table;
    for &(name, index) in parents {
        let entry = cur
            .entry(name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let next = match index {
            None => entry,
            Some(i) => {
                let len = entry.as_array().map_or(0, |a| a.len());
                entry
                    .as_array_mut()
                    .and_then(|a| a.get_mut(i))
                    .ok_or_else(|| bad(&format!("`{name}` has {len} entries; no [{i}]")))?
            }
        };
        cur = next
            .as_table_mut()
            .ok_or_else(|| bad(&format!("`{name}` is not a table")))?;
    }
    match last.1 {
        None => {
            cur.insert(last.0.to_string(), value);
        }
        Some(i) => {
            let arr = cur
                .get_mut(last.0)
                .and_then(|v| v.as_array_mut())
                .ok_or_else(|| bad(&format!("`{}` is not an array", last.0)))?;
            let len = arr.len();
            *arr.get_mut(i)
                .ok_or_else(|| bad(&format!("`{}` has {len} entries; no [{i}]", last.0)))? = value;
        }
    }
    Ok(())
}

fn first_line(m: &str) -> &str {
    m.lines().next().unwrap_or(m).trim()
}

fn prefix(p: &str, e: Error) -> Error {
    match e {
        Error::InvalidParameter {
            field,
            value,
            reason,
        } => Error::InvalidParameter {
            field: format!("{p}.{field}"),
            value,
            reason,
        },
        other => other,
    }
}
