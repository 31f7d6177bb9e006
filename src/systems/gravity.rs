//! Gravity: body force on the grid. Scheduled only when the scene has gravity.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes};
use crate::infra::traffic::Traffic;
use crate::parallel::{for_each_box_node, Disjoint};
use crate::schedule::System;
/// Adds m_i·g to every node, g from `Settings::gravity` (which a loading stage may change).
/// Since Σ_p w_ip m_p = m_i, this equals mapping each point's weight m_p·g, at the cost of
/// a grid pass instead of a point pass.
#[derive(Debug, Default)]
pub struct Gravity;

impl<D: Dim> System<D> for Gravity {
    fn name(&self) -> &str {
        "gravity"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let Some(spec) = ctx.model.gravity else {
            return Ok(());
        };
        let g = spec.step_factor(ctx.state.clock.time, ctx.numerics.dt);
        let a = spec.acceleration;
        let gv = D::vec_from([a[0] * g, a[1] * g, a[2] * g]);
        let n = nodes(&ctx.world);
        let nm = col::<NodeMass>(n);
        let nm = &*nm; // a plain slice: the column guard cannot be shared with the pool
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        let target = (Disjoint::new(&mut nf), Disjoint::new(&mut ne));
        // Over MPI the node mass is already whole (summed after the mapping) and the forces
        // are summed next: each node gets its weight from the rank that owns it only.
        let owned = ctx.owned_node_ids();
        let own = |i: usize| owned.as_ref().is_none_or(|o| o.contains(&i));
        for_each_box_node(&ctx.grid, ctx.state.active_nodes, &target, |i, k, (nf, ne)| {
            if nm[i].0 > 0.0 && own(i) {
                let w = gv * nm[i].0;
                nf[k].0 += w;
                ne[k].0 += w;
            }
        });
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let n = if ctx.model.gravity.is_some() {
            ctx.state.active_nodes.len()
        } else {
            0
        };
        Some(
            Traffic::NONE
                .read_nodes::<NodeMass>(n)
                .update_nodes::<NodeForce<D::Vec>>(n)
                .update_nodes::<NodeExternalForce<D::Vec>>(n),
        )
    }
}
