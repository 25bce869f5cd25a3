//! Contacts as blocks: gap functions `g(q)`, local frames, Jacobian blocks `G_α(q)`
//! (eq. 1, 5, 11) and contact laws.
//!
//! A [`ContactSet`] lists the candidate contacts of a scene. Each contact `α` has a
//! gap `g^α(q)` (positive when open), a law {restitution `e^α` (eq. 6), friction
//! coefficient `μ^α` (eq. 12)} ([`ContactLaw`]) and a block of `d_α` Jacobian columns
//! with a fixed sparsity pattern: `d_α = 1` (the normal `∇g^α`) without friction, and
//! with friction `d_α = 2` in 2-D (normal, tangent) or 3 in 3-D (normal, two tangents),
//! the columns of the local orthonormal frame of eq. 11 ([`frame`]). The local velocity
//! is `U_α = G_αᵀ v ∈ R^{d_α}` and the generalized reaction `r = Σ_α G_α λ_α` (eq. 5).
//! The rows of all blocks, concatenated contact by contact, are the rows of the Delassus
//! operator ([`crate::delassus`]); a frictionless scene has one row per contact, the
//! scalar layer of before.
//!
//! [`plane::NodesOnPlane`] is linear (constant `G`, so the integrators precompute the
//! Delassus operator once); [`sphere::InsideSphere`] is nonlinear (`G` and the frame
//! depend on `q`, so the Newton loop of eq. 42–51 re-linearizes them every iteration).

pub mod block;
pub mod bodies;
pub mod frame;
pub mod linear;
pub mod mortar;
pub mod plane;
pub mod slider;
pub mod sphere;
pub mod surface;

/// The law of one contact: Newton's impact law and Coulomb's friction.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct ContactLaw {
    /// Newton restitution coefficient `e` in `[0, 1]` (eq. 6).
    pub restitution: f64,
    /// Coulomb friction coefficient `μ ≥ 0` (eq. 12); 0 makes the contact frictionless
    /// (a block of one row).
    pub friction: f64,
}

/// Where a frictional contact is after a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ContactStatus {
    /// No normal impulse.
    #[default]
    Open,
    /// Closed, tangential velocity zero (inside the cone).
    Stick,
    /// Closed, sliding on the boundary of the cone.
    Slip,
    /// Closed, a frictionless contact (μ = 0 or a one-row block) in a frictional scene:
    /// neither stick nor slip applies to it.
    Frictionless,
}

impl ContactStatus {
    /// The code written to histories and frames: 0 open, 1 stick, 2 slip, 3 closed
    /// without friction.
    pub fn code(self) -> u8 {
        match self {
            ContactStatus::Open => 0,
            ContactStatus::Stick => 1,
            ContactStatus::Slip => 2,
            ContactStatus::Frictionless => 3,
        }
    }

    /// The status of a code (`None` outside 0..=3).
    pub fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0 => ContactStatus::Open,
            1 => ContactStatus::Stick,
            2 => ContactStatus::Slip,
            3 => ContactStatus::Frictionless,
            _ => return None,
        })
    }
}

/// A candidate contact set: the gap functions, frames and Jacobian blocks of eq. 1e, 11.
pub trait ContactSet: Send {
    /// Number of candidate contacts `m`.
    fn len(&self) -> usize;
    /// True when there is no candidate contact.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// True when `g` is affine in `q` and the frames are fixed (then `G` is constant).
    fn is_linear(&self) -> bool;
    /// True when contact `alpha`'s block of `G` is constant (by default, when the whole
    /// set is linear): a plane contact beside contacts between bodies keeps its block
    /// while theirs change.
    fn block_is_linear(&self, _alpha: usize) -> bool {
        self.is_linear()
    }
    /// Rows of contact `alpha`'s block: 1 without friction, the space dimension with it.
    fn dim(&self, alpha: usize) -> usize;
    /// The dofs touched by each Jacobian column, row by row (normal first in each block).
    fn pattern(&self) -> Vec<Vec<usize>>;
    /// Evaluates `g(q)` into `gap` (one value per contact) and `G(q)` into `jac` (one
    /// column per row, pattern as in [`ContactSet::pattern`]).
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian);
    /// The law of each contact.
    fn laws(&self) -> &[ContactLaw];
    /// Brings the set's search data up to date at `q` at the start of a step (the
    /// candidate facets and the pairing of contacts between bodies, [`bodies`]); `true`
    /// when the Jacobian at `q` may have changed (a node paired with another facet). It
    /// may allocate (a rebuilt tree), so the integrators call it outside the step's
    /// Newton loop; a set with fixed geometry does nothing.
    fn update(&mut self, _q: &[f64]) -> Result<bool, crate::error::Error> {
        Ok(false)
    }
    /// Every dof a Jacobian column can touch (sorted, no repeats): the contact zone the
    /// Delassus data are condensed onto ([`crate::delassus::Delassus::condense_zone`]).
    /// By default the dofs of [`ContactSet::pattern`]; a set whose columns move to
    /// other dofs lists them all.
    fn zone(&self) -> Vec<usize> {
        let mut z: Vec<usize> = self.pattern().into_iter().flatten().collect();
        z.sort_unstable();
        z.dedup();
        z
    }
    /// Forgets the search history before a run resumes at `q` (a checkpoint): the next
    /// [`ContactSet::update`] rebuilds from `q` and measures the next step's motion
    /// from it.
    fn restart(&mut self, _q: &[f64]) {}
    /// Whether the integrators should condense the step matrix onto [`ContactSet::zone`]
    /// once instead of solving for `Â⁻¹G` at every re-linearization of a nonlinear `G`.
    /// Contacts between bodies do; the rigid obstacles keep the per-linearization solves
    /// (the same numbers to round-off, but their committed golden histories are pinned
    /// to that arithmetic).
    fn condensed(&self) -> bool {
        false
    }
    /// The gap of each contact at `q` for the check of a starting state (a node may not
    /// start inside an obstacle or another body, issue 34): by default `g(q)`. A set that
    /// caps the gaps of far nodes (contacts between bodies read the search distance where
    /// no facet is near) measures them against the whole target surface instead, so a
    /// node deep inside the other body reads its depth. Called once, before the run; it
    /// may allocate.
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
        let mut jac = ContactJacobian::for_set(self);
        self.evaluate(q, gap, &mut jac);
    }
    /// The largest reference coordinate `|X|` the gap functions add to `q` (`x = X + u`):
    /// a gap cannot resolve a change of `u` below the ulps of `X`, so the Newton loop
    /// counts such changes as round-off ([`crate::integrators`]' convergence measure).
    /// 0 for sets whose gaps read `q` alone (rigid bodies, the bar).
    fn coordinate_scale(&self) -> f64 {
        0.0
    }
    /// Rows over all blocks.
    fn rows(&self) -> usize {
        (0..self.len()).map(|a| self.dim(a)).sum()
    }
    /// True when some contact has friction.
    fn has_friction(&self) -> bool {
        self.laws().iter().any(|l| l.friction > 0.0)
    }
}

/// Checks a friction coefficient (must be finite and non-negative).
pub fn check_friction(field: &str, mu: f64) -> Result<f64, crate::error::Error> {
    crate::error::require_in(field, mu, 0.0, 1e6)
}

/// The laws and block size of nodal contacts that share one `{e, μ}` (the plane and
/// round obstacles): frictionless blocks of one row until [`UniformLaws::set_friction`].
#[derive(Clone, Debug)]
pub(crate) struct UniformLaws {
    /// One law per contact.
    pub laws: Vec<ContactLaw>,
    /// Rows per contact.
    pub dim: usize,
}

impl UniformLaws {
    /// `m` frictionless contacts of restitution `e` (checked by the caller).
    pub fn frictionless(m: usize, e: f64) -> Self {
        UniformLaws {
            laws: vec![
                ContactLaw {
                    restitution: e,
                    friction: 0.0,
                };
                m
            ],
            dim: 1,
        }
    }

    /// Friction `mu` for every contact: blocks of `space_dim` rows when `mu > 0`.
    pub fn set_friction(&mut self, mu: f64, space_dim: usize) -> Result<(), crate::error::Error> {
        check_friction("friction", mu)?;
        if mu > 0.0 && space_dim < 2 {
            // a 1-D contact (a rod's end on a wall) has no tangent: friction would be
            // silently dropped
            return Err(crate::error::Error::invalid(
                "friction",
                crate::error::num(mu),
                "a 1-D contact has no tangential direction, so Coulomb friction does not \
                 apply: set friction = 0, or model the body in 2-D or 3-D",
            ));
        }
        self.laws.iter_mut().for_each(|l| l.friction = mu);
        self.dim = if mu > 0.0 { space_dim } else { 1 };
        Ok(())
    }
}

/// The `n × rows` Jacobian `G` stored by columns with a fixed pattern (one column per
/// row: `d_α` consecutive columns per contact).
#[derive(Clone, Debug)]
pub struct ContactJacobian {
    /// First column of each contact's block (`m + 1` values).
    block_ptr: Vec<usize>,
    col_ptr: Vec<usize>,
    dofs: Vec<usize>,
    values: Vec<f64>,
}

impl ContactJacobian {
    /// Allocates a Jacobian with the pattern of `set` (values zero).
    pub fn for_set<S: ContactSet + ?Sized>(set: &S) -> Self {
        let pattern = set.pattern();
        let mut col_ptr = Vec::with_capacity(pattern.len() + 1);
        col_ptr.push(0);
        let mut dofs = Vec::new();
        for p in &pattern {
            dofs.extend_from_slice(p);
            col_ptr.push(dofs.len());
        }
        let values = vec![0.0; dofs.len()];
        let mut block_ptr = Vec::with_capacity(set.len() + 1);
        block_ptr.push(0);
        for a in 0..set.len() {
            block_ptr.push(block_ptr[a] + set.dim(a));
        }
        assert_eq!(
            block_ptr[set.len()],
            pattern.len(),
            "contact set: the blocks' rows and the pattern's columns disagree"
        );
        ContactJacobian {
            block_ptr,
            col_ptr,
            dofs,
            values,
        }
    }

    /// Number of contacts (blocks).
    pub fn contacts(&self) -> usize {
        self.block_ptr.len() - 1
    }

    /// The columns of contact `alpha`'s block (its first is the normal).
    pub fn block(&self, alpha: usize) -> std::ops::Range<usize> {
        self.block_ptr[alpha]..self.block_ptr[alpha + 1]
    }

    /// Number of columns (rows of all blocks).
    pub fn ncols(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Every column's entries at once: the first entry of each column (`ncols + 1`
    /// values), then the dofs and values of all entries, column after column.
    pub fn entries(&self) -> (&[usize], &[usize], &[f64]) {
        (&self.col_ptr, &self.dofs, &self.values)
    }

    /// Dofs and values of column `alpha` (a row of the contact space).
    pub fn col(&self, alpha: usize) -> (&[usize], &[f64]) {
        let r = self.col_ptr[alpha]..self.col_ptr[alpha + 1];
        (&self.dofs[r.clone()], &self.values[r])
    }

    /// Mutable dofs and values of column `alpha`: for sets whose columns move to other
    /// dofs (a node sliding from one facet to the next, [`bodies`]); the column keeps
    /// its length.
    pub fn col_mut(&mut self, alpha: usize) -> (&mut [usize], &mut [f64]) {
        let r = self.col_ptr[alpha]..self.col_ptr[alpha + 1];
        (&mut self.dofs[r.clone()], &mut self.values[r])
    }

    /// Mutable values of column `alpha` (pattern as in [`ContactJacobian::col`]).
    pub fn col_values_mut(&mut self, alpha: usize) -> &mut [f64] {
        let r = self.col_ptr[alpha]..self.col_ptr[alpha + 1];
        &mut self.values[r]
    }

    /// `G_αᵀ x`.
    pub fn dot(&self, alpha: usize, x: &[f64]) -> f64 {
        let (d, v) = self.col(alpha);
        d.iter().zip(v).map(|(&i, &g)| g * x[i]).sum()
    }

    /// `y += s G_α`.
    pub fn axpy(&self, alpha: usize, s: f64, y: &mut [f64]) {
        let (d, v) = self.col(alpha);
        for (&i, &g) in d.iter().zip(v) {
            y[i] += s * g;
        }
    }

    /// `out = Gᵀ x` for all contacts.
    pub fn transpose_mul(&self, x: &[f64], out: &mut [f64]) {
        for (a, o) in out.iter_mut().enumerate() {
            *o = self.dot(a, x);
        }
    }

    /// `G_αᵀ G_β` (used for the Euclidean projection metric, eq. 58). Columns hold a
    /// node's few dofs, so the pairwise scan is cheaper than a scatter.
    pub fn col_dot_col(&self, alpha: usize, beta: usize) -> f64 {
        let (da, va) = self.col(alpha);
        let (db, vb) = self.col(beta);
        let mut s = 0.0;
        for (i, x) in da.iter().zip(va) {
            for (j, y) in db.iter().zip(vb) {
                if i == j {
                    s += x * y;
                }
            }
        }
        s
    }
}

/// Several contact sets seen as one (contacts and their blocks concatenated in order).
pub struct Composite {
    sets: Vec<Box<dyn ContactSet>>,
    laws: Vec<ContactLaw>,
    /// (set, index in the set) of each contact.
    owner: Vec<(usize, usize)>,
    /// Scratch Jacobians, one per set, so each set writes its own pattern.
    jacs: std::sync::Mutex<Vec<ContactJacobian>>,
}

impl Composite {
    /// Joins `sets`.
    pub fn new(sets: Vec<Box<dyn ContactSet>>) -> Self {
        let laws = sets.iter().flat_map(|s| s.laws().to_vec()).collect();
        let owner = sets
            .iter()
            .enumerate()
            .flat_map(|(i, s)| (0..s.len()).map(move |a| (i, a)))
            .collect();
        let jacs = sets
            .iter()
            .map(|s| ContactJacobian::for_set(s.as_ref()))
            .collect();
        Composite {
            sets,
            laws,
            owner,
            jacs: std::sync::Mutex::new(jacs),
        }
    }
}

impl ContactSet for Composite {
    fn len(&self) -> usize {
        self.owner.len()
    }
    fn is_linear(&self) -> bool {
        self.sets.iter().all(|s| s.is_linear())
    }
    fn dim(&self, alpha: usize) -> usize {
        let (i, a) = self.owner[alpha];
        self.sets[i].dim(a)
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        self.sets.iter().flat_map(|s| s.pattern()).collect()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let mut jacs = self.jacs.lock().expect("contact scratch poisoned");
        let (mut off, mut row) = (0, 0);
        for (s, j) in self.sets.iter().zip(jacs.iter_mut()) {
            let m = s.len();
            s.evaluate(q, &mut gap[off..off + m], j);
            for c in 0..j.ncols() {
                let (dofs, vals) = jac.col_mut(row + c);
                let (d, v) = j.col(c);
                dofs.copy_from_slice(d);
                vals.copy_from_slice(v);
            }
            off += m;
            row += j.ncols();
        }
    }
    fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }
    fn condensed(&self) -> bool {
        self.sets.iter().any(|s| s.condensed())
    }
    fn block_is_linear(&self, alpha: usize) -> bool {
        let (i, a) = self.owner[alpha];
        self.sets[i].block_is_linear(a)
    }
    fn zone(&self) -> Vec<usize> {
        let mut z: Vec<usize> = self.sets.iter().flat_map(|s| s.zone()).collect();
        z.sort_unstable();
        z.dedup();
        z
    }
    fn restart(&mut self, q: &[f64]) {
        self.sets.iter_mut().for_each(|s| s.restart(q));
    }
    fn starting_gaps(&self, q: &[f64], gap: &mut [f64]) {
        let mut off = 0;
        for s in &self.sets {
            s.starting_gaps(q, &mut gap[off..off + s.len()]);
            off += s.len();
        }
    }
    fn coordinate_scale(&self) -> f64 {
        self.sets
            .iter()
            .fold(0.0, |a, s| a.max(s.coordinate_scale()))
    }
    fn update(&mut self, q: &[f64]) -> Result<bool, crate::error::Error> {
        let mut any = false;
        for s in &mut self.sets {
            any |= s.update(q)?;
        }
        Ok(any)
    }
}

/// Checks a restitution coefficient (must lie in `[0, 1]`).
pub fn check_restitution(field: &str, e: f64) -> Result<f64, crate::error::Error> {
    crate::error::require_in(field, e, 0.0, 1.0)
}
