//! Putting a structure together from its bodies: systems joined block-diagonally,
//! fixed and prescribed dofs eliminated (the prescribed coupling blocks kept for the
//! step's loads), Rayleigh damping and gravity added.

use super::*;

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
}
