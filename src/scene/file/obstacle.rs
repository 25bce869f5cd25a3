//! Obstacles in scene files: the `[[obstacles]]` schema ([`ObstacleSpec`]), its checks,
//! the contact set an obstacle gives a body's nodes, and the outline ParaView draws of it.

use super::*;

impl Scene {
    /// The obstacle of contact `c` (validated to exist).
    pub(super) fn obstacle(&self, c: &ContactSpec) -> &ObstacleSpec {
        self.obstacles
            .iter()
            .find(|o| Some(o.name()) == c.obstacle.as_deref())
            .expect("validated obstacle name")
    }

    pub(super) fn obstacle_set(
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

pub(super) fn outside() -> Side {
    Side::Outside
}

impl ObstacleSpec {
    /// Checks the geometry in a scene of dimension `dim`, whether or not a contact uses
    /// the obstacle: finite points, non-zero normals and axes, positive radii.
    pub(super) fn validate(&self, dim: usize) -> Result<(), Error> {
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

    pub(super) fn name(&self) -> &str {
        match self {
            ObstacleSpec::Plane { name, .. }
            | ObstacleSpec::Sphere { name, .. }
            | ObstacleSpec::Cylinder { name, .. } => name,
        }
    }
}

/// The outline of obstacle `o` for ParaView, sized to the bodies' bounding box: a
/// plane as a square (3-D) or a segment (2-D) around the box centre's projection, a
/// sphere as three great circles (one circle in 2-D), a cylinder as its two end
/// circles and eight generators over the box's extent along the axis.
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
