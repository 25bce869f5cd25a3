//! The bouncing ball of eq. 7 in closed form (Ballard's example): a point of mass `m`
//! on the half-line `q ≥ 0` under a constant force `f`, with Newton's impact law
//! `v⁺ = −e v⁻` (eq. 6) at `q = 0`.
//!
//! Between impacts the motion is a parabola with acceleration `a = f/m`. With `a < 0`
//! and `0 ≤ e < 1`, the flight times after the first impact form a geometric sequence
//! (`τ_{k+1} = e τ_k`, `τ_1 = 2 v⁺_1/|a|`), so the impacts accumulate at
//! `t∞ = t_1 + τ_1/(1 − e)` and the ball rests on the line afterwards with the reaction
//! `−f`. For `f = −2, m = 1, e = 1/2, q0 = 1, v0 = 0`: impacts at 1, 2, 2.5, 2.75, …,
//! `t∞ = 3` (DESIGN.md §7).

/// The closed-form bouncing ball.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BouncingBall {
    /// Initial height `q0 ≥ 0` (m).
    pub q0: f64,
    /// Initial velocity `v0` (m/s).
    pub v0: f64,
    /// Constant force `f` (N).
    pub force: f64,
    /// Mass `m` (kg).
    pub mass: f64,
    /// Restitution `e ∈ [0, 1]`.
    pub restitution: f64,
}

impl BouncingBall {
    /// Ballard's example: `f = −2, m = 1, e = 1/2, q0 = 1, v0 = 0`.
    pub fn ballard() -> Self {
        BouncingBall {
            q0: 1.0,
            v0: 0.0,
            force: -2.0,
            mass: 1.0,
            restitution: 0.5,
        }
    }

    fn accel(&self) -> f64 {
        self.force / self.mass
    }

    /// Time until `q + v s + a s²/2` reaches 0 from `q ≥ 0` (the smallest `s > 0`), or
    /// infinity.
    fn time_to_ground(q: f64, v: f64, a: f64) -> f64 {
        if a == 0.0 {
            return if v < 0.0 { -q / v } else { f64::INFINITY };
        }
        let disc = v * v - 2.0 * a * q;
        if disc < 0.0 {
            return f64::INFINITY;
        }
        let s = (-v - disc.sqrt()) / a;
        if s > 0.0 { s } else { f64::INFINITY }
    }

    /// The accumulation time `t∞` of the impacts, if they accumulate (`a < 0`, `e < 1`).
    pub fn accumulation_time(&self) -> Option<f64> {
        let a = self.accel();
        if a >= 0.0 || self.restitution >= 1.0 {
            return None;
        }
        let t1 = Self::time_to_ground(self.q0, self.v0, a);
        let v_plus = -self.restitution * (self.v0 + a * t1);
        Some(t1 + 2.0 * v_plus / -a / (1.0 - self.restitution))
    }

    /// Impact times in `(0, t_max]`, in order (at most `cap` of them; the sequence is
    /// infinite before an accumulation).
    pub fn impact_times(&self, t_max: f64, cap: usize) -> Vec<f64> {
        let a = self.accel();
        let (mut t, mut q, mut v) = (0.0, self.q0, self.v0);
        let mut out = Vec::new();
        while out.len() < cap {
            let s = Self::time_to_ground(q, v, a);
            if !s.is_finite() || t + s > t_max || (q == 0.0 && v == 0.0) {
                break;
            }
            t += s;
            out.push(t);
            v = -self.restitution * (v + a * s);
            q = 0.0;
        }
        out
    }

    /// Position and (right-limit) velocity at time `t`.
    pub fn state(&self, t: f64) -> (f64, f64) {
        let a = self.accel();
        if let Some(tinf) = self.accumulation_time()
            && t >= tinf
        {
            return (0.0, 0.0);
        }
        let (mut t0, mut q, mut v) = (0.0, self.q0, self.v0);
        loop {
            let s = Self::time_to_ground(q, v, a);
            if t0 + s > t || !s.is_finite() {
                let d = t - t0;
                return (q + v * d + 0.5 * a * d * d, v + a * d);
            }
            t0 += s;
            v = -self.restitution * (v + a * s);
            q = 0.0;
            if v == 0.0 && a <= 0.0 {
                return (0.0, 0.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ballard_impacts_accumulate_at_three() {
        let b = BouncingBall::ballard();
        let t = b.impact_times(2.99, 6);
        assert_eq!(t, vec![1.0, 2.0, 2.5, 2.75, 2.875, 2.9375]);
        assert_eq!(b.accumulation_time(), Some(3.0));
        assert_eq!(b.state(0.5), (0.75, -1.0));
        assert_eq!(b.state(1.5), (0.25, 0.0));
        assert_eq!(b.state(3.5), (0.0, 0.0));
    }

    #[test]
    fn elastic_ball_bounces_forever_with_period_two() {
        let b = BouncingBall {
            restitution: 1.0,
            ..BouncingBall::ballard()
        };
        assert_eq!(b.accumulation_time(), None);
        assert_eq!(b.impact_times(10.0, 100), vec![1.0, 3.0, 5.0, 7.0, 9.0]);
        let (q, v) = b.state(4.0);
        assert!((q - 1.0).abs() < 1e-15 && v.abs() < 1e-15);
    }
}
