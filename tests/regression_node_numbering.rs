//! Issue 12 §6: frames number points in the order the cells first use them, not in the
//! mesh file's order; the `node_id` point array gives each point's id in the input file
//! (Gmsh node tag), so results map back to the input mesh. Checked on the committed Gmsh
//! 2.2 disk (read independently here) and on a generated box (ids = indices).

use std::collections::HashMap;
use std::path::PathBuf;

mod common;

use common::{read_frame, read_pvd};
use signorini::app::run_scene;
use signorini::io::OutputOptions;
use signorini::run::{Output, Quiet};
use signorini::scene::file::Scene;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("signorini-nodes-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Tag → coordinates of the `$Nodes` of a Gmsh 2.2 ASCII file.
fn gmsh22_nodes(text: &str) -> HashMap<u64, [f64; 3]> {
    let start = text.find("$Nodes").unwrap();
    let end = text.find("$EndNodes").unwrap();
    text[start..end]
        .lines()
        .skip(2)
        .map(|l| {
            let v: Vec<&str> = l.split_whitespace().collect();
            let x = |k: usize| v[k].parse::<f64>().unwrap();
            (v[0].parse().unwrap(), [x(1), x(2), x(3)])
        })
        .collect()
}

fn first_frame(scene: &str, name: &str) -> common::Frame {
    let mut s = Scene::from_toml(scene).unwrap();
    s.base_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let dir = tmp(name);
    let options = OutputOptions {
        plots: false,
        ..OutputOptions::default()
    };
    run_scene(
        &s,
        Some(Output {
            dir: &dir,
            options: &options,
        }),
        &mut Quiet,
    )
    .unwrap();
    let frames = read_pvd(&dir.join("fields.pvd"));
    read_frame(&dir.join(&frames[0].1))
}

#[test]
fn node_id_maps_frame_points_to_the_gmsh_tags() {
    let scene = r#"
[time]
dt = 1e-4
t_end = 2e-4
[[bodies]]
name = "disk"
formulation = "plane-strain"
mesh = { generator = "file", path = "disk.msh" }
material = { young = 1e6, poisson = 0.3, density = 1000.0 }
"#;
    let f = first_frame(scene, "disk");
    let text =
        std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/disk.msh"))
            .unwrap();
    let nodes = gmsh22_nodes(&text);
    let ids = &f.point["node_id"];
    assert_eq!(ids.len() * 3, f.points.len());
    let mut distinct = ids.clone();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    assert_eq!(distinct.len(), ids.len(), "node ids are unique");
    let mut renumbered = 0;
    for (k, &id) in ids.iter().enumerate() {
        let x = nodes[&(id as u64)];
        // the frame's reference point is the file's node of that tag, bit for bit
        assert_eq!(&f.points[3 * k..3 * k + 3], &x[..], "point {k} (tag {id})");
        renumbered += usize::from(id as usize != k + 1);
    }
    // the frames do renumber (so the array is needed): most points moved
    assert!(renumbered > ids.len() / 2, "{renumbered} of {}", ids.len());
}

#[test]
fn generated_meshes_number_their_nodes_by_index() {
    let scene = r#"
[time]
dt = 1e-5
t_end = 2e-5
[[bodies]]
name = "box"
mesh = { generator = "box", cell = "hex8", cells = [2, 1, 1], size = [0.2, 0.1, 0.1] }
material = { young = 210e9, poisson = 0.3, density = 7800.0 }
"#;
    let f = first_frame(scene, "box");
    let ids = &f.point["node_id"];
    assert_eq!(ids.len(), 12);
    for (k, &id) in ids.iter().enumerate() {
        assert_eq!(id, k as f64);
    }
}
