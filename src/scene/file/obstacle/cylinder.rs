//! The infinite cylinder obstacle (3-D, or coaxial in an axisymmetric scene), outside or
//! inside (`type = "cylinder"`).

use super::*;

/// `type = "cylinder"`: an infinite cylinder: in 3-D, or in an axisymmetric scene the
/// cylinder about the axis of revolution (`point = [0, y]`, `axis = [0, 1]`), whose
/// section is the line `r = radius`.
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

    fn validate(&self, dim: usize, axisymmetric: bool) -> Result<(), Error> {
        if dim == 2 && axisymmetric {
            // coaxial: checked by `axisymmetric_problem`
            check_vector("point", &self.point, 2, false)?;
            check_vector("axis", &self.axis, 2, true)?;
            return require_positive("radius", self.radius).map(|_| ());
        }
        if dim != 3 {
            return Err(Error::invalid(
                "type",
                "cylinder",
                &format!(
                    "is a 3-D obstacle, or the coaxial cylinder of an axisymmetric scene; this \
                     scene is {dim}-D and not axisymmetric (use a sphere: a circle in 2-D)"
                ),
            ));
        }
        check_vector("point", &self.point, 3, false)?;
        check_vector("axis", &self.axis, 3, true)?;
        require_positive("radius", self.radius).map(|_| ())
    }

    /// Coaxial (axis along y through a point of the axis): the section's gap
    /// `±(|r| − R)` is the exact gap to the cylinder. Any other axis revolves into no
    /// cylinder.
    fn axisymmetric_problem(&self) -> Option<(&'static str, String, &'static str)> {
        if self.axis[0] != 0.0 {
            return Some((
                "axis",
                format!("{:?}", self.axis),
                "a cylinder of an axisymmetric scene is coaxial: its axis is the axis of \
                 revolution, [0.0, 1.0] (another axis revolves into no cylinder)",
            ));
        }
        (self.point[0] != 0.0).then(|| {
            (
                "point",
                format!("{:?}", self.point),
                "a cylinder of an axisymmetric scene is coaxial: its axis passes through \
                 the axis of revolution, give [0.0, y]",
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
            (&self.point, Some(&self.axis)),
            (self.radius, self.side),
            (e, mu),
        )
    }

    /// The two end circles and eight generators over the box's extent along the axis.
    fn outline(&self, out: &mut Outline, view: &View, dim: usize) {
        let (centre, size, radius) = (view.centre, view.size, self.radius);
        if dim == 2 {
            // the coaxial cylinder's section: the line r = radius along the axis
            let half = 0.75 * size;
            out.segment(
                [radius, centre[1] - half, 0.0],
                [radius, centre[1] + half, 0.0],
            );
            return;
        }
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
