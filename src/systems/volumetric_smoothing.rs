//! Volumetric smoothing of the strain increment through the grid (against volumetric
//! locking and the pressure checkerboard it causes).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, points_with};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::node_pairs::{set_volumetric_rates, NodePairs};
use std::marker::PhantomData;

/// Replaces each point's volumetric strain rate tr(L_p) by its volume-weighted nodal
/// average, leaving the deviatoric part untouched:
///
/// θ_i = Σ_p w_ip V_p tr(L_p) / Σ_p w_ip V_p,   L_p ← L_p + (Σ_i w_ip θ_i − tr(L_p)) I / N.
///
/// Near-incompressible plastic flow (ψ = 0) over-constrains a low-order grid (volumetric
/// locking); the point-to-point pressure noise it leaves ratchets a slope at its limit angle
/// downhill. Smoothing only the volumetric part keeps full stiffness against every
/// deviatoric mode. Runs between `kinematics` and `stress_update`, so the stress and the
/// volume see the same smoothed rate.
#[derive(Debug)]
pub struct VolumetricSmoothing<D: Dim, S> {
    /// Per node: Σ w V tr(L), Σ w V; then θ_i in the first entry.
    sums: NodePairs,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for VolumetricSmoothing<D, S> {
    fn default() -> Self {
        VolumetricSmoothing {
            sums: NodePairs::default(),
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for VolumetricSmoothing<D, S> {
    fn name(&self) -> &str {
        "volumetric_smoothing"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if ctx.motion_dt().is_none() {
            return Ok(());
        }
        let grid = &ctx.grid;
        let sums = &mut self.sums;
        for arch in points_with::<Volume>(&ctx.world) {
            let (xg, vg, lg) = (
                col::<Position<D::Vec>>(arch),
                col::<Volume>(arch),
                col::<VelocityGradient<D::Mat>>(arch),
            );
            let (vol, l): (&[Volume], &[VelocityGradient<D::Mat>]) = (&vg, &lg);
            sums.scatter::<D, S, _>(
                &mut ctx.slabs,
                grid,
                &xg,
                |p| (vol[p].0, D::volumetric_rate(&l[p].0)),
                |node, w, &(v, t)| {
                    node[0] += w * v * t;
                    node[1] += w * v;
                },
            );
        }
        sums.sum_over_ranks(grid, &ctx.comm, &ctx.decomposition);
        sums.map(grid, |s| [if s[1] > 0.0 { s[0] / s[1] } else { 0.0 }, 0.0]);
        let nodal = sums.pairs();
        set_volumetric_rates::<D>(points_with::<Volume>(&ctx.world), |x| {
            let mut theta = 0.0;
            for_each_node::<D, S>(grid, x, |i, w, _| theta += w * nodal[i][0]);
            theta
        });
        sums.clear(grid);
        Ok(())
    }
}
