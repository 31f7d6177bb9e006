//! Nodal velocity from mapped momentum, v_i = p_i/m_i, with the boundary conditions.

use super::shared::constrain;
use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes};
use crate::infra::traffic::Traffic;
use crate::parallel::{for_each_box_node, Disjoint};
use crate::schedule::System;

/// Sets `NodeVelocity` from `NodeMomentum` and `NodeMass` (zero on massless nodes and on
/// fixed components). Used by the MUSL remap and by USF before its stress update.
pub fn velocity_from_momentum<D: Dim>(ctx: &Context<D>) {
    let min_mass = ctx.numerics.min_node_mass;
    let n = nodes(&ctx.world);
    let nm = col::<NodeMass>(n);
    let np = col::<NodeMomentum<D::Vec>>(n);
    let fix = col::<NodeFixity>(n);
    // Plain slices: the column guards cannot be shared with the pool.
    let (nm, np, fix) = (&*nm, &*np, &*fix);
    let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
    let (grid, drives) = (&ctx.grid, &ctx.state.control.drives[..]);
    for_each_box_node(
        grid,
        ctx.state.active_nodes,
        &Disjoint::new(&mut nv),
        |i, k, nv| {
            let mut v = if grid.carries(i, nm[i].0, min_mass) {
                np[i].0 * (1.0 / nm[i].0)
            } else {
                D::Vec::ZERO
            };
            constrain(&mut v, fix[i], D::N, drives);
            nv[k].0 = v;
        },
    );
}

/// The bytes [`velocity_from_momentum`] moves over `nodes` nodes.
pub fn velocity_from_momentum_traffic<D: Dim>(nodes: usize) -> Traffic {
    Traffic::NONE
        .read_nodes::<NodeMass>(nodes)
        .read_nodes::<NodeMomentum<D::Vec>>(nodes)
        .read_nodes::<NodeFixity>(nodes)
        .write_nodes::<NodeVelocity<D::Vec>>(nodes)
}

/// USF's nodal velocity at the start of the step.
#[derive(Debug, Default)]
pub struct NodalVelocity;

impl<D: Dim> System<D> for NodalVelocity {
    fn name(&self) -> &str {
        "nodal_velocity"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        velocity_from_momentum(ctx);
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        Some(velocity_from_momentum_traffic::<D>(ctx.state.active_nodes.len()))
    }
}
