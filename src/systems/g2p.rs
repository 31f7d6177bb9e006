//! Grid-to-particle velocity update and the kinetic energy of eq. (5) (paper step 4).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::CHUNK;
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use rayon::prelude::*;
use std::marker::PhantomData;

/// The first point (by row) whose velocity is not finite, as "point <id>" for a message.
fn first_non_finite_velocity<D: Dim>(world: &hecs::World) -> String {
    for arch in points_with::<Velocity<D::Vec>>(world) {
        let (v, id) = (col::<Velocity<D::Vec>>(arch), col::<PointId>(arch));
        if let Some(r) = v
            .iter()
            .position(|v| !D::vec_to3(v.0).iter().all(|c| c.is_finite()))
        {
            return format!("point {}", id[r].0);
        }
    }
    "a point (the energy's sum overflowed)".into()
}

/// v_p ← α (v_p + Δt Σ_i w_ip a_i) + (1 − α) Σ_i w_ip v_i (FLIP for α = 1, PIC for α = 0),
/// then E_k = ½ Σ m_p v_p·v_p.
#[derive(Debug)]
pub struct G2p<D, S>(PhantomData<fn() -> (D, S)>);

impl<D, S> Default for G2p<D, S> {
    fn default() -> Self {
        G2p(PhantomData)
    }
}

impl<D: Dim, S: Shape> System<D> for G2p<D, S> {
    fn name(&self) -> &str {
        "g2p"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let (grid, dt) = (&ctx.grid, ctx.numerics.dt);
        let n = nodes(&ctx.world);
        let nag = col::<NodeAcceleration<D::Vec>>(n);
        let na: &[NodeAcceleration<D::Vec>] = &nag;
        let nvg = col::<NodeVelocity<D::Vec>>(n);
        let nv: &[NodeVelocity<D::Vec>] = &nvg;
        let flip = ctx.numerics.flip;
        // Pure FLIP (the default) never reads the interpolated nodal velocity.
        let pic = flip < 1.0;
        let mut twice_ek = 0.0;
        for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
            let (xg, mg) = (col::<Position<D::Vec>>(arch), col::<Mass>(arch));
            let (x, m): (&[Position<D::Vec>], &[Mass]) = (&xg, &mg);
            let mut vg = col_mut::<Velocity<D::Vec>>(arch);
            let parts: Vec<f64> = vg
                .par_chunks_mut(CHUNK)
                .enumerate()
                .map(|(c, v)| {
                    let mut e = 0.0;
                    for (k, vp) in v.iter_mut().enumerate() {
                        let p = c * CHUNK + k;
                        let mut a = D::Vec::ZERO;
                        vp.0 = if pic {
                            let mut vg = D::Vec::ZERO;
                            for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                                a = na[i].0.madd(w, a);
                                vg = nv[i].0.madd(w, vg);
                            });
                            (vp.0 + a * dt) * flip + vg * (1.0 - flip)
                        } else {
                            for_each_node::<D, S>(grid, x[p].0, |i, w, _| a = na[i].0.madd(w, a));
                            vp.0 + a * dt
                        };
                        e += m[p].0 * vp.0.dot(vp.0);
                    }
                    e
                })
                .collect();
            // Partial sums added in chunk order: the same bits for any thread count.
            twice_ek += parts.iter().sum::<f64>();
        }
        // A NaN or infinite velocity shows in the energy's sum. Stop here, before any point
        // moves with it: positions, stresses and the solver state stay those of the last
        // finite step (the velocities do not, so the final points are not written).
        // Over MPI the energy is the ranks' sum (a NaN on one rank reaches all, so that every
        // rank stops alike).
        let mut twice_ek = [twice_ek];
        ctx.comm.sum(&mut twice_ek);
        let [twice_ek] = twice_ek;
        if !twice_ek.is_finite() {
            return Err(StepError::NonFinite {
                step: ctx.state.clock.step,
                system: "g2p",
                what: "velocity",
                location: first_non_finite_velocity::<D>(&ctx.world),
            });
        }
        ctx.state.energy.set(0.5 * twice_ek);
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let (w, n) = (&ctx.world, ctx.state.active_nodes.len());
        let t = Traffic::NONE
            .read_points::<Position<D::Vec>>(w)
            .read_points::<Mass>(w)
            .update_points::<Velocity<D::Vec>>(w)
            .read_nodes::<NodeAcceleration<D::Vec>>(n);
        // PIC's share reads the nodal velocity too.
        Some(if ctx.numerics.flip < 1.0 {
            t.read_nodes::<NodeVelocity<D::Vec>>(n)
        } else {
            t
        })
    }
}
