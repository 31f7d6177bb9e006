//! Grid reset: every step starts from the undeformed, empty background grid (paper step 8).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::NodeBox;
use crate::infra::columns::{col_mut, nodes};
use crate::parallel::fill_box;
use crate::schedule::System;

/// Zeroes the nodes of last step's box (see `SolverState::active_nodes`).
#[derive(Debug, Default)]
pub struct GridReset;

impl<D: Dim> System<D> for GridReset {
    fn name(&self) -> &str {
        "grid_reset"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        let (b, grid, z) = (ctx.state.active_nodes, &ctx.grid, D::Vec::ZERO);
        // Only last step's box can hold anything (see `SolverState::active_nodes`).
        fill_box(grid, b, &mut col_mut::<NodeMass>(n), NodeMass(0.0));
        fill_box(grid, b, &mut col_mut::<NodeMomentum<D::Vec>>(n), NodeMomentum(z));
        fill_box(grid, b, &mut col_mut::<NodeForce<D::Vec>>(n), NodeForce(z));
        fill_box(
            grid,
            b,
            &mut col_mut::<NodeExternalForce<D::Vec>>(n),
            NodeExternalForce(z),
        );
        fill_box(
            grid,
            b,
            &mut col_mut::<NodeAcceleration<D::Vec>>(n),
            NodeAcceleration(z),
        );
        fill_box(grid, b, &mut col_mut::<NodeVelocity<D::Vec>>(n), NodeVelocity(z));
        ctx.state.active_nodes = NodeBox::default();
        ctx.exchanged = 0;
        Ok(())
    }
}
