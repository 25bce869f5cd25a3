//! The starting-gap rule of a scene: no contact node starts deeper inside its obstacle
//! or the other body than its contact's `overlap_tolerance` ([`ContactSpec`]; default
//! 1e-9 of the contact body's size, the round-off of coincident meshes). The build
//! checks each `[[contacts]]` entry as it makes its contact set; [`StartingGaps`] keeps
//! the rule with the built [`Model`], so that a state set later (the initial state of a
//! built model, or a session's state between steps: [`crate::app::Session::set_state`])
//! is checked by the same rule, with the same message.
//!
//! A leaf of `scene::file`: it reads the schema (`mod.rs`) and nothing of the build or
//! the validation, which both call it.

use std::sync::Arc;

use super::*;

/// The rule of one `[[contacts]]` entry: its tolerance, its contacts among the model's,
/// and what an error names (the entry's node set and body, the node by its file tag,
/// what it starts inside).
#[derive(Clone, Debug)]
pub(super) struct EntryGaps {
    /// The entry's index in `[[contacts]]` (the error's key path).
    entry: usize,
    /// The entry's contacts among the model's (one per node, in order).
    contacts: std::ops::Range<usize>,
    /// The entry's `nodes` (the error's value).
    set: String,
    /// The entry's body.
    body: String,
    /// What the nodes may not start inside: `obstacle "floor"`, `body "b" (surface `s`)`.
    against: String,
    /// The deepest a node may start inside (m).
    tol: f64,
    /// The entry's nodes (indices into the body's mesh).
    nodes: Vec<usize>,
    /// The body's mesh as far as errors name its nodes ([`label_mesh`]).
    labels: Arc<Mesh>,
}

impl EntryGaps {
    /// The rule of contact `c` (entry `entry`, its contacts from `first` on) over the
    /// `nodes` of `mesh`, against `against`; refuses an `overlap_tolerance` out of range.
    pub(super) fn new(
        (entry, c): (usize, &ContactSpec),
        first: usize,
        mesh: &Mesh,
        labels: Arc<Mesh>,
        nodes: &[usize],
        against: String,
    ) -> Result<EntryGaps, Error> {
        let size = mesh_size(mesh);
        let tol = match c.overlap_tolerance {
            Some(t) => crate::error::require_in("overlap_tolerance", t, 0.0, f64::MAX)?,
            None => 1e-9 * size,
        };
        Ok(EntryGaps {
            entry,
            contacts: first..first + nodes.len(),
            set: c.nodes.clone(),
            body: c.body.clone(),
            against,
            tol,
            nodes: nodes.to_vec(),
            labels,
        })
    }

    /// Refuses the entry's starting gaps `gap` (one per node, at the initial
    /// displacements: [`ContactSet::starting_gaps`]) when a node starts inside deeper
    /// than the tolerance, naming the deepest node by its file tag, its depth and how
    /// many start inside. The error's key is `nodes` (the caller prefixes the entry).
    pub(super) fn check(&self, gap: &[f64]) -> Result<(), Error> {
        let tol = self.tol;
        let inside = gap.iter().filter(|&&g| g < -tol).count();
        let Some((k, &g)) = gap
            .iter()
            .enumerate()
            .filter(|(_, g)| **g < -tol)
            .min_by(|a, b| a.1.total_cmp(b.1))
        else {
            return Ok(());
        };
        let node = self
            .nodes
            .get(k)
            .map_or_else(|| format!("contact {k}"), |&v| self.labels.node_label(v));
        Err(Error::invalid(
            "nodes",
            &self.set,
            &format!(
                "{node} of body \"{}\" starts {:.3e} m inside {} ({inside} node(s) start \
                 inside; the deepest is named), expected at most overlap_tolerance = {tol:.3e} m: \
                 move the bodies apart, or raise overlap_tolerance where curved non-matching \
                 meshes cut into each other",
                self.body, -g, self.against
            ),
        ))
    }

    /// The key path of the entry (`contacts[i]`), which prefixes its errors.
    pub(super) fn key(&self) -> String {
        format!("contacts[{}]", self.entry)
    }
}

/// The starting-gap rule of a built scene, one `EntryGaps` per `[[contacts]]` entry,
/// kept with the [`Model`] to check a state set after the build. Empty (no check) for
/// the built-in bar and the examples, whose starts are their parameters' own checks.
#[derive(Clone, Debug, Default)]
pub struct StartingGaps {
    entries: Vec<EntryGaps>,
}

impl StartingGaps {
    /// Adds the rule of one entry (the build, entry by entry, in the contacts' order).
    pub(super) fn push(&mut self, entry: EntryGaps) {
        self.entries.push(entry);
    }

    /// Refuses `gap`, the starting gaps of the model's contacts at a new `q`
    /// ([`ContactSet::starting_gaps`], one per contact), where a node of an entry starts
    /// deeper inside than that entry's `overlap_tolerance`: the error the build gives
    /// for such a start (key `contacts[i].nodes`), for the first entry that has one.
    pub fn check(&self, gap: &[f64]) -> Result<(), Error> {
        for e in &self.entries {
            let own = gap
                .get(e.contacts.clone())
                .expect("a starting gap for every contact of the model");
            e.check(own).map_err(|err| prefix(&e.key(), err))?;
        }
        Ok(())
    }
}

/// What of `mesh` names its nodes in an error ([`Mesh::node_label`]): its file tags and
/// its file, no points or cells (kept for a state set after the build).
pub(super) fn label_mesh(mesh: &Mesh) -> Arc<Mesh> {
    Arc::new(Mesh {
        points: Vec::new(),
        cells: Vec::new(),
        node_sets: BTreeMap::new(),
        node_ids: mesh.node_ids.clone(),
        cell_ids: Vec::new(),
        source: mesh.source.clone(),
    })
}

/// The diagonal of a mesh's bounding box (m).
pub(super) fn mesh_size(mesh: &Mesh) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &mesh.points {
        for j in 0..3 {
            lo[j] = lo[j].min(p[j]);
            hi[j] = hi[j].max(p[j]);
        }
    }
    (0..3)
        .map(|j| (hi[j] - lo[j]).max(0.0).powi(2))
        .sum::<f64>()
        .sqrt()
}
