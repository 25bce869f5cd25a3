//! Issue 16 §6: in a frictional scene, a closed contact without friction was reported
//! as "stick" (status 1) in the history and the frames' `contact_status`. A block slid
//! into a frictionless wall while it rests on a floor with μ = 0.3: the wall's closed
//! contacts must read 3 (closed without friction), never 1 or 2, and the floor's
//! closed contacts 1 or 2, never 3.

use std::path::PathBuf;
use std::process::Command;

#[test]
fn a_closed_frictionless_contact_has_its_own_status() {
    let dir = std::env::temp_dir().join(format!("signorini-wall-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene: PathBuf = dir.join("wall.toml");
    std::fs::write(
        &scene,
        r#"[time]
dt = 1e-4
t_end = 0.02
[scheme]
kind = "moreau-jean"
[[bodies]]
name = "block"
mesh = { generator = "box", cell = "hex8", cells = [4, 4, 2], size = [0.1, 0.1, 0.05] }
material = { young = 1e7, poisson = 0.3, density = 1000.0 }
velocity = [-0.1, 0.0, 0.0]
[loads]
gravity = [0.0, 0.0, -9.81]
[[obstacles]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
[[obstacles]]
name = "wall"
type = "plane"
point = [-0.0005, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[[contacts]]
body = "block"
nodes = "x0"
obstacle = "wall"
[[contacts]]
body = "block"
nodes = "z0"
obstacle = "floor"
friction = 0.3
"#,
    )
    .unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .arg("run")
        .arg(&scene)
        .args(["--quiet", "--no-plots", "--no-fields", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let cols: Vec<usize> = (0..header.len())
        .filter(|&i| header[i].starts_with("status_"))
        .collect();
    // x0 of a 4 × 4 × 2 box: 5 × 3 nodes on the wall, then 5 × 5 on the floor
    assert_eq!(cols.len(), 15 + 25, "{header:?}");
    let (mut wall, mut floor) = ([0usize; 4], [0usize; 4]);
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        for (j, &i) in cols.iter().enumerate() {
            let code: usize = f[i].parse().unwrap();
            if j < 15 {
                wall[code] += 1;
            } else {
                floor[code] += 1;
            }
        }
    }
    assert!(wall[3] > 0 && wall[1] == 0 && wall[2] == 0, "wall {wall:?}");
    assert!(floor[1] + floor[2] > 0 && floor[3] == 0, "floor {floor:?}");
}
