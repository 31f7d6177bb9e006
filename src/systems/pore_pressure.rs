//! The pore water's load on the soil skeleton (drained, static; [`crate::water`]).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::parallel::{scatter, Disjoint};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use std::marker::PhantomData;

/// Adds f_i += Σ_p V_p w_ip (−∇u_p) to the nodal force, as applied load: the buoyancy and
/// seepage force of the pore water below each point's piezometric surface, which together
/// with the effective stress σ′ that `p2g` maps is the total stress σ = σ′ − u I and the
/// pressure of open water on a submerged surface (the divergence theorem;
/// [`crate::water`]). ∇u is taken at the point's current place, times the share of the
/// point below its surface.
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
        let Some(water) = &ctx.settings.water else {
            return Ok(());
        };
        let grid = &ctx.grid;
        let n = nodes(&ctx.world);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        for arch in points_with::<Volume>(&ctx.world) {
            let (xg, vg, mg) = (
                col::<Position<D::Vec>>(arch),
                col::<Volume>(arch),
                col::<MaterialId>(arch),
            );
            let (x, vol, mat): (&[Position<D::Vec>], &[Volume], &[MaterialId]) = (&xg, &vg, &mg);
            scatter(
                ctx.slabs.slabs(grid, x),
                grid,
                S::SUPPORT,
                &(Disjoint::new(&mut nf), Disjoint::new(&mut ne)),
                |points, (nf, ne), lo| {
                    for &p in points {
                        let p = p as usize;
                        // The point's height, its volume taken as a square (a cube in 3D).
                        let side = if D::N == 2 {
                            vol[p].0.sqrt()
                        } else {
                            vol[p].0.cbrt()
                        };
                        let b = water.body_force(mat[p].0, D::vec_to3(x[p].0), side);
                        if b == [0.0; 3] {
                            continue;
                        }
                        let f = D::vec_from(b) * vol[p].0;
                        for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                            nf[i - lo].0 = f.madd(w, nf[i - lo].0);
                            ne[i - lo].0 = f.madd(w, ne[i - lo].0);
                        });
                    }
                },
            );
        }
        Ok(())
    }
}
