//! Mechanical models: what the integrators step.
//!
//! A model is a [`LinearSystem`] (eq. 1c with `F(t, q, v) = f(t) − C v − K q`: constant
//! sparse mass `M`, stiffness `K`, optional Rayleigh damping `C`, external force `f`)
//! plus a set of contacts (see [`crate::contact`]) and initial conditions.
//! Nonlinear constraints (curved obstacles, rigid rotations) are supported through
//! the contact set; nonlinear internal forces (large strain, nonlinear materials) will
//! add a tangent-returning variant of this type, with the same integrators.
//!
//! Submodules build systems: [`rod`] (P1 rod elements, eq. 71) and [`point_mass`];
//! [`energy`] keeps a run's energy balance.

pub mod energy;
pub mod generate;
pub mod geometry;
pub mod hyperelastic;
pub mod material;
pub mod multibody;
pub mod ordering;
pub mod point_mass;
pub mod rod;
pub mod solid;
pub mod system;

use crate::linalg::{QuadraticForm, SparseMatrix, quadratic_form};

/// How the element mass matrices are formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum MassKind {
    /// Consistent mass, `∫ ρ Nᵀ N` (eq. 71 for the rod).
    Consistent,
    /// Row-sum lumped mass (diagonal).
    Lumped,
    /// No mass on the contact nodes (Khenous–Laborde–Renard's idea, as GetFEM offers
    /// it): in each element touching a contact node, the contact nodes' rows and
    /// columns are removed from the consistent mass and their row sums are added
    /// equally to the diagonal of the element's other nodes, so element masses (and the
    /// total mass) are kept. Removes the impact of the contact node's own inertia.
    Redistributed,
}

impl MassKind {
    /// Parses `consistent` or `lumped`.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "consistent" => Some(MassKind::Consistent),
            "lumped" => Some(MassKind::Lumped),
            "redistributed" => Some(MassKind::Redistributed),
            _ => None,
        }
    }
    /// The name used on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            MassKind::Consistent => "consistent",
            MassKind::Lumped => "lumped",
            MassKind::Redistributed => "redistributed",
        }
    }
}

/// The layouts of a system's `M` and `K` read once ([`LinearSystem::energy_forms`]), so
/// that the energies of every history row take the fast path of their pattern
/// ([`QuadraticForm`]).
#[derive(Clone, Debug)]
pub struct EnergyForms {
    mass: QuadraticForm,
    stiffness: QuadraticForm,
    /// No constant external force: `fᵀ q` is skipped.
    unloaded: bool,
}

/// A linear structural model `M v̇ + C v + K q = f + G λ` (eq. 1c).
#[derive(Clone, Debug)]
pub struct LinearSystem {
    /// Mass matrix `M` (symmetric positive definite).
    pub mass: SparseMatrix,
    /// Stiffness matrix `K` (symmetric positive semidefinite).
    pub stiffness: SparseMatrix,
    /// Damping matrix `C` (Rayleigh or none).
    pub damping: Option<SparseMatrix>,
    /// Constant external force `f` (N); zero for the free bar.
    pub force: Vec<f64>,
    /// Displacement components per node (1 for rods, 2 or 3 for solids).
    pub dofs_per_node: usize,
    /// The displacement component (0 = x, 1 = y, 2 = z) of each dof.
    pub component: Vec<u8>,
    /// A fill-reducing dof order (position → dof) for the Cholesky of `M̂`, from the
    /// mesh geometry ([`ordering::nested_dissection`]); the factorization keeps it
    /// only where it fills less than AMD. `None`: AMD alone.
    pub ordering: Option<Vec<usize>>,
    /// Time-dependent nodal loads `φ_i(t) b_i`, added to `force` at `t_{k+θ}` by the
    /// schemes (the scene's `[[forces]]`).
    pub loads: Vec<NodalLoad>,
    /// Dofs eliminated with a prescribed velocity (the scene's `[[prescribed]]`): their
    /// coupling to the kept dofs.
    pub prescribed: Option<Prescribed>,
    /// Nonlinear internal forces `r(q)` (large-deformation bodies), added to `F` as
    /// `−r(q)` ([`system`]); empty for a linear system. Attached to the final
    /// (restricted) system: [`LinearSystem::block_diagonal`] and
    /// [`LinearSystem::restrict`] take systems without them.
    pub nonlinear: Vec<std::sync::Arc<dyn system::NonlinearPart>>,
}

/// Dofs moved with a prescribed velocity `v_p(t) = w_p φ_p(t)` (displacement
/// `u_p(t) = w_p ∫₀ᵗ φ_p`), eliminated from the system. The kept dofs feel them through
/// the coupling blocks: the θ-method of eq. 18 on the full system, split by rows, adds
/// `−M_fp (v_p(t_{k+1}) − v_p(t_k)) − h C_fp v_p(t_{k+θ}) − h K_fp u_p(t_{k+θ})` to the
/// free-velocity right-hand side of the kept dofs.
#[derive(Clone, Debug)]
pub struct Prescribed {
    /// `M_fp` (kept × prescribed).
    pub mass: SparseMatrix,
    /// `K_fp`.
    pub stiffness: SparseMatrix,
    /// `C_fp` (with damping).
    pub damping: Option<SparseMatrix>,
    /// `w_p` per prescribed dof (m/s).
    pub velocity: Vec<f64>,
    /// Index into `functions` per prescribed dof.
    pub function: Vec<usize>,
    /// The time functions `φ`.
    pub functions: Vec<TimeFunction>,
    /// The old (unreduced) dof of each prescribed dof.
    pub dofs: Vec<usize>,
    /// `M_pp` (prescribed × prescribed), for the energy of the prescribed dofs.
    pub mass_pp: SparseMatrix,
    /// `K_pp`.
    pub stiffness_pp: SparseMatrix,
    /// The constant force on the prescribed dofs (gravity), `f_p`.
    pub force: Vec<f64>,
}

impl Prescribed {
    /// What the prescribed dofs add to the energy of the kept dofs at `(t, q, v)`:
    /// `(vᵀ M_fp v_p + ½ v_pᵀ M_pp v_p, qᵀ K_fp u_p + ½ u_pᵀ K_pp u_p − f_pᵀ u_p)`, so that
    /// the sums are the whole structure's kinetic and potential energy. `vp` and `up`
    /// are scratch of one entry per prescribed dof.
    pub fn energy(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        vp: &mut [f64],
        up: &mut [f64],
    ) -> (f64, f64) {
        self.velocity_at(t, vp);
        self.displacement_at(t, up);
        let cross = |m: &SparseMatrix, x: &[f64], y: &[f64]| -> f64 {
            let m = m.as_ref();
            let mut s = 0.0;
            for (j, &yj) in y.iter().enumerate() {
                if yj != 0.0 {
                    for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                        s += x[m.row_idx()[k]] * m.val()[k] * yj;
                    }
                }
            }
            s
        };
        let kinetic = cross(&self.mass, v, vp) + 0.5 * quadratic_form(self.mass_pp.as_ref(), vp);
        let potential = cross(&self.stiffness, q, up)
            + 0.5 * quadratic_form(self.stiffness_pp.as_ref(), up)
            - self
                .force
                .iter()
                .zip(up.iter())
                .map(|(f, u)| f * u)
                .sum::<f64>();
        (kinetic, potential)
    }

    /// `v_p(t)` into `out`.
    pub fn velocity_at(&self, t: f64, out: &mut [f64]) {
        for ((o, &w), &f) in out.iter_mut().zip(&self.velocity).zip(&self.function) {
            *o = w * self.functions[f].eval(t);
        }
    }
    /// `u_p(t)` into `out`.
    pub fn displacement_at(&self, t: f64, out: &mut [f64]) {
        for ((o, &w), &f) in out.iter_mut().zip(&self.velocity).zip(&self.function) {
            *o = w * self.functions[f].integral(t);
        }
    }
}

/// A piecewise-linear function of time through `(t, value)` points (increasing `t`),
/// constant before the first point and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeFunction {
    points: Vec<(f64, f64)>,
}

impl TimeFunction {
    /// Checks the points (at least one, finite, strictly increasing times); `field`
    /// names them in errors.
    pub fn new(field: &str, points: Vec<(f64, f64)>) -> Result<Self, crate::error::Error> {
        if points.is_empty() {
            return Err(crate::error::Error::invalid(
                field,
                "[]",
                "needs at least one [time, value] point",
            ));
        }
        for (i, &(t, v)) in points.iter().enumerate() {
            if !(t.is_finite() && v.is_finite()) {
                return Err(crate::error::Error::invalid(
                    &format!("{field}[{i}]"),
                    format!("[{t}, {v}]"),
                    "must be finite",
                ));
            }
            if i > 0 && t <= points[i - 1].0 {
                return Err(crate::error::Error::invalid(
                    &format!("{field}[{i}]"),
                    t,
                    &format!("times must increase (previous {})", points[i - 1].0),
                ));
            }
        }
        Ok(TimeFunction { points })
    }

    /// The constant 1.
    pub fn one() -> Self {
        TimeFunction {
            points: vec![(0.0, 1.0)],
        }
    }

    /// `∫₀ᵗ φ` (exact for the piecewise-linear φ, constant extension on either side).
    pub fn integral(&self, t: f64) -> f64 {
        let p = &self.points;
        // ∫₀ᵗ = F(t) − F(0) with F the antiderivative from the first point
        let anti = |t: f64| -> f64 {
            if t <= p[0].0 {
                return (t - p[0].0) * p[0].1;
            }
            let mut acc = 0.0;
            for w in p.windows(2) {
                let ((t0, v0), (t1, v1)) = (w[0], w[1]);
                if t <= t1 {
                    let vt = v0 + (v1 - v0) * (t - t0) / (t1 - t0);
                    return acc + 0.5 * (v0 + vt) * (t - t0);
                }
                acc += 0.5 * (v0 + v1) * (t1 - t0);
            }
            let last = p[p.len() - 1];
            acc + (t - last.0) * last.1
        };
        anti(t) - anti(0.0)
    }

    /// The value at `t`.
    pub fn eval(&self, t: f64) -> f64 {
        let p = &self.points;
        if t <= p[0].0 {
            return p[0].1;
        }
        let last = p[p.len() - 1];
        if t >= last.0 {
            return last.1;
        }
        let k = p.partition_point(|&(tk, _)| tk <= t);
        let ((t0, v0), (t1, v1)) = (p[k - 1], p[k]);
        v0 + (v1 - v0) * (t - t0) / (t1 - t0)
    }
}

/// A load `φ(t) b` on a few dofs (`b` as dof/value pairs).
#[derive(Clone, Debug, PartialEq)]
pub struct NodalLoad {
    /// The dofs loaded.
    pub dofs: Vec<usize>,
    /// `b` on those dofs (N).
    pub values: Vec<f64>,
    /// `φ(t)`.
    pub time: TimeFunction,
}

impl LinearSystem {
    /// `out += s · Σ_i φ_i(t) b_i` (no allocation: the schemes call it every step).
    pub fn add_loads(&self, t: f64, s: f64, out: &mut [f64]) {
        for l in &self.loads {
            let f = s * l.time.eval(t);
            if f != 0.0 {
                for (&d, &b) in l.dofs.iter().zip(&l.values) {
                    out[d] += f * b;
                }
            }
        }
    }
}

/// Adds the element mass `me` (dense, `dofs.len()` square) to `asm` as `kind` asks;
/// `is_contact[a]` marks the element's local dofs that belong to contact nodes.
pub(crate) fn add_element_mass(
    asm: &mut impl crate::assembly::Accumulate,
    kind: MassKind,
    dofs: &[usize],
    me: impl Fn(usize, usize) -> f64,
    is_contact: impl Fn(usize) -> bool,
) {
    let n = dofs.len();
    let row_sum = |a: usize| (0..n).map(|b| me(a, b)).sum::<f64>();
    match kind {
        MassKind::Consistent => asm.add_element(dofs, me),
        MassKind::Lumped => {
            for (a, &i) in dofs.iter().enumerate() {
                asm.add(i, i, row_sum(a));
            }
        }
        MassKind::Redistributed => {
            let keep: Vec<usize> = (0..n).filter(|&a| !is_contact(a)).collect();
            if keep.len() == n {
                return asm.add_element(dofs, me);
            }
            if keep.is_empty() {
                // every node is a contact node: nothing to move the mass to; lump it
                for (a, &i) in dofs.iter().enumerate() {
                    asm.add(i, i, row_sum(a));
                }
                return;
            }
            // Keep the block of the non-contact dofs and put the rest of the element
            // mass on their diagonal, in proportion to their full row sums, so the
            // element mass is unchanged (for solids each displacement component keeps
            // its share, as the consistent mass is I ⊗ m).
            let total: f64 = (0..n).map(row_sum).sum();
            let kept_block: f64 = keep
                .iter()
                .flat_map(|&a| keep.iter().map(move |&b| (a, b)))
                .map(|(a, b)| me(a, b))
                .sum();
            let kept_rows: f64 = keep.iter().map(|&a| row_sum(a)).sum();
            for &a in &keep {
                for &b in &keep {
                    asm.add(dofs[a], dofs[b], me(a, b));
                }
                asm.add(
                    dofs[a],
                    dofs[a],
                    (total - kept_block) * row_sum(a) / kept_rows,
                );
            }
        }
    }
}

/// Component of each of `n` interleaved dofs with `d` components per node.
pub fn interleaved_components(n: usize, d: usize) -> Vec<u8> {
    (0..n).map(|i| (i % d) as u8).collect()
}

use crate::assembly::Accumulate;

impl LinearSystem {
    /// Joins independent systems into one block-diagonal system (dofs concatenated).
    pub fn block_diagonal(parts: Vec<LinearSystem>) -> Result<LinearSystem, crate::error::Error> {
        let d = parts[0].dofs_per_node;
        if parts.iter().any(|p| p.dofs_per_node != d) {
            return Err(crate::error::Error::invalid(
                "bodies",
                "mixed dimensions",
                "every body must have the same number of displacement components",
            ));
        }
        assert!(
            parts.iter().all(|p| p.nonlinear.is_empty()),
            "internal forces are attached after the join"
        );
        if parts.len() == 1 {
            return Ok(parts.into_iter().next().expect("one part"));
        }
        let n: usize = parts.iter().map(|p| p.ndof()).sum();
        let any_damping = parts.iter().any(|p| p.damping.is_some());
        let join = |pick: &dyn Fn(&LinearSystem) -> Option<&SparseMatrix>| {
            let mut asm = crate::assembly::Assembler::new(n, 0);
            let mut off = 0;
            for p in &parts {
                if let Some(m) = pick(p) {
                    let m = m.as_ref();
                    for j in 0..m.ncols() {
                        for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                            asm.add(off + m.row_idx()[k], off + j, m.val()[k]);
                        }
                    }
                }
                off += p.ndof();
            }
            asm.finish()
        };
        Ok(LinearSystem {
            mass: join(&|p| Some(&p.mass)),
            stiffness: join(&|p| Some(&p.stiffness)),
            damping: any_damping.then(|| join(&|p| p.damping.as_ref())),
            force: parts.iter().flat_map(|p| p.force.iter().copied()).collect(),
            dofs_per_node: d,
            component: parts
                .iter()
                .flat_map(|p| p.component.iter().copied())
                .collect(),
            ordering: None,
            prescribed: None,
            nonlinear: Vec::new(),
            loads: {
                let mut off = 0;
                let mut loads = Vec::new();
                for p in parts {
                    for l in &p.loads {
                        loads.push(NodalLoad {
                            dofs: l.dofs.iter().map(|d| d + off).collect(),
                            ..l.clone()
                        });
                    }
                    off += p.ndof();
                }
                loads
            },
        })
    }

    /// Removes the dofs marked `fixed` (homogeneous Dirichlet conditions, u = 0) and those
    /// with a prescribed velocity (`prescribed[i] = Some((w, function))`, keeping their
    /// coupling blocks, see [`Prescribed`]). Returns the reduced system and, for each old
    /// dof, its new index.
    pub fn restrict_prescribed(
        &self,
        fixed: &[bool],
        prescribed: &[Option<(f64, usize)>],
        functions: Vec<TimeFunction>,
    ) -> (LinearSystem, Vec<Option<usize>>) {
        let gone: Vec<bool> = fixed
            .iter()
            .zip(prescribed)
            .map(|(&f, p)| f || p.is_some())
            .collect();
        let (mut sys, map) = self.restrict(&gone);
        let pdofs: Vec<usize> = (0..self.ndof())
            .filter(|&i| !fixed[i] && prescribed[i].is_some())
            .collect();
        if pdofs.is_empty() {
            return (sys, map);
        }
        let nf = sys.ndof();
        // columns of the prescribed dofs, rows of the kept ones
        let block = |m: &SparseMatrix| {
            let m = m.as_ref();
            let mut col_ptr = vec![0];
            let (mut rows, mut vals) = (Vec::new(), Vec::new());
            for &j in &pdofs {
                for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                    if let Some(a) = map[m.row_idx()[k]] {
                        rows.push(a);
                        vals.push(m.val()[k]);
                    }
                }
                col_ptr.push(rows.len());
            }
            let sym = faer::sparse::SymbolicSparseColMat::new_checked(
                nf,
                pdofs.len(),
                col_ptr,
                None,
                rows,
            );
            SparseMatrix::new(sym, vals)
        };
        // rows and columns of the prescribed dofs
        let mut pos = vec![usize::MAX; self.ndof()];
        for (a, &i) in pdofs.iter().enumerate() {
            pos[i] = a;
        }
        let pp = |m: &SparseMatrix| {
            let m = m.as_ref();
            let mut col_ptr = vec![0];
            let (mut rows, mut vals) = (Vec::new(), Vec::new());
            for &j in &pdofs {
                for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                    let a = pos[m.row_idx()[k]];
                    if a != usize::MAX {
                        rows.push(a);
                        vals.push(m.val()[k]);
                    }
                }
                col_ptr.push(rows.len());
            }
            let n = pdofs.len();
            let sym = faer::sparse::SymbolicSparseColMat::new_checked(n, n, col_ptr, None, rows);
            SparseMatrix::new(sym, vals)
        };
        sys.prescribed = Some(Prescribed {
            mass: block(&self.mass),
            stiffness: block(&self.stiffness),
            damping: self.damping.as_ref().map(block),
            velocity: pdofs
                .iter()
                .map(|&i| prescribed[i].expect("prescribed").0)
                .collect(),
            function: pdofs
                .iter()
                .map(|&i| prescribed[i].expect("prescribed").1)
                .collect(),
            functions,
            mass_pp: pp(&self.mass),
            stiffness_pp: pp(&self.stiffness),
            force: pdofs.iter().map(|&i| self.force[i]).collect(),
            dofs: pdofs,
        });
        (sys, map)
    }

    /// Removes the dofs marked `fixed` (homogeneous Dirichlet conditions, u = 0).
    /// Returns the reduced system and, for each old dof, its new index.
    pub fn restrict(&self, fixed: &[bool]) -> (LinearSystem, Vec<Option<usize>>) {
        assert!(
            self.nonlinear.is_empty(),
            "internal forces are attached after the restriction"
        );
        let mut map = vec![None; self.ndof()];
        let mut next = 0;
        for (i, f) in fixed.iter().enumerate() {
            if !f {
                map[i] = Some(next);
                next += 1;
            }
        }
        // The map is increasing, so kept rows stay sorted within each kept column: the
        // sub-matrix is a filter of the compressed columns (no triplets, no sort).
        let sub = |m: &SparseMatrix| {
            let m = m.as_ref();
            let mut col_ptr = Vec::with_capacity(next + 1);
            let mut row_idx = Vec::with_capacity(m.compute_nnz());
            let mut values = Vec::with_capacity(m.compute_nnz());
            col_ptr.push(0);
            for j in (0..m.ncols()).filter(|&j| map[j].is_some()) {
                for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                    if let Some(a) = map[m.row_idx()[k]] {
                        row_idx.push(a);
                        values.push(m.val()[k]);
                    }
                }
                col_ptr.push(row_idx.len());
            }
            let sym =
                faer::sparse::SymbolicSparseColMat::new_checked(next, next, col_ptr, None, row_idx);
            SparseMatrix::new(sym, values)
        };
        let sys = LinearSystem {
            mass: sub(&self.mass),
            stiffness: sub(&self.stiffness),
            damping: self.damping.as_ref().map(sub),
            force: (0..self.ndof())
                .filter(|&i| map[i].is_some())
                .map(|i| self.force[i])
                .collect(),
            dofs_per_node: self.dofs_per_node,
            component: (0..self.ndof())
                .filter(|&i| map[i].is_some())
                .map(|i| self.component[i])
                .collect(),
            ordering: None,
            prescribed: None,
            nonlinear: Vec::new(),
            loads: self
                .loads
                .iter()
                .map(|l| {
                    let (dofs, values) = l
                        .dofs
                        .iter()
                        .zip(&l.values)
                        .filter_map(|(&d, &b)| map[d].map(|a| (a, b)))
                        .unzip();
                    NodalLoad {
                        dofs,
                        values,
                        time: l.time.clone(),
                    }
                })
                .collect(),
        };
        (sys, map)
    }

    /// Adds Rayleigh damping `C = αM + βK`.
    pub fn with_rayleigh(mut self, alpha: f64, beta: f64) -> Result<Self, crate::error::Error> {
        crate::error::require_in("damping.alpha", alpha, 0.0, f64::MAX)?;
        crate::error::require_in("damping.beta", beta, 0.0, f64::MAX)?;
        if alpha > 0.0 || beta > 0.0 {
            self.damping = Some(crate::assembly::linear_combination(&[
                (alpha, &self.mass),
                (beta, &self.stiffness),
            ]));
        }
        Ok(self)
    }

    /// Adds the body force of a uniform acceleration field `g` (m/s²): `f += M g`,
    /// exact for consistent and lumped mass since the shape functions sum to one.
    pub fn add_gravity(&mut self, g: &[f64]) -> Result<(), crate::error::Error> {
        let d = self.dofs_per_node;
        if g.len() != d || g.iter().any(|x| !x.is_finite()) {
            return Err(crate::error::Error::invalid(
                "gravity",
                format!("{g:?}"),
                &format!("needs {d} finite components"),
            ));
        }
        let gv: Vec<f64> = self.component.iter().map(|&c| g[c as usize]).collect();
        crate::linalg::spmv_add(self.mass.as_ref(), 1.0, &gv, &mut self.force);
        Ok(())
    }

    /// Number of degrees of freedom.
    pub fn ndof(&self) -> usize {
        self.mass.nrows()
    }

    /// The whole structure's kinetic and potential energy at `(t, q, v)` (J): those of
    /// the kept dofs ([`LinearSystem::kinetic_energy`], [`LinearSystem::potential_energy`])
    /// plus what the prescribed dofs add ([`Prescribed::energy`]). `scratch` holds at
    /// least twice [`LinearSystem::prescribed_dofs`] values.
    pub fn energies(&self, t: f64, q: &[f64], v: &[f64], scratch: &mut [f64]) -> (f64, f64) {
        let (k, u) = self.prescribed_energy(t, q, v, scratch);
        (self.kinetic_energy(q, v) + k, self.potential_energy(q) + u)
    }

    /// What the prescribed dofs add to the kept dofs' kinetic and potential energy at
    /// `(t, q, v)` ([`Prescribed::energy`]; `(0, 0)` without them). `scratch` as for
    /// [`LinearSystem::energies`].
    pub fn prescribed_energy(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
    ) -> (f64, f64) {
        match &self.prescribed {
            Some(p) => {
                let (vp, up) = scratch[..2 * p.velocity.len()].split_at_mut(p.velocity.len());
                p.energy(t, q, v, vp, up)
            }
            None => (0.0, 0.0),
        }
    }

    /// [`LinearSystem::energies`] summed, with its own scratch (allocates: for the start
    /// and end of a run, not per step).
    pub fn total_energy(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let (ke, pe) = self.energies(t, q, v, &mut vec![0.0; 2 * self.prescribed_dofs()]);
        ke + pe
    }

    /// Number of prescribed (eliminated) dofs.
    pub fn prescribed_dofs(&self) -> usize {
        self.prescribed.as_ref().map_or(0, |p| p.velocity.len())
    }

    /// The layouts of `M` and `K` read once, for [`LinearSystem::energies_with`].
    pub fn energy_forms(&self) -> EnergyForms {
        EnergyForms {
            mass: QuadraticForm::new(self.mass.as_ref()),
            stiffness: QuadraticForm::new(self.stiffness.as_ref()),
            unloaded: self.force.iter().all(|&f| f == 0.0),
        }
    }

    /// [`LinearSystem::energies`] through `forms` (from [`LinearSystem::energy_forms`]
    /// of this system): the same energies, their sums reordered for speed (they differ
    /// by round-off). Does not allocate; what each history row calls.
    pub fn energies_with(
        &self,
        forms: &EnergyForms,
        t: f64,
        q: &[f64],
        v: &[f64],
        scratch: &mut [f64],
    ) -> (f64, f64) {
        let (k, u) = self.prescribed_energy(t, q, v, scratch);
        let kinetic = 0.5 * forms.mass.eval(self.mass.as_ref(), v) + self.parts_kinetic(q, v);
        let mut potential = 0.5 * forms.stiffness.eval(self.stiffness.as_ref(), q);
        if !forms.unloaded {
            potential -= crate::linalg::dot_lanes(&self.force, q);
        }
        (kinetic + k, potential + self.parts_potential(q) + u)
    }

    /// The nonlinear parts' kinetic energy (0 without them).
    fn parts_kinetic(&self, q: &[f64], v: &[f64]) -> f64 {
        self.nonlinear
            .iter()
            .map(|p| p.kinetic_energy(q, v))
            .sum::<f64>()
    }

    /// The nonlinear parts' internal energy (0 without them; NaN where a cell is
    /// inverted).
    fn parts_potential(&self, q: &[f64]) -> f64 {
        if self.nonlinear.is_empty() {
            return 0.0;
        }
        self.nonlinear
            .iter()
            .map(|r| r.energy(q).unwrap_or(f64::NAN))
            .sum::<f64>()
    }

    /// Kinetic energy of the kept dofs `½ vᵀ M(q) v` (J; `q` matters only with a mass
    /// part, [`system::NonlinearPart::mass_entries`]).
    pub fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64 {
        // without parts the sum is a zero, which keeps the constant term bit for bit
        0.5 * quadratic_form(self.mass.as_ref(), v)
            + self
                .nonlinear
                .iter()
                .map(|p| p.kinetic_energy(q, v))
                .sum::<f64>()
    }

    /// Potential energy of the kept dofs `½ qᵀ K q − fᵀ q` (J): elastic energy plus the
    /// potential of the constant external force, plus the energies of the nonlinear
    /// internal forces ([`system::NonlinearPart::energy`]; NaN where a cell is inverted).
    pub fn potential_energy(&self, q: &[f64]) -> f64 {
        let linear = 0.5 * quadratic_form(self.stiffness.as_ref(), q)
            - self.force.iter().zip(q).map(|(f, x)| f * x).sum::<f64>();
        if self.nonlinear.is_empty() {
            return linear;
        }
        linear
            + self
                .nonlinear
                .iter()
                .map(|r| r.energy(q).unwrap_or(f64::NAN))
                .sum::<f64>()
    }

    /// Linear momentum along the first axis, `e_xᵀ M v` (kg·m/s), where `e_x` is 1 on
    /// every x-component dof.
    pub fn momentum(&self, v: &[f64]) -> f64 {
        let m = self.mass.as_ref();
        let mut s = 0.0;
        for (j, &vj) in v.iter().enumerate() {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if self.component[m.row_idx()[k]] == 0 {
                    s += m.val()[k] * vj;
                }
            }
        }
        s
    }

    /// Total mass `e_xᵀ M e_x` (kg).
    pub fn total_mass(&self) -> f64 {
        let m = self.mass.as_ref();
        let mut s = 0.0;
        for j in (0..m.ncols()).filter(|&j| self.component[j] == 0) {
            for k in m.col_ptr()[j]..m.col_ptr()[j + 1] {
                if self.component[m.row_idx()[k]] == 0 {
                    s += m.val()[k];
                }
            }
        }
        s
    }
}
