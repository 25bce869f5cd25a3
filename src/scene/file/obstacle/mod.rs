//! Obstacles in scene files (`[[obstacles]]`): the [`ObstacleShape`] trait every rigid
//! obstacle implements, and [`ObstacleSpec`], the registry of shapes a scene can name.
//!
//! A shape says how it is checked (alone, and in an axisymmetric scene), which contact
//! set it gives a body's candidate nodes, and the outline ParaView draws of it. To add a
//! shape: one file here with its table (a serde struct whose fields are the shape's keys,
//! `name` among them) implementing [`ObstacleShape`], and its line in the
//! [`obstacle_shapes!`] invocation below; the scene's schema (`type = "…"`), validation,
//! contacts, starting-gap check and outlines take it from there.

use super::*;

mod cylinder;
mod plane;
mod sphere;

pub use cylinder::CylinderSpec;
pub use plane::PlaneSpec;
pub use sphere::SphereSpec;

/// A rigid obstacle's behaviour in a scene (module doc).
pub trait ObstacleShape {
    /// The name contacts use (`obstacle = "…"`).
    fn name(&self) -> &str;
    /// Checks the geometry in a scene of dimension `dim` (`axisymmetric`: the 2-D scene
    /// is the section of a solid of revolution), whether or not a contact uses the
    /// obstacle; errors name the key inside the obstacle's table.
    fn validate(&self, dim: usize, axisymmetric: bool) -> Result<(), Error>;
    /// In an axisymmetric scene (`x` = r, `y` the axis): `None` when the shape revolves
    /// into a surface whose gap the section's gap gives exactly (a plane normal to the
    /// axis, a coaxial cylinder, a sphere centred on it), else the key, its value and
    /// why not.
    fn axisymmetric_problem(&self) -> Option<(&'static str, String, &'static str)>;
    /// The contact set between this obstacle and the nodes with `dofs` (per node, its
    /// coordinates' dofs) at reference positions `refs`, restitution `e`, friction `mu`.
    fn contact_set(
        &self,
        dofs: Vec<Vec<usize>>,
        refs: Vec<Vec<f64>>,
        e: f64,
        mu: f64,
    ) -> Result<Box<dyn ContactSet>, Error>;
    /// The unit normal `n` and offset `c` of the half-space `n·x ≥ c` when the obstacle
    /// is a plane (the surface rule's gaps are affine there), else `None`.
    fn plane(&self) -> Option<(Vec<f64>, f64)> {
        None
    }
    /// Draws the obstacle into `out` for ParaView, sized to the bodies' bounding box
    /// (`view`) in a scene of dimension `dim`.
    fn outline(&self, out: &mut Outline, view: &View, dim: usize);
}

/// The bodies' bounding box as an outline sees it: its centre and diagonal (at least 1 mm).
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// Centre of the bounding box (m).
    pub centre: [f64; 3],
    /// Length of its diagonal, at least 1e-3 (m).
    pub size: f64,
}

/// The registry: the [`ObstacleSpec`] enum (serde-tagged by `type`, one variant per
/// shape) and its dispatch to [`ObstacleShape`]. One line per shape:
/// `Variant(Table) = "type"`.
macro_rules! obstacle_shapes {
    ($($variant:ident($table:ty) = $key:literal),+ $(,)?) => {
        /// `[[obstacles]]`: one of the registered shapes, by `type`.
        #[derive(Clone, Debug, Serialize, Deserialize)]
        #[serde(tag = "type")]
        pub enum ObstacleSpec {
            $(
                #[doc = concat!("`type = \"", $key, "\"`.")]
                #[serde(rename = $key)]
                $variant($table),
            )+
        }

        impl ObstacleSpec {
            /// The shape behind the table.
            pub fn shape(&self) -> &dyn ObstacleShape {
                match self {
                    $(ObstacleSpec::$variant(s) => s,)+
                }
            }
        }
    };
}

obstacle_shapes! {
    Plane(PlaneSpec) = "plane",
    Sphere(SphereSpec) = "sphere",
    Cylinder(CylinderSpec) = "cylinder",
}

impl ObstacleSpec {
    /// The name contacts use.
    pub fn name(&self) -> &str {
        self.shape().name()
    }
}

impl Scene {
    /// The obstacle of contact `c` (validated to exist).
    pub(super) fn obstacle(&self, c: &ContactSpec) -> &ObstacleSpec {
        self.obstacles
            .iter()
            .find(|o| Some(o.name()) == c.obstacle.as_deref())
            .expect("validated obstacle name")
    }
}

pub(super) fn outside() -> Side {
    Side::Outside
}

/// Checks a vector key: `n` finite components, and not the zero vector when it gives a
/// direction.
pub(super) fn check_vector(key: &str, v: &[f64], n: usize, nonzero: bool) -> Result<(), Error> {
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
}

/// The contact set of a sphere (`axis = None`) or cylinder through `centre` of `radius`,
/// admissible on `side`, with restitution `e` and friction `mu`.
pub(super) fn round_set(
    dofs: Vec<Vec<usize>>,
    refs: Vec<Vec<f64>>,
    (centre, axis): (&[f64], Option<&Vec<f64>>),
    (radius, side): (f64, Side),
    (e, mu): (f64, f64),
) -> Result<Box<dyn ContactSet>, Error> {
    Ok(Box::new(
        RoundObstacle::general(dofs, refs, centre.to_vec(), axis.cloned(), radius, side, e)?
            .with_friction(mu)?,
    ))
}

/// A vector key as three components (missing ones zero).
pub(super) fn v3(v: &[f64]) -> [f64; 3] {
    std::array::from_fn(|i| v.get(i).copied().unwrap_or(0.0))
}

/// `v / |v|`.
pub(super) fn unit(v: [f64; 3]) -> [f64; 3] {
    let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.map(|x| x / l)
}

/// `a · b`.
pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| a[i] * b[i]).sum::<f64>()
}

/// The outline of obstacle `o` for ParaView, sized to the bodies' bounding box
/// ([`ObstacleShape::outline`]).
pub(super) fn outline(o: &ObstacleSpec, points: &[[f64; 3]], dim: usize) -> Outline {
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
    let mut out = Outline {
        name: o.name().to_string(),
        ..Outline::default()
    };
    o.shape().outline(&mut out, &View { centre, size }, dim);
    out
}
