//! Reading the committed meshes, written by the real tools (`meshes/make_meshes.py`:
//! gmsh 4.15.2 and meshio 5.3.5). The expected counts are what meshio reports for the
//! same files; every bad-mesh class gets a clear error.

use std::path::{Path, PathBuf};

use signorini::io::mesh::read_mesh;
use signorini::model::MassKind;
use signorini::model::solid::{CellKind, Formulation, Material, assemble};

fn mesh_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(name)
}

#[test]
fn committed_meshes_have_the_counts_meshio_reports() {
    for (file, points, kind, cells, sets) in [
        (
            "ball.msh",
            208,
            CellKind::Tet4,
            672,
            vec![("ball", 208), ("surface", 167)],
        ),
        (
            "ball_binary.msh",
            208,
            CellKind::Tet4,
            672,
            vec![("ball", 208), ("surface", 167)],
        ),
        (
            "disk.msh",
            123,
            CellKind::Tri3,
            212,
            vec![("disk", 123), ("rim", 32)],
        ),
        (
            "disk_binary.msh",
            123,
            CellKind::Tri3,
            212,
            vec![("disk", 123), ("rim", 32)],
        ),
        ("plate.vtu", 27, CellKind::Quad4, 16, vec![("bottom", 9)]),
        ("plate.vtk", 27, CellKind::Quad4, 16, vec![("bottom", 9)]),
    ] {
        let m = read_mesh(&mesh_path(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(m.points.len(), points, "{file}");
        assert_eq!(m.cells.len(), cells, "{file}");
        assert!(m.cells.iter().all(|(k, _)| *k == kind), "{file}");
        for (name, n) in sets {
            assert_eq!(m.node_sets[name].len(), n, "{file}: set {name}");
        }
    }
    // the binary file holds the same mesh as the ASCII one (whose coordinates are
    // printed with 16 significant digits: equal to 1e-15 relative)
    for (x, y) in [
        ("ball.msh", "ball_binary.msh"),
        ("disk.msh", "disk_binary.msh"),
        ("plate.vtu", "plate.vtk"),
    ] {
        let a = read_mesh(&mesh_path(x)).unwrap();
        let b = read_mesh(&mesh_path(y)).unwrap();
        assert!(
            a.cells == b.cells && a.node_sets == b.node_sets,
            "{x} vs {y}: topology differs"
        );
        let d = a
            .points
            .iter()
            .zip(&b.points)
            .flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs()))
            .fold(0.0, f64::max);
        assert!(d <= 1e-15, "{x} vs {y}: coordinates differ by {d}");
    }
}

/// Every `.vtu` layout VTK and meshio write holds the same plate as `meshes/plate.vtu`
/// (meshio's default: inline binary, zlib, UInt32 headers), read by our own reader:
/// meshio's ascii and uncompressed binary; VTK's raw appended data (zlib with UInt64
/// headers, and uncompressed), base64 appended data, big-endian inline binary with
/// UInt64 headers, and ascii with `InformationKey`s inside the arrays
/// (`tests/data/vtu/make.py` wrote them with VTK 9.x and meshio 5.3.5). Binary layouts
/// hold the same doubles (equal bit for bit); ascii prints at least 11 significant
/// digits (VTK: `0.20615528128`), so 1e-10 there.
#[test]
fn every_vtu_layout_reads_the_same_plate() {
    let reference = read_mesh(&mesh_path("plate.vtu")).unwrap();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtu");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("vtu") {
            continue;
        }
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        let m = read_mesh(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(m.cells, reference.cells, "{name}: cells");
        assert_eq!(
            m.node_sets["bottom"], reference.node_sets["bottom"],
            "{name}"
        );
        let tol = if name.contains("ascii") { 1e-10 } else { 0.0 };
        let d = m
            .points
            .iter()
            .zip(&reference.points)
            .flat_map(|(p, q)| p.iter().zip(q).map(|(u, v)| (u - v).abs()))
            .fold(0.0, f64::max);
        assert!(
            m.points.len() == reference.points.len() && d <= tol,
            "{name}: coordinates differ by {d}"
        );
        n += 1;
    }
    assert_eq!(n, 7, "the seven layouts are found");
}

#[test]
fn ball_mesh_has_the_mass_of_its_polyhedron() {
    let m = read_mesh(&mesh_path("ball.msh")).unwrap();
    let mat = Material {
        young: 1e7,
        poisson: 0.3,
        density: 1000.0,
        model: signorini::model::solid::MaterialModel::LINEAR,
    };
    let sys = assemble(&m, &mat, Formulation::Solid, MassKind::Lumped).unwrap();
    // Every tet has positive orientation (assembly checks it); the inscribed
    // polyhedron of a 0.025 m mesh on R = 0.05 m holds 90–100 % of (4/3)πR³.
    let sphere = 1000.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.05f64.powi(3);
    let ratio = sys.total_mass() / sphere;
    assert!(ratio > 0.9 && ratio <= 1.0, "{ratio}");
}

fn write(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("signorini-badmesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const HEAD: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";

#[test]
fn bad_meshes_are_rejected_with_what_is_wrong() {
    let nodes = "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n";
    let cases = [
        (
            "missing_node.msh",
            format!("{HEAD}{nodes}$Elements\n1\n1 4 2 1 1 1 2 3 9\n$EndElements\n"),
            "node tag 9",
        ),
        (
            "prism.msh",
            format!("{HEAD}{nodes}$Elements\n1\n1 6 2 1 1 1 2 3 4 1 2\n$EndElements\n"),
            "unsupported element type",
        ),
        (
            "nan.msh",
            format!(
                "{HEAD}$Nodes\n4\n1 0 0 0\n2 nan 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n"
            ),
            "non-finite",
        ),
        (
            "empty.msh",
            format!("{HEAD}{nodes}$Elements\n0\n$EndElements\n"),
            "no cells",
        ),
        (
            "version.msh",
            "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n".to_string(),
            "3.0",
        ),
        (
            "mesh.stl",
            "solid x\n".to_string(),
            "unknown mesh extension",
        ),
    ];
    for (name, text, needle) in cases {
        let p = write(name, &text);
        let e = read_mesh(&p).unwrap_err().to_string();
        assert!(e.contains(needle), "{name}: expected {needle:?} in {e}");
        assert!(
            e.contains(name),
            "{name}: the message must name the file: {e}"
        );
    }
    // a Gmsh 2.2 binary file cut short (a partial copy) names the section that ran out
    let bytes = std::fs::read(mesh_path("disk_binary.msh")).unwrap();
    let p = write("cut_binary.msh", "");
    std::fs::write(&p, &bytes[..bytes.len() * 3 / 5]).unwrap();
    let e = read_mesh(&p).unwrap_err().to_string();
    assert!(
        e.contains("cut_binary.msh") && e.contains("past the end"),
        "{e}"
    );
    // an inverted tet (nodes 1, 3, 2, 4) reads, and assembly names the cell
    let p = write(
        "inverted.msh",
        &format!("{HEAD}{nodes}$Elements\n1\n1 4 2 1 1 1 3 2 4\n$EndElements\n"),
    );
    let m = read_mesh(&p).unwrap();
    let mat = Material {
        young: 1e7,
        poisson: 0.3,
        density: 1000.0,
        model: signorini::model::solid::MaterialModel::LINEAR,
    };
    let e = assemble(&m, &mat, Formulation::Solid, MassKind::Consistent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cell 0") && e.contains("inverted"), "{e}");
    // an empty node set (a physical group on a point no cell uses) is refused by scenes
    let p = write(
        "orphan.msh",
        &format!(
            "{HEAD}$PhysicalNames\n1\n0 7 \"tip\"\n$EndPhysicalNames\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 5 5 5\n$EndNodes\n$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 15 2 7 2 5\n$EndElements\n"
        ),
    );
    let m = read_mesh(&p).unwrap();
    assert_eq!(m.points.len(), 4, "the orphan node is dropped");
    assert!(m.node_sets["tip"].is_empty());
    let scene = format!(
        "[time]\ndt = 1e-6\nt_end = 1e-5\n[[bodies]]\nname = \"b\"\nmesh = {{ generator = \"file\", path = \"{}\" }}\nmaterial = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}\n[[obstacles]]\nname = \"w\"\ntype = \"plane\"\npoint = [0.0, 0.0, -1.0]\nnormal = [0.0, 0.0, 1.0]\n[[contacts]]\nbody = \"b\"\nnodes = \"tip\"\nobstacle = \"w\"\n",
        p.display()
    );
    let e = signorini::scene::file::Scene::from_toml(&scene)
        .unwrap()
        .build()
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("empty"), "{e}");
}

/// The quadratic meshes of `meshes/make_quadratic_meshes.py` (gmsh 4.15.2 with
/// `setOrder(2)`, meshio 5.3.5): each `.vtu`, meshio's conversion of the `.msh` beside
/// it into VTK's node order, reads to the same cells as the `.msh` through signorini's
/// Gmsh reader — node by node, the same coordinates — so the reader's Gmsh-to-VTK node
/// permutations (tet10, hex20, hex27) are meshio's; and every quadratic mesh measures
/// its geometry: the box exactly (round-off, 1e-12), the ball and the disks (mid-side
/// nodes on the curved boundary) within 1e-3 of `4/3 πR³` and 1e-4 of `πR²` (a piecewise
/// quadratic boundary at these sizes: measured 1.4e-4 and 1e-5).
#[test]
fn quadratic_meshes_read_in_meshio_node_order_and_measure_their_geometry() {
    use std::f64::consts::PI;
    for (msh, vtu) in [
        ("quadratic/ball_tet10.msh", "quadratic/ball_tet10.vtu"),
        ("quadratic/block_hex20.msh", "quadratic/block_hex20.vtu"),
        ("quadratic/block_hex27.msh", "quadratic/block_hex27.vtu"),
        ("quadratic/disk_quad9.msh", "quadratic/disk_quad9.vtu"),
    ] {
        let a = read_mesh(&mesh_path(msh)).unwrap();
        let b = read_mesh(&mesh_path(vtu)).unwrap();
        assert_eq!(a.cells.len(), b.cells.len(), "{msh}");
        for (ca, cb) in a.cells.iter().zip(&b.cells) {
            assert_eq!(ca.0, cb.0, "{msh}");
            for (&va, &vb) in ca.1.iter().zip(&cb.1) {
                assert_eq!(a.points[va], b.points[vb], "{msh}: a cell's nodes differ");
            }
        }
    }
    let steel = Material {
        young: 210e9,
        poisson: 0.3,
        density: 1.0,
        model: signorini::model::solid::MaterialModel::LINEAR,
    };
    for (file, kind, f, exact, tol) in [
        (
            "quadratic/ball_tet10.msh",
            CellKind::Tet10,
            Formulation::Solid,
            4.0 / 3.0 * PI * 0.05f64.powi(3),
            1e-3,
        ),
        (
            "quadratic/block_hex20.msh",
            CellKind::Hex20,
            Formulation::Solid,
            0.1 * 0.1 * 0.05,
            1e-12,
        ),
        (
            "quadratic/block_hex27.msh",
            CellKind::Hex27,
            Formulation::Solid,
            0.1 * 0.1 * 0.05,
            1e-12,
        ),
        (
            "quadratic/disk_tri6.msh",
            CellKind::Tri6,
            Formulation::PlaneStrain,
            PI * 0.05f64.powi(2),
            1e-4,
        ),
        (
            "quadratic/disk_quad8.msh",
            CellKind::Quad8,
            Formulation::PlaneStrain,
            PI * 0.05f64.powi(2),
            1e-4,
        ),
        (
            "quadratic/disk_quad9.msh",
            CellKind::Quad9,
            Formulation::PlaneStrain,
            PI * 0.05f64.powi(2),
            1e-4,
        ),
    ] {
        let mesh = read_mesh(&mesh_path(file)).unwrap();
        assert!(mesh.cells.iter().all(|c| c.0 == kind), "{file}");
        let sys = assemble(&mesh, &steel, f, MassKind::Consistent).unwrap();
        let rel = sys.total_mass() / exact - 1.0;
        println!("{file}: volume error {rel:e}");
        assert!(rel.abs() < tol, "{file}: volume error {rel:e}");
    }
}
