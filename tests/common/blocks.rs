//! The hex8 block on a rigid floor with friction, shared by the friction tests, and the
//! two hex8 cubes meeting over a face, shared by the contact-zone tests.

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

/// The summed normal impulse `ΣP_N` (N·s) and the magnitude of the summed tangential
/// force `|ΣP_T| / h` (N, the tangential impulses summed as vectors of the tangent plane:
/// the contacts share one frame, as on a plane or a flat interface between bodies).
pub fn contact_sums(s: &signorini::integrators::State, h: f64) -> (f64, f64) {
    let (td, nc) = (s.tangent_dim, s.impulse.len());
    let pn: f64 = s.impulse.iter().sum();
    let ft = (0..td)
        .map(|j| {
            (0..nc)
                .map(|c| s.tangent_impulse[c * td + j])
                .sum::<f64>()
                .powi(2)
        })
        .sum::<f64>()
        .sqrt()
        / h;
    (pn, ft)
}

/// The checks of `meshes/pushed_block.toml` (the 0.5 kg block, μ = 0.3, pushed along x
/// by a force ramped from 0 at t = 0.1 s to 3 N at 1.1 s), run to `t_end` on whatever
/// floor `integ` has: ΣN = m g to 1e-3 from t = 0.1 s; the friction equals the push
/// within 1 % and stays inside the cone over [0.15, 0.55] s; |ΣT| = μ ΣN within 1 % from
/// 0.62 s; and the slide starts (|ΣT| ≥ 0.99 μ ΣN) within 1 % of t* = 0.1 + μ m g / 3 N.
pub fn check_pushed(integ: &mut dyn Integrator, label: &str, t_end: f64) {
    const G: f64 = 9.81;
    let (mu, m) = (0.3, 0.5);
    let t_star = 0.1 + mu * m * G / 3.0;
    let h = integ.dt();
    let mut reached = None;
    while integ.state().time < t_end - 1e-12 {
        integ.prepare().unwrap();
        let st = integ.step().unwrap();
        assert_eq!(st.caps_hit, 0, "{label}");
        let s = integ.state();
        let t = s.time;
        let (pn, ft) = contact_sums(s, h);
        let push = 3.0 * (t - 0.1).clamp(0.0, 1.0);
        // ΣN = m g once settled (Moreau–Jean's contacts activate over the first steps)
        if t >= 0.1 {
            assert!(
                (pn / h / (m * G) - 1.0).abs() < 1e-3,
                "{label} t = {t}: ΣN/mg = {}",
                pn / h / (m * G)
            );
        }
        if (0.15..=0.55).contains(&t) {
            assert!(
                (ft / push - 1.0).abs() < 0.01,
                "{label} t = {t}: friction {ft} N, push {push} N"
            );
            assert!(
                ft < mu * pn / h,
                "{label} t = {t}: beyond the cone while sticking"
            );
        }
        if t >= 0.62 {
            assert!(
                (ft / (mu * pn / h) - 1.0).abs() < 0.01,
                "{label} t = {t}: |ΣT|/μΣN = {}",
                ft / (mu * pn / h)
            );
        }
        if reached.is_none() && ft >= 0.99 * mu * pn / h {
            reached = Some(t);
        }
    }
    let t = reached.expect("never slid");
    eprintln!("{label}: slides from {t} s (analytic {t_star} s)");
    assert!(
        (t / t_star - 1.0).abs() < 0.01,
        "{label}: slides from {t} s, analytic {t_star} s"
    );
}

/// Two 8³-cell hex8 cubes (0.1 m, E = 1e7 Pa, ν = 0.3, ρ = 1000 kg/m³) meeting over a
/// full face, `benches/getfem_two_blocks.py`'s problem at N = 8: the lower one held on its
/// base, the upper one launched down at 1 m/s, 81 node-to-surface contacts; Algorithm 2
/// at h = 1e-5 s until `t_end`, Delassus storage `delassus`.
pub fn two_cubes(t_end: f64, delassus: &str) -> String {
    format!(
        r#"
[time]
dt = 1e-5
t_end = {t_end:e}
[scheme]
kind = "combined-projection"
delassus = "{delassus}"
[[bodies]]
name = "lower"
mesh = {{ generator = "box", cell = "hex8", cells = [8, 8, 8], size = [0.1, 0.1, 0.1] }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
fixed = ["z0"]
[[bodies]]
name = "upper"
mesh = {{ generator = "box", cell = "hex8", cells = [8, 8, 8], size = [0.1, 0.1, 0.1], origin = [0.0, 0.0, 0.1] }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
velocity = [0.0, 0.0, -1.0]
[[contacts]]
body = "upper"
nodes = "z0"
target = {{ body = "lower", surface = "z1" }}
"#
    )
}

/// Frictionless contacts of the 3-D nodes `face` (dofs `3v .. 3v + 3`) with a plane of
/// normal `z`, at the signed offset `offset` of `NodesOnPlane` (−1e-4: a 1e-4 m gap).
pub fn floor_contacts(
    face: &[usize],
    points: &[[f64; 3]],
    offset: f64,
) -> Box<dyn signorini::contact::ContactSet> {
    Box::new(
        signorini::contact::plane::NodesOnPlane::new(
            face.iter()
                .map(|&v| vec![3 * v, 3 * v + 1, 3 * v + 2])
                .collect(),
            face.iter().map(|&v| points[v].to_vec()).collect(),
            vec![0.0, 0.0, 1.0],
            offset,
            0.0,
        )
        .unwrap(),
    )
}
