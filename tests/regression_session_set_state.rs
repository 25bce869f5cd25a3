//! Issue 49 §5: a state set after the build passes the scene's own starting-gap rule
//! (`overlap_tolerance`, the error a scene's start gives), through the library
//! (`Model::set_state` before the run opens, `app::Session::set_state` between steps),
//! not a copy of it in the Python binding with a fixed tolerance; and the one
//! `history.csv` reader (`io::read_history`) takes a `.part` whose last line a kill cut.

use signorini::app::Session;
use signorini::scene::file::Scene;

/// A box on the plane z = 0 (its face `z0` on it), `body` added to its body's table and
/// `extra` to its contact's.
fn scene_with(body: &str, extra: &str) -> Scene {
    Scene::from_toml(&format!(
        r#"
[time]
dt = 1e-5
t_end = 1e-3

[scheme]
kind = "moreau-jean"

[[bodies]]
name = "box"
mesh = {{ generator = "box", cell = "hex8", cells = [2, 2, 1], size = [0.2, 0.2, 0.1] }}
material = {{ young = 1e7, poisson = 0.3, density = 1000.0 }}
{body}

[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[[contacts]]
body = "box"
nodes = "z0"
obstacle = "floor"
{extra}
"#
    ))
    .unwrap()
}

/// The box on its floor, `extra` added to its contact.
fn scene(extra: &str) -> Scene {
    scene_with("", extra)
}

/// The model's displacements with every node moved by `dz` along z.
fn shifted(model: &signorini::scene::Model, dz: f64) -> Vec<f64> {
    let mut q = model.problem.q0.clone();
    for (full, d) in model.geometry.dof_of.iter().enumerate() {
        if let (2, Some(d)) = (full % 3, d) {
            q[*d] += dz;
        }
    }
    q
}

/// What the scene's start says of a box sunk 1 mm into its floor.
const SUNK: &str = "starts 1.000e-3 m inside obstacle \"floor\"";

#[test]
fn a_state_set_between_steps_passes_the_scenes_own_overlap_rule() {
    let s = scene("");
    let (model, report) = s.build().unwrap();
    let down = shifted(&model, -1e-3);
    let up = shifted(&model, 1e-3);
    let mut session = Session::scene(
        &s,
        Some((model, report)),
        None,
        &mut signorini::run::Quiet,
        None,
    )
    .unwrap();
    session.advance(1, &mut signorini::run::Quiet).unwrap();
    let before = session.integrator().state().q.clone();
    let e = session.set_state(Some(down.clone()), None).unwrap_err();
    let msg = e.to_string();
    assert_eq!(e.exit_code(), 2, "{msg}");
    assert!(msg.contains("contacts[0].nodes"), "{msg}");
    assert!(msg.contains("z0"), "{msg}");
    assert!(msg.contains(&format!("of body \"box\" {SUNK}")), "{msg}");
    assert!(msg.contains("9 node(s) start inside"), "{msg}");
    assert!(msg.contains("overlap_tolerance = "), "{msg}");
    // refused, the state is left as it was
    assert_eq!(session.integrator().state().q, before);
    // a lifted box is taken, and the run goes on from it
    session.set_state(Some(up.clone()), None).unwrap();
    assert_eq!(session.integrator().state().q, up);
    session.advance(2, &mut signorini::run::Quiet).unwrap();
    // a vector of the wrong length is refused by name
    let e = session.set_state(None, Some(vec![0.0; 3])).unwrap_err();
    assert!(e.to_string().contains("`v`"), "{e}");

    // within a contact's own overlap_tolerance the same sinking is taken
    let s = scene("overlap_tolerance = 2e-3");
    let (model, report) = s.build().unwrap();
    let down = shifted(&model, -1e-3);
    let mut session = Session::scene(
        &s,
        Some((model, report)),
        None,
        &mut signorini::run::Quiet,
        None,
    )
    .unwrap();
    session.advance(1, &mut signorini::run::Quiet).unwrap();
    session.set_state(Some(down.clone()), None).unwrap();
    assert_eq!(session.integrator().state().q, down);
    session.advance(2, &mut signorini::run::Quiet).unwrap();
}

#[test]
fn a_built_models_initial_state_passes_the_same_rule() {
    let s = scene("");
    let (mut model, _) = s.build().unwrap();
    let q0 = model.problem.q0.clone();
    let down = shifted(&model, -1e-3);
    let msg = model.set_state(Some(down), None).unwrap_err().to_string();
    assert!(
        msg.contains("contacts[0].nodes") && msg.contains(SUNK),
        "{msg}"
    );
    assert_eq!(model.problem.q0, q0);
    // the message is the build's own for a scene that starts there (its 18 nodes
    // sunk by an `initial_displacement`)
    let rows = vec!["[0.0, 0.0, -1e-3]"; 18].join(", ");
    let sunk = scene_with(&format!("initial_displacement = [{rows}]"), "");
    let start = sunk.build().map(|_| ()).unwrap_err().to_string();
    assert_eq!(start, msg);
    let up = shifted(&model, 1e-3);
    model.set_state(Some(up.clone()), None).unwrap();
    assert_eq!(model.problem.q0, up);

    let s = scene("overlap_tolerance = 2e-3");
    let (mut model, _) = s.build().unwrap();
    let down = shifted(&model, -1e-3);
    model.set_state(Some(down.clone()), None).unwrap();
    assert_eq!(model.problem.q0, down);
}

#[test]
fn the_history_reader_takes_a_cut_part_line_and_refuses_a_bad_row_elsewhere() {
    let dir = std::env::temp_dir().join(format!("signorini-history-read-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let head = "step,time,gap_0\n1,1e-6,0.5\n2,2e-6,nan\n";
    // a kill cut the third row between two digits, and one with too few values
    let part = dir.join("history.csv.part");
    for cut in ["3,3e-6,0.2", "3,3e-6\n"] {
        std::fs::write(&part, format!("{head}{cut}")).unwrap();
        let h = signorini::io::read_history(&part).unwrap();
        assert_eq!(h.header, ["step", "time", "gap_0"]);
        assert_eq!(h.rows.len(), 2, "{cut:?}");
        assert_eq!(h.rows[1][1], 2e-6);
        assert!(h.rows[1][2].is_nan());
        let cols = h.columns();
        assert_eq!(cols[0], ("step".to_string(), vec![1.0, 2.0]));
        assert_eq!(h.column("gap_0"), Some(2));
    }
    // a whole history: a short row is bad input, naming its line
    let whole = dir.join("history.csv");
    std::fs::write(&whole, format!("{head}3,3e-6\n4,4e-6,0.1\n")).unwrap();
    let e = signorini::io::read_history(&whole).unwrap_err();
    assert_eq!(e.exit_code(), 2);
    let msg = e.to_string();
    assert!(
        msg.contains("line 4") && msg.contains("expected 3 numbers"),
        "{msg}"
    );
    // an empty file has no header and no rows
    std::fs::write(&whole, "").unwrap();
    let h = signorini::io::read_history(&whole).unwrap();
    assert!(h.header.is_empty() && h.rows.is_empty());
    std::fs::remove_dir_all(&dir).unwrap();
}
