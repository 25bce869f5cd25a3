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
//!
//! This file holds the schema (the serde types of every table); the rest by role:
//! `parse` (text, TOML tables and `--set` overrides to a [`Scene`]), `validate` (ranges
//! and cross-references), `build` (the [`Model`] a scene describes, phase by phase),
//! `contacts` (each contact entry's nodes and contact set), `gaps` (the starting-gap
//! rule, [`StartingGaps`]), `meshes` (the build's phases on the meshes before assembly),
//! `initial` (the initial fields and motions),
//! `mesh_spec` (a body's mesh and node sets), `arrays` (the flat tables of a mesh or a
//! field given as arrays, [`Rows`], and their memory from their shapes), `obstacle`
//! (obstacles: schema, checks, contact sets, outlines).

mod arrays;
mod build;
mod contact_rows;
mod contacts;
mod rule;
pub use rule::ContactRule;
mod gaps;
mod initial;
mod loads;
use loads::time_points;
pub use loads::{ForceSpec, Loads, PressureSpec};
mod mesh_spec;
mod meshes;
mod obstacle;
mod parse;
mod time;
mod validate;

pub use arrays::{Rows, arrays_memory};
pub use gaps::StartingGaps;
pub use obstacle::ObstacleSpec;
use {gaps::*, mesh_spec::*, obstacle::*, validate::*};

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
use crate::model::hyperelastic::HyperBody;
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
    /// Uniform pressures on boundary faces with a time function.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pressures: Vec<PressureSpec>,
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
    /// Time step (s); in the accuracy mode the first and, unless `dt_max` says otherwise,
    /// the largest step.
    pub dt: f64,
    /// End time (s).
    pub t_end: f64,
    /// The accuracy mode ([`crate::run::accuracy`]): the relative accuracy asked of the
    /// run's observables (contact impulse history, energy, gaps); the run chooses its
    /// steps on the ladder `dt_max · 2⁻ᵏ` and writes the error it estimates. `None`:
    /// every step is `dt`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<f64>,
    /// The accuracy mode's largest step (s; default `dt`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_max: Option<f64>,
    /// The accuracy mode's smallest step (s; default `dt_max / 2¹⁰`): a window that
    /// misses the accuracy at it is kept and the run reports it (exit 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_min: Option<f64>,
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
    /// Initial velocity (m/s, one value per component): uniform, or the translation of
    /// the rigid motion `v(x) = velocity + angular_velocity × (x − rotation_center)`.
    #[serde(default)]
    pub velocity: Option<Vec<f64>>,
    /// Initial angular velocity of the body's rigid motion (rad/s): three values for a
    /// 3-D solid, one (about z) for a plane body; not for rods or axisymmetric bodies.
    #[serde(default)]
    pub angular_velocity: Option<Vec<f64>>,
    /// The point the initial rigid motion turns about (m, one value per component);
    /// default: the body's centre of mass.
    #[serde(default)]
    pub rotation_center: Option<Vec<f64>>,
    /// A per-node initial velocity field (m/s) instead of a rigid motion: one row of
    /// one value per component for every node of the body's mesh, in its order, given
    /// inline (`[[vx, vy, vz], …]`, or a numpy array through the Python package's
    /// `Scene.from_dict`) or as `{ file = "v0.csv" }` (relative to the scene's
    /// directory; values separated by commas or white space, `#` starts a comment).
    /// Excludes `velocity`, `angular_velocity` and `rotation_center`; zero on the
    /// components `fixed` holds.
    #[serde(default)]
    pub initial_velocity: Option<NodalField>,
    /// A per-node initial displacement field (m), given as `initial_velocity` is; zero
    /// on the components `fixed` holds. The starting gaps are checked at it (no node
    /// may start inside an obstacle or another body beyond `overlap_tolerance`).
    #[serde(default)]
    pub initial_displacement: Option<NodalField>,
    /// Node sets held fixed (u = 0).
    #[serde(default)]
    pub fixed: Vec<String>,
}

/// A field with one row per node of a body's mesh (`initial_velocity`,
/// `initial_displacement`): rows of numbers, or `{ file = "…" }` and no other key.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum NodalField {
    /// The rows, in the scene.
    Rows(Rows<f64>),
    /// A text file of rows.
    File {
        /// Its path, relative to the scene's directory.
        file: String,
    },
}

/// Read by hand rather than as an untagged enum: its refusals name the row or key that
/// is wrong (serde's untagged enums say only that no variant matched), and a file
/// table's unknown keys are refused (`{ file = "v0.csv", columns = [1, 2, 3] }` read
/// every column, silently).
impl<'de> Deserialize<'de> for NodalField {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl<'de> serde::de::Visitor<'de> for Visit {
            type Value = NodalField;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("rows of numbers, one per node ([[x, y, z], …]), or { file = \"…\" }")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<NodalField, A::Error> {
                let mut rows = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 20));
                // a bad row is named by serde's path (`initial_velocity[3][1]`)
                while let Some(row) = seq.next_element::<Vec<f64>>()? {
                    rows.push(row);
                }
                Ok(NodalField::Rows(Rows::from_rows(rows)))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<NodalField, A::Error> {
                let mut file = None;
                while let Some(key) = map.next_key::<String>()? {
                    if key != "file" {
                        return Err(at_key(
                            &format!(".{key}"),
                            crate::error::excerpt(&key),
                            "is not a key of a field file: the table is { file = \"…\" } \
                             alone (one row per node, one column per component, in order)",
                        ));
                    }
                    if file.is_some() {
                        return Err(at_key(".file", "(twice)", "is given once"));
                    }
                    // a bad value is named by serde's path (`initial_velocity.file`)
                    file = Some(map.next_value::<String>()?);
                }
                file.map(|file| NodalField::File { file })
                    .ok_or_else(|| at_key("", "{}", "needs `file = \"…\"` (the path of the rows)"))
            }
        }
        d.deserialize_any(Visit)
    }
}

/// Separates the parts of an [`at_key`] message.
pub(super) const KEY_MARK: char = '\u{1f}';

/// A deserialization error below the key path serde reports (inside an internally
/// tagged or hand-read value, whose inner path serde loses): `sub` is appended to that
/// path (`.cells.hex8[0][7]`, `[3]`), and [`Scene::from_toml`] reports it as an
/// [`Error::InvalidParameter`] with `value` and `reason`.
pub(super) fn at_key<E: serde::de::Error>(
    sub: &str,
    value: impl std::fmt::Display,
    reason: &str,
) -> E {
    E::custom(format!(
        "{KEY_MARK}{sub}{KEY_MARK}{value}{KEY_MARK}{reason}"
    ))
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
    /// A mesh given as arrays (a scene built in code or from Python's numpy arrays):
    /// point coordinates, connectivity by cell kind and named node sets.
    Arrays {
        /// Coordinates (m) of each point: `[x, y, z]`, or `[x, y]` for a plane or
        /// axisymmetric body.
        points: Rows<f64>,
        /// Connectivity by cell kind (`hex8`, `tet4`, `quad4`, `tri3`): each cell's
        /// point indices (0-based, in `points`), in the VTK/Gmsh node order.
        #[serde(deserialize_with = "mesh_spec::cell_lists")]
        cells: BTreeMap<String, Rows<usize>>,
        /// Named node sets (point indices) for `fixed`, `[[contacts]]`, `[[forces]]`,
        /// `[[prescribed]]` and `[[probes]]` (`boundary` and `all` always exist).
        #[serde(default, deserialize_with = "mesh_spec::index_sets")]
        node_sets: BTreeMap<String, Vec<usize>>,
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
    /// `nodes` (default: one row per node, its own gap) or `surface`: against a plane
    /// obstacle, rows at points of the body's faces ([`crate::contact::surface`]); with a
    /// `target`, mortar rows ([`crate::contact::mortar`]); both with or without friction.
    #[serde(default, skip_serializing_if = "ContactRule::is_nodes")]
    pub rule: ContactRule,
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
    /// Number of steps.
    pub fn steps(&self) -> usize {
        crate::limits::step_count(self.time.t_end, self.time.dt, "time.t_end", "time.dt")
            .unwrap_or(0)
    }

    /// The files the scene reads besides itself (mesh files, initial field files),
    /// as written (relative to [`Scene::base_dir`] unless absolute), once each: what a
    /// checkpoint verifies before it resumes.
    pub fn data_files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = Vec::new();
        for b in &self.bodies {
            if let MeshSpec::File { path } = &b.mesh
                && !files.contains(path)
            {
                files.push(path.clone());
            }
            for field in [&b.initial_velocity, &b.initial_displacement] {
                if let Some(NodalField::File { file }) = field
                    && !files.iter().any(|f| f.as_os_str() == file.as_str())
                {
                    files.push(PathBuf::from(file));
                }
            }
        }
        files
    }

    /// The index of the body named `name` (validated to exist).
    pub(super) fn body_index(&self, name: &str) -> usize {
        self.bodies
            .iter()
            .position(|b| b.name == name)
            .expect("validated body name")
    }
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
