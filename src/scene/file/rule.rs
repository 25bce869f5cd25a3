//! How an obstacle contact's rows are formed (`[[contacts]] rule`, issue 51 §3).

use serde::{Deserialize, Serialize};

/// How an obstacle contact's rows are formed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactRule {
    /// One row per node: its own gap.
    #[default]
    Nodes,
    /// Against an obstacle, rows at points of the body's boundary faces, each the
    /// geometric gap of its point ([`crate::contact::surface`]); against another body,
    /// mortar rows, each a slave node's weighted gap ([`crate::contact::mortar`]).
    Surface,
}

impl ContactRule {
    /// The default rule (a scene written back leaves it out).
    pub fn is_nodes(&self) -> bool {
        *self == ContactRule::Nodes
    }
}
