//! The hex8 block on a rigid floor with friction, shared by the friction tests.

use signorini::integrators::Integrator;

/// The undamped block of issue 16 §1 (10 × 10 × 5 cm, E = 1e8 Pa, ν = 0, ρ = 1000 kg/m³,
/// 4 × 4 × 2 hex8 cells) launched at 1 m/s on a rigid plane with friction `mu`, as a
/// scene text with step `dt`, end `t_end`, scheme `kind` and θ `theta`.
pub fn undamped_block(dt: f64, t_end: f64, kind: &str, theta: f64, mu: f64) -> String {
    format!(
        r#"
[time]
dt = {dt:e}
t_end = {t_end}
[scheme]
kind = "{kind}"
theta = {theta}
[[bodies]]
name = "block"
mesh = {{ generator = "box", cell = "hex8", cells = [4, 4, 2], size = [0.1, 0.1, 0.05] }}
material = {{ young = 1e8, poisson = 0.0, density = 1000.0 }}
velocity = [1.0, 0.0, 0.0]
[loads]
gravity = [0.0, 0.0, -9.81]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
friction = {mu}
"#
    )
}

/// x-momentum `1ₓᵀ M v` and x-mass `1ₓᵀ M 1ₓ` of an integrator's state.
pub fn momentum_x(integ: &dyn Integrator) -> (f64, f64) {
    let sys = integ.system();
    let mut mv = vec![0.0; sys.ndof()];
    let ones: Vec<f64> = sys
        .component
        .iter()
        .map(|&c| if c == 0 { 1.0 } else { 0.0 })
        .collect();
    signorini::linalg::spmv(sys.mass.as_ref(), &integ.state().v, &mut mv);
    let p: f64 = mv.iter().zip(&ones).map(|(a, b)| a * b).sum();
    signorini::linalg::spmv(sys.mass.as_ref(), &ones, &mut mv);
    let m: f64 = mv.iter().zip(&ones).map(|(a, b)| a * b).sum();
    (p, m)
}
