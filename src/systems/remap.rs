//! MUSL remap: the updated point velocities mapped back to the grid (paper step 6).

use super::nodal_velocity::{velocity_from_momentum, velocity_from_momentum_traffic};
use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::{fill_box, scatter, Disjoint};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::exchange::{exchange_again, MOMENTUM};
use std::marker::PhantomData;

/// p_i = Σ_p w_ip m_p v_p with the new v_p, then v_i = p_i/m_i with boundary conditions
/// (the rigid bodies' contacts are held on it next, by `remap_contact`). After a
/// kinetic-damping reset all v_p are zero, and so is the remapped field.
#[derive(Debug)]
pub struct Remap<D: Dim, S> {
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for Remap<D, S> {
    fn default() -> Self {
        Remap { _marker: PhantomData }
    }
}

impl<D: Dim, S: Shape> System<D> for Remap<D, S> {
    fn name(&self) -> &str {
        "remap"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        if ctx.state.resets.this_step {
            let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
            fill_box(
                &ctx.grid,
                ctx.state.active_nodes,
                &mut nv,
                NodeVelocity(D::Vec::ZERO),
            );
            return Ok(());
        }
        {
            let grid = &ctx.grid;
            let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
            fill_box(grid, ctx.state.active_nodes, &mut np, NodeMomentum(D::Vec::ZERO));
            let mut reached = ctx.state.active_nodes;
            for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
                let (xg, mg, vg) = (
                    col::<Position<D::Vec>>(arch),
                    col::<Mass>(arch),
                    col::<Velocity<D::Vec>>(arch),
                );
                let (x, m): (&[Position<D::Vec>], &[Mass]) = (&xg, &mg);
                let v: &[Velocity<D::Vec>] = &vg;
                reached = reached.union(scatter(
                    ctx.slabs.slabs(grid, x),
                    grid,
                    S::SUPPORT,
                    &Disjoint::new(&mut np),
                    |points, np, lo| {
                        for &p in points {
                            let p = p as usize;
                            let mv = v[p].0 * m[p].0;
                            for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                                let n = &mut np[i - lo].0;
                                *n = mv.madd(w, *n);
                            });
                        }
                    },
                ));
            }
            ctx.state.active_nodes = reached;
        }
        exchange_again(ctx, MOMENTUM);
        velocity_from_momentum(ctx);
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let (w, n) = (&ctx.world, ctx.state.active_nodes.len());
        if ctx.state.resets.this_step {
            return Some(Traffic::NONE.write_nodes::<NodeVelocity<D::Vec>>(n));
        }
        let mut t = Traffic::NONE
            // Zeroed, then the scatter's sums.
            .write_nodes::<NodeMomentum<D::Vec>>(n)
            .update_nodes::<NodeMomentum<D::Vec>>(n)
            .read_order::<Velocity<D::Vec>>(w)
            .read_points::<Position<D::Vec>>(w)
            .read_points::<Mass>(w)
            .read_points::<Velocity<D::Vec>>(w);
        // v_i = p_i / m_i.
        t += velocity_from_momentum_traffic::<D>(n);
        Some(t)
    }
}
