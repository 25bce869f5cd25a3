//! Closed-form references.
//!
//! [`ImpactingBar`]: an elastic bar of length `L` hitting a rigid wall with velocity
//! `v0` (sec. 6.2, after Doyen–Ern–Piperno): the contact force is constant,
//! `r = E S |v0| / c0` with `c0 = √(E/ρ)`, for `T = 2L/c0`; the bar then leaves with
//! `−v0` (all its momentum reversed), so the total impulse is `2 ρ S L |v0|`.
//!
//! [`ball::BouncingBall`]: the bouncing ball of eq. 7 (Ballard's example).
//! [`oscillator::Oscillator`]: the impacting linear oscillator of eq. 8.

pub mod ball;
pub mod oscillator;

/// The analytic impacting bar.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpactingBar {
    /// Length `L` (m).
    pub length: f64,
    /// Cross-section `S` (m²).
    pub area: f64,
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Density `ρ` (kg/m³).
    pub density: f64,
    /// Impact velocity `v0` (m/s, towards the wall: negative).
    pub velocity: f64,
}

impl ImpactingBar {
    /// The reference bar (sec. 6.2, Table 1 with `S = π·10⁻⁴ m²`, DESIGN.md §7): `L = 1 m`,
    /// `E = 210 GPa`, `ρ = 7800 kg/m³`, `v0 = −0.1 m/s`.
    pub const REFERENCE: ImpactingBar = ImpactingBar {
        length: 1.0,
        area: std::f64::consts::PI * 1e-4,
        young: 210e9,
        density: 7800.0,
        velocity: -0.1,
    };

    /// `c0 = √(E/ρ)` (m/s).
    pub fn wave_speed(&self) -> f64 {
        (self.young / self.density).sqrt()
    }
    /// `E S |v0| / c0` (N).
    pub fn contact_force(&self) -> f64 {
        self.young * self.area * self.velocity.abs() / self.wave_speed()
    }
    /// `2 L / c0` (s).
    pub fn contact_duration(&self) -> f64 {
        2.0 * self.length / self.wave_speed()
    }
    /// `2 ρ S L |v0|` (N·s).
    pub fn total_impulse(&self) -> f64 {
        2.0 * self.density * self.area * self.length * self.velocity.abs()
    }
    /// Centre-of-mass velocity after release, `−v0` (m/s).
    pub fn release_velocity(&self) -> f64 {
        -self.velocity
    }
    /// The displacement `u(x, t)` (m) of the point at distance `x` from the impacting end
    /// (the bar touches the wall at `t = 0`). The compression front reaches `x` at
    /// `x/c0` and stops it; the unloading front reflected at the free end reaches it at
    /// `(2L − x)/c0` and sends it back at `−v0`, which it keeps after release at `2L/c0`
    /// (the bar then moves rigidly, stress-free):
    /// `u = v0 t` before the first front, `v0 x/c0` between them, `v0 x/c0 − v0 (t −
    /// (2L − x)/c0)` after the second.
    pub fn displacement(&self, x: f64, t: f64) -> f64 {
        let c0 = self.wave_speed();
        let v0 = self.velocity;
        let (t1, t2) = (x / c0, (2.0 * self.length - x) / c0);
        if t <= t1 {
            v0 * t
        } else if t <= t2 {
            v0 * t1
        } else {
            v0 * t1 - v0 * (t - t2)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_bar_matches_design_numbers() {
        let b = ImpactingBar::REFERENCE;
        // DESIGN.md §7: c0 = 5188.745 m/s, T = 3.8545e-4 s, r = 1271.472 N (printed digits)
        assert!((b.wave_speed() - 5188.745).abs() < 5e-4);
        assert!((b.contact_duration() - 3.8545e-4).abs() < 5e-9);
        assert!((b.contact_force() - 1271.472).abs() < 5e-4);
    }

    #[test]
    fn displacement_is_continuous_and_ends_stress_free() {
        let b = ImpactingBar::REFERENCE;
        let (c0, t_end) = (b.wave_speed(), b.contact_duration());
        // the contact end never moves during contact; the free end turns at L/c0, where
        // it has moved v0 L / c0, and is back at 0 at release
        assert_eq!(b.displacement(0.0, 0.5 * t_end), 0.0);
        let tip = b.displacement(1.0, 1.0 / c0);
        assert!((tip - (-0.1 / c0)).abs() < 1e-20, "{tip}");
        for x in [0.0, 0.25, 0.5, 1.0] {
            // at release every point is back at u = 0 (uniform zero strain), and the
            // whole bar then moves at −v0
            assert!(b.displacement(x, t_end).abs() < 1e-19, "x = {x}");
            let later = b.displacement(x, t_end + 1e-4);
            assert!((later - 1e-5).abs() < 1e-18, "x = {x}: {later}");
            // continuous at both fronts
            for t in [x / c0, (2.0 - x) / c0] {
                let (a, c) = (
                    b.displacement(x, t * (1.0 - 1e-12)),
                    b.displacement(x, t * (1.0 + 1e-12)),
                );
                assert!((a - c).abs() < 1e-15, "x = {x}, t = {t}");
            }
        }
    }
}
