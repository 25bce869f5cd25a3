//! The infinite cylinder obstacle (3-D), outside or inside (`type = "cylinder"`).

use super::*;

/// `type = "cylinder"`: an infinite cylinder (3-D).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    /// Name used by contacts.
    pub name: String,
    /// A point of the axis.
    pub point: Vec<f64>,
    /// Axis direction.
    pub axis: Vec<f64>,
    /// Radius (m).
    pub radius: f64,
    /// `outside` (default) or `inside`.
    #[serde(default = "outside")]
    pub side: Side,
}

impl ObstacleShape for CylinderSpec {
    fn name(&self) -> &str {
        &self.name
    }

    fn validate(&self, dim: usize) -> Result<(), Error> {
        if dim != 3 {
            return Err(Error::invalid(
                "type",
                "cylinder",
                &format!(
                    "is a 3-D obstacle; this scene is {dim}-D (use a sphere: a circle in 2-D)"
                ),
            ));
        }
        check_vector("point", &self.point, 3, false)?;
        check_vector("axis", &self.axis, 3, true)?;
        require_positive("radius", self.radius).map(|_| ())
    }

    fn axisymmetric_problem(&self) -> Option<(&'static str, String, &'static str)> {
        Some((
            "type",
            "cylinder".to_string(),
            "a cylinder is a 3-D obstacle; an axisymmetric scene takes planes and spheres",
        ))
    }

    fn contact_set(
        &self,
        dofs: Vec<Vec<usize>>,
        refs: Vec<Vec<f64>>,
        e: f64,
        mu: f64,
    ) -> Result<Box<dyn ContactSet>, Error> {
        round_set(
            dofs,
            refs,
            (&self.point, Some(&self.axis)),
            (self.radius, self.side),
            (e, mu),
        )
    }

    /// The two end circles and eight generators over the box's extent along the axis.
    fn outline(&self, out: &mut Outline, view: &View, _dim: usize) {
        let (centre, size, radius) = (view.centre, view.size, self.radius);
        let (p, n) = (v3(&self.point), unit(v3(&self.axis)));
        let (a, b) = orthonormal(n);
        let t = dot(n, std::array::from_fn(|i| centre[i] - p[i]));
        let half = 0.75 * size;
        for s in [-1.0, 1.0] {
            let c: [f64; 3] = std::array::from_fn(|i| p[i] + (t + s * half) * n[i]);
            out.circle(c, a, b, radius, 96);
        }
        for k in 0..8 {
            let th = std::f64::consts::PI * k as f64 / 4.0;
            let r: [f64; 3] = std::array::from_fn(|i| radius * (th.cos() * a[i] + th.sin() * b[i]));
            out.segment(
                std::array::from_fn(|i| p[i] + r[i] + (t - half) * n[i]),
                std::array::from_fn(|i| p[i] + r[i] + (t + half) * n[i]),
            );
        }
    }
}
