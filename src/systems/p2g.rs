//! Particle-to-grid: mass, momentum and internal force mapped to the nodes (paper step 1).

use crate::columns::{col, col_mut, nodes, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::error::StepError;
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::simulation::Context;
use std::marker::PhantomData;

/// What a [`P2g`] pass maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum P2gPart {
    /// Mass, momentum and internal force in one pass (USL, MUSL).
    All,
    /// Mass and momentum only (first half of USF).
    MassMomentum,
    /// Internal force only (second half of USF, after the stress update).
    InternalForce,
}

/// Maps point mass m_p, momentum m_p v_p and internal force −V_p σ_p·∇w_ip to the grid.
#[derive(Debug)]
pub struct P2g<D, S> {
    part: P2gPart,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S: Shape> P2g<D, S> {
    /// A pass that maps `part`.
    pub fn new(part: P2gPart) -> Self {
        P2g { part, _marker: PhantomData }
    }
}

impl<D: Dim, S: Shape> System<D> for P2g<D, S> {
    fn name(&self) -> &str {
        match self.part {
            P2gPart::All => "p2g",
            P2gPart::MassMomentum => "p2g_momentum",
            P2gPart::InternalForce => "p2g_force",
        }
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let grid = &ctx.grid;
        let n = nodes(&ctx.world);
        let mut nm = col_mut::<NodeMass>(n);
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let (mass_momentum, force) = match self.part {
            P2gPart::All => (true, true),
            P2gPart::MassMomentum => (true, false),
            P2gPart::InternalForce => (false, true),
        };
        for arch in points_with::<Position<D::Vec>>(&ctx.world) {
            let x = col::<Position<D::Vec>>(arch);
            let m = col::<Mass>(arch);
            let v = col::<Velocity<D::Vec>>(arch);
            // Load carriers have no volume or stress and add no internal force.
            let stressed = arch.get::<&Stress>().zip(arch.get::<&Volume>());
            let force = force && stressed.is_some();
            if !mass_momentum && !force {
                continue;
            }
            for p in 0..x.len() {
                let (mp, mv) = (m[p].0, v[p].0 * m[p].0);
                let f = match (&stressed, force) {
                    (Some((s, vol)), true) => Some((&s[p].0, -vol[p].0)),
                    _ => None,
                };
                for_each_node::<D, S>(grid, x[p].0, |i, w, grad| {
                    if mass_momentum {
                        nm[i].0 += w * mp;
                        np[i].0 += mv * w;
                    }
                    if let Some((s, neg_vol)) = f {
                        nf[i].0 += D::stress_dot(s, grad) * neg_vol;
                    }
                });
            }
        }
        Ok(())
    }
}
