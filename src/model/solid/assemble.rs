//! The parallel assembly of the element kernels into the global `M` and `K` (with the
//! contact nodes named for a redistributed mass), and the mesh checks before it (finite
//! coordinates, cells of the formulation's dimension, node numbers in range).

use super::*;
use crate::model::element::{Lumping, MAX_NODES};

/// Assembles `M` and `K` of a mesh in parallel (rayon; each task owns a range of
/// columns of the one pattern, see [`PatternAssembler::par_assemble_pair`]); the result
/// does not depend on the thread count. `contact_nodes` matter only for
/// [`MassKind::Redistributed`].
pub fn assemble(
    mesh: &Mesh,
    mat: &Material,
    f: Formulation,
    mass: MassKind,
) -> Result<LinearSystem, Error> {
    assemble_with_contacts(mesh, mat, f, mass, &[])
}

/// Checks `mesh` against formulation `f` before anything reads it: finite coordinates
/// (`x = r ≥ 0` for an axisymmetric body), cells of the formulation's dimension with
/// their node counts and node numbers in range. Errors name the node or cell by its file
/// tag.
pub fn check_mesh(mesh: &Mesh, f: Formulation) -> Result<(), Error> {
    let dim = f.dim();
    for (i, p) in mesh.points.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(
                &mesh.node_label(i),
                format!("{p:?}"),
                "coordinates must be finite",
            ));
        }
        if f == Formulation::Axisymmetric && p[0] < 0.0 {
            return Err(Error::invalid(
                &mesh.node_label(i),
                format!("{p:?}"),
                "an axisymmetric mesh lies in the half plane x = r ≥ 0 (y is the axis)",
            ));
        }
    }
    for (id, (kind, nodes)) in mesh.cells.iter().enumerate() {
        if kind.dim() != dim {
            // named by the formulation the user chose (issue 34: a tet4 mesh given
            // `axisymmetric` was blamed on an obstacle's point or a negative radius)
            return Err(Error::invalid(
                "formulation",
                f.name(),
                &format!(
                    "takes {dim}-D cells ({}), and cell {} of the mesh is {}: give \
                     formulation = {}",
                    CellKind::names(Some(dim)),
                    mesh.cell_ids.get(id).map_or(id as u64, |&t| t),
                    kind.name(),
                    if dim == 3 {
                        "\"plane-strain\", \"plane-stress\" or \"axisymmetric\" for a 2-D mesh"
                    } else {
                        "\"solid\" (the default) for a 3-D mesh"
                    }
                ),
            ));
        }
        if nodes.len() != kind.nodes() {
            return Err(Error::invalid(
                &format!("cell {id}"),
                format!("{} nodes", nodes.len()),
                &format!("{} needs {}", kind.name(), kind.nodes()),
            ));
        }
        if let Some(&bad) = nodes.iter().find(|&&v| v >= mesh.points.len()) {
            return Err(Error::invalid(
                &format!("cell {id}"),
                format!("node {bad}"),
                &format!("mesh has {} nodes", mesh.points.len()),
            ));
        }
    }
    Ok(())
}

/// [`assemble`] with the contact nodes named (for the redistributed mass).
pub fn assemble_with_contacts(
    mesh: &Mesh,
    mat: &Material,
    f: Formulation,
    mass: MassKind,
    contact_nodes: &[usize],
) -> Result<LinearSystem, Error> {
    let mut is_contact_node = vec![false; mesh.points.len()];
    for &v in contact_nodes {
        if v < is_contact_node.len() {
            is_contact_node[v] = true;
        }
    }
    mat.validate()?;
    if let Formulation::PlaneStress { thickness } = f {
        require_positive("thickness", thickness)?;
    }
    check_mesh(mesh, f)?;
    if mass == MassKind::Redistributed
        && let Some((kind, _)) = mesh
            .cells
            .iter()
            .find(|(k, _)| k.element().lumping() != Lumping::RowSum)
    {
        return Err(Error::invalid(
            "mass",
            "redistributed",
            &format!(
                "moves a cell's mass off its contact nodes by row sums, which are zero or \
                 negative at the corners of a {} cell: give mass = \"consistent\" or \
                 \"lumped\" (HRZ for quadratic cells)",
                kind.name()
            ),
        ));
    }
    let dim = f.dim();
    let n = mesh.points.len() * dim;
    let cell_nodes: Vec<&[usize]> = mesh.cells.iter().map(|(_, c)| c.as_slice()).collect();
    let mut ak = PatternAssembler::new(mesh.points.len(), dim, &cell_nodes);
    let mut am = ak.zeroed_like();
    ak.par_assemble_pair(&mut am, &cell_nodes, |id, k, m| {
        let (kind, nodes) = &mesh.cells[id];
        let mut x = [[0.0; 3]; MAX_NODES];
        let mut dofs = [0usize; 3 * MAX_NODES];
        for (a, &v) in nodes.iter().enumerate() {
            x[a] = mesh.points[v];
            for i in 0..dim {
                dofs[a * dim + i] = v * dim + i;
            }
        }
        let nd = nodes.len() * dim;
        let (x, dofs) = (&x[..nodes.len()], &dofs[..nd]);
        let e = element_matrices(id, *kind, x, mat, f)?;
        k.add_element(dofs, |a, b| e.k(a, b));
        super::super::add_element_mass(
            m,
            (mass, kind.element().lumping()),
            dofs,
            |a, b| e.m(a, b),
            |a| is_contact_node[dofs[a] / dim],
        );
        Ok(())
    })
    .map_err(|(id, e)| match (&mesh.source, e) {
        // a cell of a mesh file: name the file and the file's own element id
        (
            Some(file),
            Error::InvalidParameter {
                field,
                value,
                reason,
            },
        ) => Error::bad_file(
            file,
            format!(
                "element {}",
                mesh.cell_ids.get(id).copied().unwrap_or(id as u64)
            ),
            format!("{field}: {value}: {reason}"),
        ),
        (_, e) => e,
    })?;
    Ok(LinearSystem {
        mass: am.finish(),
        stiffness: ak.finish(),
        damping: None,
        force: vec![0.0; n],
        dofs_per_node: dim,
        component: super::super::interleaved_components(n, dim),
        ordering: None,
        loads: Vec::new(),
        prescribed: None,
        nonlinear: Vec::new(),
    })
}
