//! Grid-to-particle velocity update and the kinetic energy of eq. (5) (paper step 4).

use crate::columns::{col, col_mut, nodes, points_with};
use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::simulation::Context;
use std::marker::PhantomData;

/// v_p ← v_p + Δt Σ_i w_ip a_i (FLIP update), then E_k = ½ Σ m_p v_p·v_p.
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
        let (grid, dt) = (&ctx.grid, ctx.state.dt);
        let n = nodes(&ctx.world);
        let na = col::<NodeAcceleration<D::Vec>>(n);
        let mut twice_ek = 0.0;
        for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
            let x = col::<Position<D::Vec>>(arch);
            let m = col::<Mass>(arch);
            let mut v = col_mut::<Velocity<D::Vec>>(arch);
            for p in 0..x.len() {
                let mut a = D::Vec::ZERO;
                for_each_node::<D, S>(grid, x[p].0, |i, w, _| a += na[i].0 * w);
                let vp = v[p].0 + a * dt;
                v[p].0 = vp;
                twice_ek += m[p].0 * vp.dot(vp);
            }
        }
        ctx.state.kinetic_energy = 0.5 * twice_ek;
        Ok(())
    }
}
