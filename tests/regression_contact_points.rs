//! Issue 37: a model names each of its contacts (`Geometry::contacts`: the node, its
//! body, what it meets), the list a notebook user reads as arrays. The list must be the
//! contact set's, contact for contact: on every shipped scene whose contacts are mesh
//! nodes, there are as many entries as contacts, and the normal column of contact `a`
//! of `G` (at the initial state) acts on a displacement component of entry `a`'s node,
//! which lies in the named body; the target is the scene's obstacle or target body.

use std::path::Path;

use signorini::contact::ContactJacobian;
use signorini::scene::file::Scene;

fn check(name: &str, model: &signorini::scene::Model, bodies: &[String], targets: &[String]) {
    let geo = &model.geometry;
    let set = model.problem.contacts.as_ref();
    assert_eq!(
        geo.contacts.len(),
        set.len(),
        "{name}: one entry per contact"
    );
    let mut jac = ContactJacobian::for_set(set);
    let mut gap = vec![0.0; set.len()];
    set.evaluate(&model.problem.q0, &mut gap, &mut jac);
    for (a, c) in geo.contacts.iter().enumerate() {
        let normal = jac.block(a).start;
        let (dofs, _) = jac.col(normal);
        let own: Vec<usize> = (0..geo.dim)
            .filter_map(|i| geo.dof_of[c.point * geo.dim + i])
            .collect();
        assert!(
            dofs.iter().any(|d| own.contains(d)),
            "{name}: contact {a}'s column acts on dofs {dofs:?}, none of node {}'s {own:?}",
            c.point
        );
        assert!(
            geo.cells
                .iter()
                .any(|(_, nodes, b)| *b == c.body && nodes.contains(&c.point)),
            "{name}: contact {a}'s node {} is not in body {}",
            c.point,
            c.body
        );
        if !bodies.is_empty() {
            assert!(targets.contains(&c.target), "{name}: target {:?}", c.target);
        }
    }
}

#[test]
fn every_contact_names_its_node_body_and_target() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if name == "wide_block.toml" {
            continue; // 30 000 rows: the same code path as sliding_block, ten times longer
        }
        let scene = Scene::from_file(&path).unwrap();
        if scene.example.is_some() {
            continue; // the academic examples' contacts are corners and points, no mesh
        }
        let (model, _) = scene.build().unwrap();
        let bodies: Vec<String> = scene.bodies.iter().map(|b| b.name.clone()).collect();
        let mut targets: Vec<String> = scene
            .obstacles
            .iter()
            .map(|o| o.name().to_string())
            .collect();
        targets.extend(bodies.iter().cloned());
        check(&name, &model, &bodies, &targets);
        checked += 1;
    }
    assert!(checked >= 12, "{checked} scenes checked");
    // the built-in bars: one contact at x = 0 (rod), the x0 face (hex8 bar)
    let bar = signorini::scene::bar::BarScene::default().build().unwrap();
    check("bar", &bar, &[], &[]);
    assert_eq!(bar.geometry.contacts[0].point, 0);
    assert_eq!(bar.geometry.points[0][0], 0.0);
}
