//! The plane obstacle: the half-space `n·(x − p) ≥ 0` (`type = "plane"`).

use super::*;

/// `type = "plane"`: the half-space `n·(x − p) ≥ 0`.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlaneSpec {
    /// Name used by contacts.
    pub name: String,
    /// A point of the plane.
    pub point: Vec<f64>,
    /// Normal towards the admissible side.
    pub normal: Vec<f64>,
}

impl ObstacleShape for PlaneSpec {
    fn name(&self) -> &str {
        &self.name
    }

    fn validate(&self, dim: usize, _axisymmetric: bool) -> Result<(), Error> {
        check_vector("point", &self.point, dim, false)?;
        check_vector("normal", &self.normal, dim, true)
    }

    /// A line normal to the axis revolves into a plane; a line parallel to it, at
    /// `r = point[0] > 0`, into a coaxial cylinder (a shaft for `normal = [1, 0]`, a bore
    /// for `[-1, 0]`): the section's gap `±(r − r₀)` is the exact gap to it, and its
    /// tangent (along the axis) a tangent of the cylinder. An oblique line revolves into
    /// a cone, whose gap the line gives only where its foot lies at r ≥ 0: refused.
    fn axisymmetric_problem(&self) -> Option<(&'static str, String, &'static str)> {
        let (nr, ny) = (self.normal[0], self.normal[1]);
        if nr == 0.0 {
            return None;
        }
        if ny != 0.0 {
            return Some((
                "normal",
                format!("{:?}", self.normal),
                "an oblique line revolves into a cone, whose gap the section's line does not \
                 give exactly: give [0.0, ±1.0] (a plane normal to the axis) or [±1.0, 0.0] \
                 (a line parallel to it: a coaxial cylinder of radius point[0])",
            ));
        }
        (self.point[0] <= 0.0).then(|| {
            (
                "point",
                format!("{:?}", self.point),
                "a line parallel to the axis (normal [±1.0, 0.0]) revolves into a coaxial \
                 cylinder of radius point[0] = r, which must be > 0",
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
        let (point, normal) = (&self.point, &self.normal);
        let offset = point.iter().zip(normal).map(|(p, n)| p * n).sum::<f64>();
        if point.len() != normal.len() {
            return Err(Error::invalid(
                "point",
                format!("{point:?}"),
                "needs as many components as normal",
            ));
        }
        Ok(Box::new(
            NodesOnPlane::new(dofs, refs, normal.clone(), offset, e)?.with_friction(mu)?,
        ))
    }

    fn plane(&self) -> Option<(Vec<f64>, f64)> {
        let norm = self.normal.iter().map(|x| x * x).sum::<f64>().sqrt();
        let n: Vec<f64> = self.normal.iter().map(|x| x / norm).collect();
        let c = self.point.iter().zip(&n).map(|(p, n)| p * n).sum();
        Some((n, c))
    }

    /// A square (3-D) or a segment (2-D) around the projection of the box centre.
    fn outline(&self, out: &mut Outline, view: &View, dim: usize) {
        let (centre, size) = (view.centre, view.size);
        let (p, n) = (v3(&self.point), unit(v3(&self.normal)));
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
}
