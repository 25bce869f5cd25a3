//! The impacting bar as a 3-D solid: a square-section box of hex8 (or tet4) cells
//! along x, hitting the rigid plane `x = −gap` with every node of its `x0` face.
//! With ν = 0 the axial response is the rod's, so the summed contact force has the
//! same analytic plateau `E S |v0| / c0` (sec. 6.2).

use crate::integrators::Problem;
use serde::{Deserialize, Serialize};

use crate::analytic::ImpactingBar;
use crate::contact::plane::NodesOnPlane;
use crate::error::{Error, require_finite, require_in, require_positive};
use crate::integrators::SchemeParams;
use crate::io::frames::{GeomCell, Geometry};
use crate::model::MassKind;
use crate::model::generate::box_mesh;
use crate::model::solid::{CellKind, Formulation, Material, assemble};
use crate::scene::Model;

/// Parameters of the 3-D bar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolidBarScene {
    /// Cells along the length.
    pub cells_along: usize,
    /// Cells across each side of the section.
    pub cells_across: usize,
    /// Hex8 or tet4.
    pub cell: CellKind,
    /// Time step (s).
    pub dt: f64,
    /// End time (s).
    pub t_end: f64,
    /// Length (m).
    pub length: f64,
    /// Section area (m²); the section is a square of side √S.
    pub area: f64,
    /// Material (ν = 0 makes the axial motion one-dimensional).
    pub material: Material,
    /// Initial x-velocity (m/s).
    pub velocity: f64,
    /// Initial gap (m).
    pub gap: f64,
    /// Restitution.
    pub restitution: f64,
    /// Mass kind.
    pub mass: MassKind,
    /// Scheme.
    pub scheme: SchemeParams,
}

impl Default for SolidBarScene {
    fn default() -> Self {
        SolidBarScene {
            cells_along: 100,
            cells_across: 1,
            cell: CellKind::Hex8,
            dt: 2e-6,
            t_end: 1e-3,
            length: 1.0,
            area: std::f64::consts::PI * 1e-4,
            material: Material {
                young: 210e9,
                poisson: 0.0,
                density: 7800.0,
                model: crate::model::solid::MaterialModel::LINEAR,
            },
            velocity: -0.1,
            gap: 0.0,
            restitution: 0.0,
            mass: MassKind::Consistent,
            scheme: SchemeParams::default(),
        }
    }
}

impl SolidBarScene {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), Error> {
        if self.cells_along == 0 || self.cells_across == 0 {
            return Err(Error::invalid(
                "cells_along/cells_across",
                0,
                "must be at least 1",
            ));
        }
        if self.cell.dim() != 3 {
            return Err(Error::invalid(
                "cell",
                self.cell.name(),
                "must be hex8 or tet4",
            ));
        }
        require_positive("dt", self.dt)?;
        require_positive("t_end", self.t_end)?;
        require_positive("length", self.length)?;
        require_positive("area", self.area)?;
        require_finite("velocity", self.velocity)?;
        require_in("gap", self.gap, 0.0, f64::MAX)?;
        self.material.validate()?;
        crate::limits::step_count(self.t_end, self.dt, "t_end", "dt")?;
        self.scheme.validate()
    }

    /// Number of steps.
    pub fn steps(&self) -> usize {
        crate::limits::step_count(self.t_end, self.dt, "t_end", "dt").unwrap_or(0)
    }

    /// Meshes and assembles the bar, with its `x0` face nodes as contacts.
    pub fn build(&self) -> Result<Model, Error> {
        self.validate()?;
        let a = self.area.sqrt();
        let mesh = box_mesh(
            self.cell,
            [self.cells_along, self.cells_across, self.cells_across],
            [self.length, a, a],
        );
        let system = assemble(&mesh, &self.material, Formulation::Solid, self.mass)?;
        let face = &mesh.node_sets["x0"];
        let contacts = NodesOnPlane::new(
            face.iter()
                .map(|&v| vec![3 * v, 3 * v + 1, 3 * v + 2])
                .collect(),
            face.iter().map(|&v| mesh.points[v].to_vec()).collect(),
            vec![1.0, 0.0, 0.0],
            -self.gap,
            self.restitution,
        )?;
        let n = system.ndof();
        let mut v0 = vec![0.0; n];
        for v in v0.iter_mut().step_by(3) {
            *v = self.velocity;
        }
        let geometry = Geometry {
            points: mesh.points.clone(),
            cells: mesh
                .cells
                .iter()
                .map(|(k, c)| (GeomCell::Solid(*k), c.clone(), 0))
                .collect(),
            bodies: vec![(self.material, Formulation::Solid)],
            dim: 3,
            dof_of: (0..n).map(Some).collect(),
            contacts: face
                .iter()
                .map(|&v| crate::model::geometry::ContactPoint {
                    point: v,
                    body: 0,
                    target: "wall".to_string(),
                    entry: 0,
                })
                .collect(),
            ..Geometry::default()
        };
        let mut system = system;
        system.ordering = crate::model::ordering::candidate(self.scheme.ordering, &geometry, n)
            .map_err(|e| Error::invalid("scheme.ordering", self.scheme.ordering.name(), &e))?;
        Ok(Model {
            problem: Problem::new(system, Box::new(contacts), vec![0.0; n], v0),
            geometry,
            probes: Vec::new(),
            starting_gaps: Default::default(),
        })
    }

    /// The 1-D analytic reference.
    pub fn analytic(&self) -> Option<ImpactingBar> {
        (self.velocity < 0.0).then_some(ImpactingBar {
            length: self.length,
            area: self.area,
            young: self.material.young,
            density: self.material.density,
            velocity: self.velocity,
        })
    }
}
