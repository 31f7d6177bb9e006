//! The pore water's part of the internal force (drained, hydrostatic; [`crate::water`]).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::parallel::{scatter, Disjoint};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use std::marker::PhantomData;

/// Adds f_i += Σ_p V_p u_p ∇w_ip to the nodal force: with the effective stress σ′ that the
/// points carry, the total stress is σ = σ′ − u I (tension positive), and the internal force
/// −Σ V σ·∇w that `p2g` maps from σ′ lacks this part. u_p is the pore pressure at the
/// point's current position.
#[derive(Debug)]
pub struct PorePressure<D: Dim, S> {
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for PorePressure<D, S> {
    fn default() -> Self {
        PorePressure { _marker: PhantomData }
    }
}

impl<D: Dim, S: Shape> System<D> for PorePressure<D, S> {
    fn name(&self) -> &str {
        "pore_pressure"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let Some(water) = ctx.settings.water else {
            return Ok(());
        };
        let grid = &ctx.grid;
        let mut nf = col_mut::<NodeForce<D::Vec>>(nodes(&ctx.world));
        for arch in points_with::<Volume>(&ctx.world) {
            let (xg, vg) = (col::<Position<D::Vec>>(arch), col::<Volume>(arch));
            let (x, vol): (&[Position<D::Vec>], &[Volume]) = (&xg, &vg);
            scatter(
                ctx.slabs.slabs(grid, x),
                grid,
                S::SUPPORT,
                &Disjoint::new(&mut nf),
                |points, nf, lo| {
                    for &p in points {
                        let p = p as usize;
                        let vu = vol[p].0 * water.pore_pressure(D::vec_to3(x[p].0));
                        if vu == 0.0 {
                            continue;
                        }
                        for_each_node::<D, S>(grid, x[p].0, |i, _, grad| {
                            let n = &mut nf[i - lo].0;
                            *n = grad.madd(vu, *n);
                        });
                    }
                },
            );
        }
        Ok(())
    }
}
