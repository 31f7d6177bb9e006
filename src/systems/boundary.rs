//! Essential boundary conditions on the grid (paper step 2).

use crate::columns::{col, col_mut, nodes};
use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::parallel::{for_each_box_node, Disjoint};
use crate::schedule::System;

/// Zeroes the fixed components of nodal momentum and force, so that fixed nodes neither
/// move nor accelerate.
#[derive(Debug, Default)]
pub struct Boundary;

impl<D: Dim> System<D> for Boundary {
    fn name(&self) -> &str {
        "boundary"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        let fix = col::<NodeFixity>(n);
        let fix = &*fix; // a plain slice: the column guard cannot be shared with the pool
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let target = (Disjoint::new(&mut np), Disjoint::new(&mut nf));
        for_each_box_node(&ctx.grid, ctx.state.active_nodes, &target, |i, k, (np, nf)| {
            let f = fix[i];
            if f.0 == 0 {
                return;
            }
            for a in 0..D::N {
                if f.is_fixed(a) {
                    np[k].0.set(a, 0.0);
                    nf[k].0.set(a, 0.0);
                }
            }
        });
        Ok(())
    }
}

/// Zeroes the fixed components of a nodal velocity.
#[inline(always)]
pub fn constrain<V: Vector>(v: &mut V, fixity: NodeFixity, dims: usize) {
    if fixity.0 != 0 {
        for a in 0..dims {
            if fixity.is_fixed(a) {
                v.set(a, 0.0);
            }
        }
    }
}
