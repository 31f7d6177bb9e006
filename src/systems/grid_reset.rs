//! Grid reset: every step starts from the undeformed, empty background grid (paper step 8).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::NodeBox;
use crate::infra::columns::{col_mut, nodes};
use crate::infra::traffic::Traffic;
use crate::parallel::fill_box;
use crate::schedule::System;

/// Zeroes the nodes of last step's box (see `SolverState::active_nodes`).
#[derive(Debug, Default)]
pub struct GridReset {
    /// Nodes zeroed by the last call (for the byte budget).
    zeroed: usize,
}

impl<D: Dim> System<D> for GridReset {
    fn name(&self) -> &str {
        "grid_reset"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        let (b, grid, z) = (ctx.state.active_nodes, &ctx.grid, D::Vec::ZERO);
        self.zeroed = b.len();
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
    fn traffic(&self, _: &Context<D>) -> Option<Traffic> {
        let n = self.zeroed;
        Some(
            Traffic::NONE
                .write_nodes::<NodeMass>(n)
                .write_nodes::<NodeMomentum<D::Vec>>(n)
                .write_nodes::<NodeForce<D::Vec>>(n)
                .write_nodes::<NodeExternalForce<D::Vec>>(n)
                .write_nodes::<NodeAcceleration<D::Vec>>(n)
                .write_nodes::<NodeVelocity<D::Vec>>(n),
        )
    }
}
