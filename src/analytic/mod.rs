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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_bar_matches_design_numbers() {
        let b = ImpactingBar {
            length: 1.0,
            area: std::f64::consts::PI * 1e-4,
            young: 210e9,
            density: 7800.0,
            velocity: -0.1,
        };
        // DESIGN.md §7: c0 = 5188.745 m/s, T = 3.8545e-4 s, r = 1271.472 N (printed digits)
        assert!((b.wave_speed() - 5188.745).abs() < 5e-4);
        assert!((b.contact_duration() - 3.8545e-4).abs() < 5e-9);
        assert!((b.contact_force() - 1271.472).abs() < 5e-4);
    }
}
