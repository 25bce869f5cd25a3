//! The impacting linear oscillator of eq. 8 in closed form: `m q̈ + c q̇ + k q = f` on
//! `q ≥ 0`, Newton's impact law `v⁺ = −e v⁻` at `q = 0` (eq. 6), underdamped.
//!
//! Between impacts `q = f/k + e^{−ζω s} (A cos ω_d s + B sin ω_d s)` with `ω² = k/m`,
//! `ζ = c / (2 m ω) < 1`, `ω_d = ω √(1 − ζ²)`. The next impact is the first root of
//! that expression: found by scanning the flight in steps of 1/400 of the damped
//! period for a sign change, then bisecting to the last bit. An impact with
//! `|v⁻| ≤ 1e-14` (or a contact that would be pushed into the line) ends in rest at
//! `q = 0` while `f ≤ 0`.

/// The closed-form impacting oscillator.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Oscillator {
    /// Mass `m` (kg).
    pub mass: f64,
    /// Damping `c` (N·s/m).
    pub damping: f64,
    /// Stiffness `k` (N/m).
    pub stiffness: f64,
    /// Constant force `f` (N).
    pub force: f64,
    /// Restitution `e`.
    pub restitution: f64,
    /// Initial position `q0 ≥ 0` (m).
    pub q0: f64,
    /// Initial velocity (m/s).
    pub v0: f64,
}

impl Oscillator {
    /// The study's example: `m = 1`, `k = 4π²` (period 1 s), `c = 0.2`, `f = 0`,
    /// `e = 1/2`, released from `q0 = 1` at rest: impacts near 0.25, 0.75, 1.25, … s.
    pub fn example() -> Self {
        Oscillator {
            mass: 1.0,
            damping: 0.2,
            stiffness: 4.0 * std::f64::consts::PI * std::f64::consts::PI,
            force: 0.0,
            restitution: 0.5,
            q0: 1.0,
            v0: 0.0,
        }
    }

    fn params(&self) -> (f64, f64, f64) {
        let w = (self.stiffness / self.mass).sqrt();
        let z = self.damping / (2.0 * self.mass * w);
        (w, z, w * (1.0 - z * z).sqrt())
    }

    /// State `s` after a flight that starts at `(q, v)`.
    fn flight(&self, q: f64, v: f64, s: f64) -> (f64, f64) {
        let (w, z, wd) = self.params();
        let qp = self.force / self.stiffness;
        let (a, b) = (q - qp, (v + z * w * (q - qp)) / wd);
        let ex = (-z * w * s).exp();
        let (c, si) = ((wd * s).cos(), (wd * s).sin());
        let x = ex * (a * c + b * si);
        let xd = ex * ((-z * w) * (a * c + b * si) + wd * (-a * si + b * c));
        (qp + x, xd)
    }

    /// Time to the next impact from `(q, v)`, or infinity (searched over 1000 periods).
    fn next_impact(&self, q: f64, v: f64) -> f64 {
        let (_, _, wd) = self.params();
        let ds = 2.0 * std::f64::consts::PI / wd / 400.0;
        let mut s0 = 0.0;
        let mut q0 = q;
        // leaving the line: skip the start point itself
        for i in 1..400_000 {
            let s1 = i as f64 * ds;
            let q1 = self.flight(q, v, s1).0;
            if q1 < 0.0 || (q0 > 0.0 && q1 == 0.0) {
                let (mut lo, mut hi) = (s0, s1);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    if self.flight(q, v, mid).0 > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return hi;
            }
            s0 = s1;
            q0 = q1;
        }
        f64::INFINITY
    }

    /// Impact times in `(0, t_max]`, at most `cap`.
    pub fn impact_times(&self, t_max: f64, cap: usize) -> Vec<f64> {
        let mut out = Vec::new();
        let (mut t, mut q, mut v) = (0.0, self.q0, self.v0);
        while out.len() < cap {
            let s = self.next_impact(q, v);
            if t + s > t_max {
                break;
            }
            t += s;
            out.push(t);
            let vm = self.flight(q, v, s).1;
            if vm.abs() <= 1e-14 {
                break;
            }
            (q, v) = (0.0, -self.restitution * vm);
        }
        out
    }

    /// The flights up to `t_max`, computed once, for evaluating many times.
    pub fn flights(&self, t_max: f64) -> Flights {
        let mut starts = vec![(0.0, self.q0, self.v0)];
        let mut rest = None;
        let (mut t, mut q, mut v) = (0.0, self.q0, self.v0);
        loop {
            let s = self.next_impact(q, v);
            if t + s > t_max {
                break;
            }
            let vm = self.flight(q, v, s).1;
            t += s;
            if vm.abs() <= 1e-14 && self.force <= 0.0 {
                rest = Some(t);
                break;
            }
            (q, v) = (0.0, -self.restitution * vm);
            starts.push((t, q, v));
        }
        Flights {
            osc: *self,
            starts,
            rest,
        }
    }

    /// Position and (right-limit) velocity at `t`.
    pub fn state(&self, t: f64) -> (f64, f64) {
        let (mut t0, mut q, mut v) = (0.0, self.q0, self.v0);
        loop {
            let s = self.next_impact(q, v);
            if t0 + s > t {
                return self.flight(q, v, t - t0);
            }
            let vm = self.flight(q, v, s).1;
            t0 += s;
            if vm.abs() <= 1e-14 && self.force <= 0.0 {
                return (0.0, 0.0);
            }
            (q, v) = (0.0, -self.restitution * vm);
        }
    }
}

/// Precomputed flights of an [`Oscillator`] (start time, position, velocity).
#[derive(Clone, Debug)]
pub struct Flights {
    osc: Oscillator,
    starts: Vec<(f64, f64, f64)>,
    rest: Option<f64>,
}

impl Flights {
    /// Position and (right-limit) velocity at `t` (within the computed horizon).
    pub fn at(&self, t: f64) -> (f64, f64) {
        if self.rest.is_some_and(|r| t >= r) {
            return (0.0, 0.0);
        }
        let i = self.starts.partition_point(|s| s.0 <= t).max(1) - 1;
        let (t0, q, v) = self.starts[i];
        self.osc.flight(q, v, t - t0)
    }
    /// Impact times.
    pub fn impacts(&self) -> Vec<f64> {
        self.starts[1..].iter().map(|s| s.0).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Undamped, e = 1/2: every flight is half a period (0.5 s) after the first quarter
    /// (0.25 s), and each rebound halves the amplitude.
    #[test]
    fn undamped_flights_are_half_periods() {
        let o = Oscillator {
            damping: 0.0,
            ..Oscillator::example()
        };
        let t = o.impact_times(2.0, 10);
        let want = [0.25, 0.75, 1.25, 1.75];
        assert_eq!(t.len(), 4);
        for (a, b) in t.iter().zip(want) {
            assert!((a - b).abs() < 1e-13, "{t:?}");
        }
        // after the first impact v⁺ = π (= e · 2π), amplitude v⁺/ω = 1/2
        let (q, v) = o.state(0.5);
        assert!((q - 0.5).abs() < 1e-12 && v.abs() < 1e-12, "{q} {v}");
        let f = o.flights(2.0);
        assert_eq!(f.impacts(), t);
        for s in [0.1, 0.5, 0.9, 1.6] {
            assert_eq!(f.at(s), o.state(s));
        }
    }

    /// Damped: the closed form satisfies the equation of motion between impacts
    /// (finite-difference residual of m q̈ + c q̇ + k q − f, relative 1e-6).
    #[test]
    fn damped_flight_solves_the_ode() {
        let o = Oscillator::example();
        let (t, d) = (0.1, 1e-5);
        let q = |t: f64| o.state(t).0;
        let acc = (q(t + d) - 2.0 * q(t) + q(t - d)) / (d * d);
        let vel = o.state(t).1;
        let r = o.mass * acc + o.damping * vel + o.stiffness * q(t) - o.force;
        assert!(r.abs() < 1e-6 * o.stiffness, "residual {r}");
        assert!(((q(t + d) - q(t - d)) / (2.0 * d) - vel).abs() < 1e-6);
    }
}
