//! Volumetric smoothing of the strain increment through the grid (against volumetric
//! locking and the pressure checkerboard it causes).

use crate::columns::{col, col_mut, points_with};
use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::grid::NodeBox;
use crate::parallel::{fill_box, for_each_box_node, scatter, Disjoint, CHUNK};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use rayon::prelude::*;
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
    /// Per node: Σ w V tr(L), Σ w V; then θ_i in the first entry. Zero outside the points'
    /// box between runs.
    sums: Vec<[f64; 2]>,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for VolumetricSmoothing<D, S> {
    fn default() -> Self {
        VolumetricSmoothing {
            sums: Vec::new(),
            _marker: PhantomData,
        }
    }
}

/// Trace of a velocity gradient through the volume ratio's first-order term.
#[inline(always)]
fn trace<D: Dim>(l: &D::Mat) -> f64 {
    D::strain_spin(|i, j| D::mat_entry(l, i, j), 1.0).0.trace()
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
        let mut active = NodeBox::default();
        let sums = &mut self.sums;
        sums.resize(grid.node_count(), [0.0; 2]);
        for arch in points_with::<Volume>(&ctx.world) {
            let (xg, vg, lg) = (
                col::<Position<D::Vec>>(arch),
                col::<Volume>(arch),
                col::<VelocityGradient<D::Mat>>(arch),
            );
            let (x, vol): (&[Position<D::Vec>], &[Volume]) = (&xg, &vg);
            let l: &[VelocityGradient<D::Mat>] = &lg;
            active = active.union(scatter(
                ctx.slabs.slabs(grid, x),
                grid,
                S::SUPPORT,
                &Disjoint::new(sums),
                |points, sums, lo| {
                    for &p in points {
                        let p = p as usize;
                        let (v, t) = (vol[p].0, trace::<D>(&l[p].0));
                        for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                            sums[i - lo][0] += w * v * t;
                            sums[i - lo][1] += w * v;
                        });
                    }
                },
            ));
        }
        for_each_box_node(grid, active, &Disjoint::new(sums), |_, k, sums| {
            let s = sums[k];
            sums[k] = [if s[1] > 0.0 { s[0] / s[1] } else { 0.0 }, 0.0];
        });
        let nodal: &[[f64; 2]] = sums;
        let n = D::N as f64;
        for arch in points_with::<Volume>(&ctx.world) {
            let xg = col::<Position<D::Vec>>(arch);
            let x: &[Position<D::Vec>] = &xg;
            let mut lg = col_mut::<VelocityGradient<D::Mat>>(arch);
            lg.par_chunks_mut(CHUNK).enumerate().for_each(|(c, l)| {
                for (k, lp) in l.iter_mut().enumerate() {
                    let mut theta = 0.0;
                    for_each_node::<D, S>(grid, x[c * CHUNK + k].0, |i, w, _| theta += w * nodal[i][0]);
                    let shift = (theta - trace::<D>(&lp.0)) / n;
                    D::add_identity(&mut lp.0, shift);
                }
            });
        }
        fill_box(grid, active, sums, [0.0; 2]);
        Ok(())
    }
}
