//! The sphere obstacle (a circle in 2-D), outside or inside (`type = "sphere"`).

use super::*;

/// `type = "sphere"`: a sphere (circle in 2-D).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    /// Name used by contacts.
    pub name: String,
    /// Centre.
    pub center: Vec<f64>,
    /// Radius (m).
    pub radius: f64,
    /// `outside` (an obstacle, default) or `inside` (a container).
    #[serde(default = "outside")]
    pub side: Side,
}

impl ObstacleShape for SphereSpec {
    fn name(&self) -> &str {
        &self.name
    }

    fn validate(&self, dim: usize, _axisymmetric: bool) -> Result<(), Error> {
        check_vector("center", &self.center, dim, false)?;
        require_positive("radius", self.radius).map(|_| ())
    }

    fn axisymmetric_problem(&self) -> Option<(&'static str, String, &'static str)> {
        self.center.first().is_some_and(|&c| c != 0.0).then(|| {
            (
                "center",
                format!("{:?}", self.center),
                "a sphere of revolution is centred on the axis: give [0.0, y]",
            )
        })
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
            (&self.center, None),
            (self.radius, self.side),
            (e, mu),
        )
    }

    /// Three great circles (one circle in 2-D).
    fn outline(&self, out: &mut Outline, _view: &View, dim: usize) {
        let c = v3(&self.center);
        let e = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        out.circle(c, e[0], e[1], self.radius, 96);
        if dim == 3 {
            out.circle(c, e[1], e[2], self.radius, 96);
            out.circle(c, e[0], e[2], self.radius, 96);
        }
    }
}
