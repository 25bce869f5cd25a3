//! Rigid multibody systems in minimal coordinates (issue 17 §3): the slider–crank of the
//! paper's sec. 6.3.1, after Flores, Leine and Glocker (Multibody Syst. Dyn. 23, 2010).
//!
//! Coordinates `q = (θ₁, θ₂, θ₃)`: the crank, connecting-rod and slider angles from the
//! x-axis. The crank turns about the origin, the rod is pinned to the crank's tip, the
//! slider's centre is the rod's tip `(x_s, y_s) = l₁(cos θ₁, sin θ₁) + l₂(cos θ₂, sin θ₂)`,
//! and the slider (length 2a, height 2b) moves between two guides at `y = ±d/2` with the
//! clearance `c = d/2 − b`. The crank's and rod's centres of mass are at their middles;
//! `J_i` are the moments of inertia about the centres of mass.
//!
//! Lagrange's equations, derived from the kinetic energy
//! `T = ½(J₁ + m₁l₁²/4)θ̇₁² + ½m₂|ẋ_{G2}|² + ½J₂θ̇₂² + ½m₃|ẋ_s|² + ½J₃θ̇₃²` and the potential
//! of gravity `V = (m₁/2 + m₂ + m₃) g l₁ sin θ₁ + (m₂/2 + m₃) g l₂ sin θ₂`, read
//! `M(q) q̈ + r(q, q̇) = Gλ` with, for `A = (m₂/2 + m₃) l₁ l₂` and `δ = θ₁ − θ₂`,
//!
//! - `M₁₁ = J₁ + (m₁/4 + m₂ + m₃) l₁²`, `M₂₂ = J₂ + (m₂/4 + m₃) l₂²`, `M₃₃ = J₃`,
//!   `M₁₂ = M₂₁ = A cos δ` (the only entry that depends on `q`);
//! - `r₁ = A sin δ θ̇₂² + B₁ cos θ₁`, `r₂ = −A sin δ θ̇₁² + B₂ cos θ₂`, `r₃ = 0`, with
//!   `B₁ = (m₁/2 + m₂ + m₃) g l₁`, `B₂ = (m₂/2 + m₃) g l₂` (gyroscopic and gravity terms);
//!
//! the same as Siconos' `SliderCrankPlugin.cpp`. The tangents `∂r/∂q` and `∂r/∂v` are
//! not symmetric, so `M̂ⁿ` is factored by LU ([`crate::integrators::structure`]). The
//! constant part of `M` is the system's mass matrix; `M₁₂(q)` is the part's
//! [`NonlinearPart::mass`].
//!
//! The four slider corners against the guides are [`crate::contact::slider::SliderCorners`].

use crate::error::{Error, require_in, require_positive};
use crate::model::LinearSystem;
use crate::model::system::NonlinearPart;

/// The slider–crank's geometry and inertia (module doc); defaults: the paper's Table 2.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SliderCrankParams {
    /// Crank length `l₁` (m).
    pub l1: f64,
    /// Connecting-rod length `l₂` (m).
    pub l2: f64,
    /// Half length of the slider `a` (m).
    pub a: f64,
    /// Half height of the slider `b` (m).
    pub b: f64,
    /// Clearance `c` between slider and guide (m); the guides are `d = 2(b + c)` apart.
    pub c: f64,
    /// Masses of crank, rod and slider (kg).
    pub m1: f64,
    /// Rod mass (kg).
    pub m2: f64,
    /// Slider mass (kg).
    pub m3: f64,
    /// Moments of inertia about the centres of mass (kg m²): crank.
    pub j1: f64,
    /// Rod (the paper's Table 2: 8.9e-4; Siconos' example: [`SICONOS_J2`]).
    pub j2: f64,
    /// Slider.
    pub j3: f64,
    /// Gravity, along −y (m/s²).
    pub gravity: f64,
}

/// The rod's moment of inertia in Siconos' slider–crank example (`SCConst.h`), against
/// the paper's 8.9e-4 (Table 2).
pub const SICONOS_J2: f64 = 5.9e-4;

impl Default for SliderCrankParams {
    fn default() -> Self {
        SliderCrankParams {
            l1: 0.1530,
            l2: 0.3060,
            a: 0.0500,
            b: 0.0250,
            c: 0.0010,
            m1: 0.0380,
            m2: 0.0380,
            m3: 0.0760,
            j1: 7.4e-5,
            j2: 8.9e-4,
            j3: 2.7e-6,
            gravity: 9.81,
        }
    }
}

impl SliderCrankParams {
    /// Checks every value (positive lengths, masses and inertias; gravity ≥ 0), naming
    /// the field under `prefix`.
    pub fn validate(&self, prefix: &str) -> Result<(), Error> {
        for (name, v) in [
            ("l1", self.l1),
            ("l2", self.l2),
            ("a", self.a),
            ("b", self.b),
            ("c", self.c),
            ("m1", self.m1),
            ("m2", self.m2),
            ("m3", self.m3),
            ("j1", self.j1),
            ("j2", self.j2),
            ("j3", self.j3),
        ] {
            require_positive(&format!("{prefix}{name}"), v)?;
        }
        require_in(&format!("{prefix}gravity"), self.gravity, 0.0, 1e6)?;
        Ok(())
    }

    /// `A = (m₂/2 + m₃) l₁ l₂` (module doc).
    fn coupling(&self) -> f64 {
        (0.5 * self.m2 + self.m3) * self.l1 * self.l2
    }

    /// `B₁`, `B₂` (module doc).
    fn gravity_moments(&self) -> (f64, f64) {
        (
            (0.5 * self.m1 + self.m2 + self.m3) * self.gravity * self.l1,
            (0.5 * self.m2 + self.m3) * self.gravity * self.l2,
        )
    }

    /// The guides' half distance `d/2 = b + c` (m).
    pub fn half_gap(&self) -> f64 {
        self.b + self.c
    }

    /// The system: the constant diagonal of `M` and the [`SliderCrank`] part.
    pub fn system(&self) -> Result<LinearSystem, Error> {
        self.validate("")?;
        let p = self;
        let diag = [
            p.j1 + (0.25 * p.m1 + p.m2 + p.m3) * p.l1 * p.l1,
            p.j2 + (0.25 * p.m2 + p.m3) * p.l2 * p.l2,
            p.j3,
        ];
        let mut sys = crate::model::point_mass::diagonal(&diag, &[0.0; 3])?;
        sys.add_nonlinear_part(std::sync::Arc::new(SliderCrank { p: *self }));
        Ok(sys)
    }

    /// Slider centre `(x_s, y_s)` at `q`.
    pub fn slider_centre(&self, q: &[f64]) -> (f64, f64) {
        (
            self.l1 * q[0].cos() + self.l2 * q[1].cos(),
            self.l1 * q[0].sin() + self.l2 * q[1].sin(),
        )
    }
}

/// The slider–crank's configuration-dependent mass, gyroscopic and gravity terms
/// (module doc).
#[derive(Clone, Debug)]
pub struct SliderCrank {
    p: SliderCrankParams,
}

impl NonlinearPart for SliderCrank {
    fn tangent_entries(&self) -> Vec<(usize, usize)> {
        vec![(0, 0), (1, 0), (0, 1), (1, 1)]
    }
    fn damping_entries(&self) -> Vec<(usize, usize)> {
        vec![(1, 0), (0, 1)]
    }
    fn mass_entries(&self) -> Vec<(usize, usize)> {
        vec![(1, 0), (0, 1)]
    }
    fn symmetric(&self) -> bool {
        false
    }
    fn evaluate(
        &self,
        q: &[f64],
        v: &[f64],
        force: &mut [f64],
        tangent: Option<&mut [f64]>,
        damping: Option<&mut [f64]>,
    ) -> Result<(), Error> {
        let a = self.p.coupling();
        let (b1, b2) = self.p.gravity_moments();
        let (sd, cd) = (q[0] - q[1]).sin_cos();
        let (s1, c1) = q[0].sin_cos();
        let (s2, c2) = q[1].sin_cos();
        let (w1, w2) = (v[0], v[1]);
        force[0] += a * sd * w2 * w2 + b1 * c1;
        force[1] += -a * sd * w1 * w1 + b2 * c2;
        if let Some(t) = tangent {
            // ∂r/∂q in the order of `tangent_entries`: (0,0), (1,0), (0,1), (1,1)
            t[0] = a * cd * w2 * w2 - b1 * s1;
            t[1] = -a * cd * w1 * w1;
            t[2] = -a * cd * w2 * w2;
            t[3] = a * cd * w1 * w1 - b2 * s2;
        }
        if let Some(d) = damping {
            // ∂r/∂v: (1,0), (0,1)
            d[0] = -2.0 * a * sd * w1;
            d[1] = 2.0 * a * sd * w2;
        }
        Ok(())
    }
    fn mass(&self, q: &[f64], values: &mut [f64]) {
        let m12 = self.p.coupling() * (q[0] - q[1]).cos();
        values[0] = m12;
        values[1] = m12;
    }
    fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64 {
        self.p.coupling() * (q[0] - q[1]).cos() * v[0] * v[1]
    }
    fn energy(&self, q: &[f64]) -> Result<f64, Error> {
        let (b1, b2) = self.p.gravity_moments();
        Ok(b1 * q[0].sin() + b2 * q[1].sin())
    }
    fn describe(&self) -> String {
        "slider–crank in minimal coordinates (M(q), gyroscopic and gravity terms)".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `r` and the tangents against central differences (relative error ≤ 1e-7, the
    /// differencing error at step 1e-6 on O(1) angles and rates).
    #[test]
    fn tangents_match_central_differences() {
        let part = SliderCrank {
            p: SliderCrankParams::default(),
        };
        let (q, v) = ([0.7, -0.3, 0.05], [150.0, -75.0, 0.1]);
        let r = |q: &[f64], v: &[f64]| {
            let mut f = [0.0; 3];
            part.evaluate(q, v, &mut f, None, None).unwrap();
            f
        };
        let (mut t, mut d) = ([0.0; 4], [0.0; 2]);
        let mut f = [0.0; 3];
        part.evaluate(&q, &v, &mut f, Some(&mut t), Some(&mut d))
            .unwrap();
        let eps = 1e-6;
        let fd = |j: usize, wrt_v: bool, i: usize| {
            let (mut qp, mut qm, mut vp, mut vm) = (q, q, v, v);
            if wrt_v {
                vp[j] += eps;
                vm[j] -= eps;
            } else {
                qp[j] += eps;
                qm[j] -= eps;
            }
            (r(&qp, &vp)[i] - r(&qm, &vm)[i]) / (2.0 * eps)
        };
        let scale = t.iter().chain(&d).fold(0.0_f64, |m, x| m.max(x.abs()));
        for (k, &(i, j)) in part.tangent_entries().iter().enumerate() {
            assert!(
                (t[k] - fd(j, false, i)).abs() <= 1e-7 * scale,
                "dr/dq {i} {j}"
            );
        }
        for (k, &(i, j)) in part.damping_entries().iter().enumerate() {
            assert!(
                (d[k] - fd(j, true, i)).abs() <= 1e-7 * scale,
                "dr/dv {i} {j}"
            );
        }
        // r is the gradient of V plus the gyroscopic terms: at rest, r = ∇V
        let f0 = r(&q, &[0.0; 3]);
        let e = |q: &[f64]| part.energy(q).unwrap();
        for (j, &fj) in f0.iter().enumerate() {
            let (mut qp, mut qm) = (q, q);
            qp[j] += eps;
            qm[j] -= eps;
            let g = (e(&qp) - e(&qm)) / (2.0 * eps);
            assert!((fj - g).abs() <= 1e-7 * f0[0].abs().max(1e-3), "dV/dq {j}");
        }
    }

    /// The gyroscopic terms are Lagrange's: the power of `r` without gravity equals
    /// `½ q̇ᵀ Ṁ q̇` (so that `d/dt(½q̇ᵀMq̇) = q̇ᵀ(Mq̈ + ½Ṁq̇)` and free motion conserves `T`).
    #[test]
    fn gyroscopic_power_is_half_the_mass_rate() {
        let p = SliderCrankParams {
            gravity: 0.0,
            ..SliderCrankParams::default()
        };
        let part = SliderCrank { p };
        let (q, v) = ([0.4, -1.1, 0.0], [150.0, -75.0, 0.0]);
        let mut f = [0.0; 3];
        part.evaluate(&q, &v, &mut f, None, None).unwrap();
        let power: f64 = f.iter().zip(&v).map(|(a, b)| a * b).sum();
        // Ṁ₁₂ = −A sin δ (θ̇₁ − θ̇₂); ½ q̇ᵀṀq̇ = Ṁ₁₂ θ̇₁ θ̇₂
        let m12_rate = -p.coupling() * (q[0] - q[1]).sin() * (v[0] - v[1]);
        let half = m12_rate * v[0] * v[1];
        // Lagrange: M q̈ = −r, so d/dt T = q̇ᵀMq̈ + ½q̇ᵀṀq̇ = −q̇ᵀr + ½q̇ᵀṀq̇ = 0
        assert!((power - half).abs() <= 1e-12 * half.abs(), "{power} {half}");
    }
}
