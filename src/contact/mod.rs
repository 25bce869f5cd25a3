//! Contacts: gap functions `g(q)`, their Jacobians `G(q)` (eq. 1, 5) and impact laws.
//!
//! A [`ContactSet`] lists the candidate contacts of a scene. Each contact `α` has a
//! gap `g^α(q)` (positive when open), a Jacobian column `G_α = ∇g^α` with a fixed
//! sparsity pattern, and a Newton restitution coefficient `e^α` (eq. 6). The local
//! velocity is `U = Gᵀ v` and the generalized reaction `r = G λ` (eq. 5).
//!
//! [`plane::NodesOnPlane`] is linear (constant `G`, so the integrators precompute the
//! Delassus operator once); [`sphere::InsideSphere`] is nonlinear (`G` depends on
//! `q`, so the Newton loop of eq. 42–51 re-linearizes it every iteration).

pub mod block;
pub mod plane;
pub mod sphere;

/// A candidate contact set: the gap functions and Jacobians of eq. 1e.
pub trait ContactSet: Send {
    /// Number of candidate contacts `m`.
    fn len(&self) -> usize;
    /// True when there is no candidate contact.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// True when `g` is affine in `q` (then `G` is constant).
    fn is_linear(&self) -> bool;
    /// The dofs touched by each Jacobian column (a fixed pattern).
    fn pattern(&self) -> Vec<Vec<usize>>;
    /// Evaluates `g(q)` into `gap` and `G(q)` into `jac` (same pattern as [`ContactSet::pattern`]).
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian);
    /// Restitution coefficient of each contact (eq. 6).
    fn restitution(&self) -> &[f64];
}

/// The `n × m` Jacobian `G` stored by columns with a fixed pattern (one column per contact).
#[derive(Clone, Debug)]
pub struct ContactJacobian {
    col_ptr: Vec<usize>,
    dofs: Vec<usize>,
    values: Vec<f64>,
}

impl ContactJacobian {
    /// Allocates a Jacobian with the pattern of `set` (values zero).
    pub fn for_set(set: &dyn ContactSet) -> Self {
        let pattern = set.pattern();
        let mut col_ptr = Vec::with_capacity(pattern.len() + 1);
        col_ptr.push(0);
        let mut dofs = Vec::new();
        for p in &pattern {
            dofs.extend_from_slice(p);
            col_ptr.push(dofs.len());
        }
        let values = vec![0.0; dofs.len()];
        ContactJacobian {
            col_ptr,
            dofs,
            values,
        }
    }

    /// Number of columns (contacts).
    pub fn ncols(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// Dofs and values of column `alpha`.
    pub fn col(&self, alpha: usize) -> (&[usize], &[f64]) {
        let r = self.col_ptr[alpha]..self.col_ptr[alpha + 1];
        (&self.dofs[r.clone()], &self.values[r])
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

/// Several contact sets seen as one (columns concatenated in order).
pub struct Composite {
    sets: Vec<Box<dyn ContactSet>>,
    e: Vec<f64>,
    /// Scratch Jacobians, one per set, so each set writes its own pattern.
    jacs: std::sync::Mutex<Vec<ContactJacobian>>,
}

impl Composite {
    /// Joins `sets`.
    pub fn new(sets: Vec<Box<dyn ContactSet>>) -> Self {
        let e = sets.iter().flat_map(|s| s.restitution().to_vec()).collect();
        let jacs = sets
            .iter()
            .map(|s| ContactJacobian::for_set(s.as_ref()))
            .collect();
        Composite {
            sets,
            e,
            jacs: std::sync::Mutex::new(jacs),
        }
    }
}

impl ContactSet for Composite {
    fn len(&self) -> usize {
        self.sets.iter().map(|s| s.len()).sum()
    }
    fn is_linear(&self) -> bool {
        self.sets.iter().all(|s| s.is_linear())
    }
    fn pattern(&self) -> Vec<Vec<usize>> {
        self.sets.iter().flat_map(|s| s.pattern()).collect()
    }
    fn evaluate(&self, q: &[f64], gap: &mut [f64], jac: &mut ContactJacobian) {
        let mut jacs = self.jacs.lock().expect("contact scratch poisoned");
        let mut off = 0;
        for (s, j) in self.sets.iter().zip(jacs.iter_mut()) {
            let m = s.len();
            s.evaluate(q, &mut gap[off..off + m], j);
            for a in 0..m {
                jac.col_values_mut(off + a).copy_from_slice(j.col(a).1);
            }
            off += m;
        }
    }
    fn restitution(&self) -> &[f64] {
        &self.e
    }
}

/// Checks a restitution coefficient (must lie in `[0, 1]`).
pub fn check_restitution(field: &str, e: f64) -> Result<f64, crate::error::Error> {
    crate::error::require_in(field, e, 0.0, 1.0)
}
