//! Solid elements: patch tests, total mass, inverted cells, and the axial
//! eigenfrequencies of a free 3-D bar.

use signorini::linalg::{SpdFactor, spmv};
use signorini::model::MassKind;
use signorini::model::generate::{box_mesh, rectangle_mesh};
use signorini::model::solid::{
    CellKind, Formulation, Material, Mesh, assemble, assemble_with_contacts,
};

const STEEL: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
    model: signorini::model::solid::MaterialModel::LINEAR,
};

/// Moves interior nodes so the patch is irregular (boundary nodes stay put).
fn distort(mut mesh: Mesh, dim: usize) -> Mesh {
    let mut boundary = vec![false; mesh.points.len()];
    for set in mesh.node_sets.values() {
        for &v in set {
            boundary[v] = true;
        }
    }
    for (i, p) in mesh.points.iter_mut().enumerate() {
        if !boundary[i] {
            for (c, x) in p.iter_mut().take(dim).enumerate() {
                *x += 0.08 * (((i * 7 + c * 3) % 5) as f64 - 2.0) / 4.0;
            }
        }
    }
    mesh
}

fn cases() -> Vec<(CellKind, Formulation, Mesh)> {
    vec![
        (
            CellKind::Tri3,
            Formulation::PlaneStrain,
            rectangle_mesh(CellKind::Tri3, [3, 3], [1.0, 1.0]),
        ),
        (
            CellKind::Quad4,
            Formulation::PlaneStress { thickness: 0.1 },
            rectangle_mesh(CellKind::Quad4, [3, 3], [1.0, 1.0]),
        ),
        (
            CellKind::Tet4,
            Formulation::Solid,
            box_mesh(CellKind::Tet4, [2, 2, 2], [1.0, 1.0, 1.0]),
        ),
        (
            CellKind::Hex8,
            Formulation::Solid,
            box_mesh(CellKind::Hex8, [3, 3, 3], [1.0, 1.0, 1.0]),
        ),
    ]
}

#[test]
fn patch_test_constant_strain_is_in_equilibrium_at_interior_nodes() {
    for (kind, f, mesh) in cases() {
        let dim = f.dim();
        let mesh = distort(mesh, dim);
        let sys = assemble(&mesh, &STEEL, f, MassKind::Consistent).unwrap();
        // u = A x with a full (non-symmetric) gradient A: constant strain and rotation.
        let a = [
            [1e-3, 2e-4, -3e-4],
            [5e-4, -1e-3, 1e-4],
            [-2e-4, 3e-4, 7e-4],
        ];
        let mut u = vec![0.0; sys.ndof()];
        for (v, p) in mesh.points.iter().enumerate() {
            for i in 0..dim {
                u[v * dim + i] = (0..dim).map(|j| a[i][j] * p[j]).sum();
            }
        }
        let mut r = vec![0.0; sys.ndof()];
        spmv(sys.stiffness.as_ref(), &u, &mut r);
        let scale = r.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let mut boundary = vec![false; mesh.points.len()];
        for set in mesh.node_sets.values() {
            for &v in set {
                boundary[v] = true;
            }
        }
        // Interior nodes: the constant stress is self-equilibrated, so K u vanishes
        // there to rounding (relative to the boundary forces).
        for (v, b) in boundary.iter().enumerate() {
            if !b {
                for i in 0..dim {
                    assert!(
                        r[v * dim + i].abs() < 1e-10 * scale,
                        "{kind:?}: node {v}: {}",
                        r[v * dim + i]
                    );
                }
            }
        }
        // and the boundary forces balance
        for i in 0..dim {
            let s: f64 = (0..mesh.points.len()).map(|v| r[v * dim + i]).sum();
            assert!(s.abs() < 1e-10 * scale, "{kind:?}: net force {s}");
        }
    }
}

#[test]
fn total_mass_is_rho_v_for_every_element_and_mass_kind() {
    for (kind, f, mesh) in cases() {
        let mesh = distort(mesh, f.dim());
        let t = match f {
            Formulation::PlaneStress { thickness } => thickness,
            _ => 1.0,
        };
        for mass in [
            MassKind::Consistent,
            MassKind::Lumped,
            MassKind::Redistributed,
        ] {
            // redistributed: the x0 face carries no mass, the total is unchanged
            let contact = &mesh.node_sets["x0"];
            let sys = assemble_with_contacts(&mesh, &STEEL, f, mass, contact).unwrap();
            if mass == MassKind::Redistributed {
                let d = sys.mass.to_dense();
                let dim = f.dim();
                for &v in contact {
                    for i in 0..dim {
                        assert!(
                            d.row(v * dim + i).iter().all(|&x| x == 0.0),
                            "{kind:?}: node {v} keeps mass"
                        );
                    }
                }
            }
            // unit square or cube (distortion keeps the boundary): V = t·1
            let expected = STEEL.density * t;
            let rel = sys.total_mass() / expected - 1.0;
            assert!(rel.abs() < 1e-12, "{kind:?} {mass:?}: {rel}");
        }
    }
}

#[test]
fn inverted_cells_are_reported_with_their_index() {
    let mut mesh = box_mesh(CellKind::Hex8, [2, 1, 1], [2.0, 1.0, 1.0]);
    mesh.cells[1].1.swap(0, 1);
    let e = assemble(&mesh, &STEEL, Formulation::Solid, MassKind::Consistent).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("cell 1") && msg.contains("inverted"), "{msg}");
    let mut tri = rectangle_mesh(CellKind::Tri3, [1, 1], [1.0, 1.0]);
    tri.cells[0].1.swap(1, 2);
    let msg = assemble(&tri, &STEEL, Formulation::PlaneStrain, MassKind::Lumped)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("cell 0"), "{msg}");
    let mut nan = rectangle_mesh(CellKind::Quad4, [1, 1], [1.0, 1.0]);
    nan.points[2][0] = f64::NAN;
    let msg = assemble(&nan, &STEEL, Formulation::PlaneStrain, MassKind::Lumped)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("node 2"), "{msg}");
    let mut missing = rectangle_mesh(CellKind::Quad4, [1, 1], [1.0, 1.0]);
    missing.cells[0].1[3] = 99;
    let msg = assemble(&missing, &STEEL, Formulation::PlaneStrain, MassKind::Lumped)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("node 99"), "{msg}");
}

#[test]
fn free_bar_axial_frequencies_match_n_pi_c0_over_l() {
    // ν = 0 decouples the axial motion, which is then the 1-D rod: ω_n = nπ c0 / L.
    // 40 hex8 along L = 1 m: consistent-mass error (nπ/N)²/24 ≤ 0.23 % for n ≤ 3.
    let mat = Material {
        poisson: 0.0,
        ..STEEL
    };
    let a = 0.05;
    let mesh = box_mesh(CellKind::Hex8, [40, 1, 1], [1.0, a, a]);
    let sys = assemble(&mesh, &mat, Formulation::Solid, MassKind::Consistent).unwrap();
    let n = sys.ndof();
    // dense generalized eigenproblem K x = ω² M x through M = L Lᵀ
    let mut chol = SpdFactor::new(sys.mass.as_ref(), "M").unwrap();
    let k = sys.stiffness.to_dense();
    // A = L⁻¹ K L⁻ᵀ is similar to M⁻¹ K; form M⁻¹ K columns and symmetrize via
    // the Rayleigh quotient: use nalgebra's general eigenvalues of M⁻¹K instead.
    let mut minv_k = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut col = vec![0.0; n];
    for j in 0..n {
        for i in 0..n {
            col[i] = k[(i, j)];
        }
        chol.solve_in_place(&mut col);
        for i in 0..n {
            minv_k[(i, j)] = col[i];
        }
    }
    let eig = minv_k.complex_eigenvalues();
    let mut w: Vec<f64> = eig.iter().map(|z| z.re.max(0.0).sqrt()).collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    let c0 = (mat.young / mat.density).sqrt();
    for m in 1..=3 {
        let exact = m as f64 * std::f64::consts::PI * c0;
        let best = w
            .iter()
            .map(|x| (x / exact - 1.0).abs())
            .fold(f64::INFINITY, f64::min);
        assert!(best < 5e-3, "mode {m}: closest relative error {best}");
    }
}

/// The parallel assembly hands each task a range of columns and visits cells in order,
/// so `M` and `K` must be bitwise the same for 1 and 3 threads, and the same as the
/// element matrices summed one by one (to rounding: 1e-12 relative).
#[test]
fn parallel_assembly_is_independent_of_threads() {
    let mesh = distort(box_mesh(CellKind::Hex8, [5, 4, 3], [1.0, 0.8, 0.6]), 3);
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| assemble(&mesh, &STEEL, Formulation::Solid, MassKind::Consistent).unwrap())
    };
    let (one, three) = (with(1), with(3));
    assert_eq!(one.stiffness.val(), three.stiffness.val());
    assert_eq!(one.mass.val(), three.mass.val());
    // reference: dense sum of the element matrices
    let n = 3 * mesh.points.len();
    let mut k = vec![0.0; n * n];
    for (id, (kind, nodes)) in mesh.cells.iter().enumerate() {
        let x: Vec<[f64; 3]> = nodes.iter().map(|&v| mesh.points[v]).collect();
        let e =
            signorini::model::solid::element_matrices(id, *kind, &x, &STEEL, Formulation::Solid)
                .unwrap();
        for (a, &va) in nodes.iter().enumerate() {
            for (b, &vb) in nodes.iter().enumerate() {
                for i in 0..3 {
                    for j in 0..3 {
                        k[(3 * va + i) * n + 3 * vb + j] += e.k(3 * a + i, 3 * b + j);
                    }
                }
            }
        }
    }
    let s = one.stiffness.as_ref();
    let scale = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut seen = 0.0;
    for j in 0..n {
        for p in s.col_ptr()[j]..s.col_ptr()[j + 1] {
            let i = s.row_idx()[p];
            assert!(
                (s.val()[p] - k[i * n + j]).abs() <= 1e-12 * scale,
                "K({i},{j})"
            );
            seen += k[i * n + j].abs();
        }
    }
    // every nonzero of the dense sum is in the pattern
    let total: f64 = k.iter().map(|v| v.abs()).sum();
    assert!((seen - total).abs() <= 1e-12 * total);
}

/// Axisymmetric tri3 and quad4 (the ring `0.5 ≤ r ≤ 1`, `0 ≤ z ≤ 1`, interior nodes
/// moved): the uniform dilatation `u = ε (r, z)` has strains `ε_rr = ε_zz = ε_θθ = ε`
/// everywhere (the hoop strain `u_r / r` is exact because `u_r` is linear), so
/// `½ uᵀKu = ½·3(3λ + 2μ)ε²·V` with `V = π(1 − 0.25)·1`, and the mass is `ρV`, both to
/// rounding (the integrands are polynomials the rules integrate exactly on the
/// undistorted ring; on the distorted one, within 1e-12 for the mass of the straight-
/// sided cells and 1e-10 for the energy).
#[test]
fn axisymmetric_ring_dilatation_energy_and_mass() {
    for kind in [CellKind::Tri3, CellKind::Quad4] {
        for moved in [false, true] {
            let mut mesh = rectangle_mesh(kind, [4, 6], [0.5, 1.0]);
            if moved {
                mesh = distort(mesh, 2);
            }
            for p in mesh.points.iter_mut() {
                p[0] += 0.5;
            }
            let f = Formulation::Axisymmetric;
            let sys = assemble(&mesh, &STEEL, f, MassKind::Consistent).unwrap();
            let v = std::f64::consts::PI * (1.0 - 0.25);
            let rel = sys.total_mass() / (STEEL.density * v) - 1.0;
            assert!(rel.abs() < 1e-12, "{kind:?} moved {moved}: mass {rel:e}");
            let eps = 1e-4;
            let u: Vec<f64> = mesh
                .points
                .iter()
                .flat_map(|p| [eps * p[0], eps * p[1]])
                .collect();
            let mut ku = vec![0.0; u.len()];
            spmv(sys.stiffness.as_ref(), &u, &mut ku);
            let energy: f64 = 0.5 * u.iter().zip(&ku).map(|(a, b)| a * b).sum::<f64>();
            let (l, m) = STEEL.lame();
            let exact = 0.5 * 3.0 * (3.0 * l + 2.0 * m) * eps * eps * v;
            let rel = energy / exact - 1.0;
            assert!(rel.abs() < 1e-10, "{kind:?} moved {moved}: energy {rel:e}");
        }
    }
}

/// An axisymmetric mesh must lie in `x = r ≥ 0`; a node at `r < 0` is refused by name.
#[test]
fn axisymmetric_mesh_left_of_the_axis_is_refused() {
    let mut mesh = rectangle_mesh(CellKind::Quad4, [2, 2], [1.0, 1.0]);
    mesh.points[4][0] = -0.1;
    let e = assemble(
        &mesh,
        &STEEL,
        Formulation::Axisymmetric,
        MassKind::Consistent,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("node 4") && e.contains("r ≥ 0"), "{e}");
}
