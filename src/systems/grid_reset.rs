//! Grid reset: every step starts from the undeformed, empty background grid (paper step 8).

use crate::columns::{col_mut, nodes};
use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::NodeBox;
use crate::schedule::System;
use crate::simulation::Context;

/// Zeroes the nodes of last step's box (see `SolverState::active_nodes`).
#[derive(Debug, Default)]
pub struct GridReset;

impl<D: Dim> System<D> for GridReset {
    fn name(&self) -> &str {
        "grid_reset"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        let mut nm = col_mut::<NodeMass>(n);
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        let mut na = col_mut::<NodeAcceleration<D::Vec>>(n);
        let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
        // Only last step's box can hold anything (see `SolverState::active_nodes`).
        for r in ctx.state.active_nodes.rows(&ctx.grid) {
            nm[r.clone()].fill(NodeMass(0.0));
            np[r.clone()].fill(NodeMomentum(D::Vec::ZERO));
            nf[r.clone()].fill(NodeForce(D::Vec::ZERO));
            ne[r.clone()].fill(NodeExternalForce(D::Vec::ZERO));
            na[r.clone()].fill(NodeAcceleration(D::Vec::ZERO));
            nv[r].fill(NodeVelocity(D::Vec::ZERO));
        }
        drop((nm, np, nf, ne, na, nv));
        ctx.state.active_nodes = NodeBox::default();
        Ok(())
    }
}
