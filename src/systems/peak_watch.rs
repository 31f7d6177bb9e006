//! Kinetic damping: watch the kinetic energy and zero all velocities at a peak (paper §2.2,
//! step 5). Scheduled only with kinetic damping.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col_mut, points_with};
use crate::infra::traffic::Traffic;
use crate::schedule::System;
use crate::state::Peak;

/// When E_k(n) < E_k(n−1) the energy peaked in the previous step: every point velocity is
/// set to zero (E_k counts the model's own masses, [`crate::model::Model::kinetic_energy`],
/// whose control zeroes their velocity in the same step), the points do not move in this
/// step, and the stored energy becomes 0 so that the next step cannot count as a peak.
///
/// With `peak_interpolation` the peak is placed between steps: a parabola through
/// E(n−2), E(n−1), E(n) at offsets −1, 0, 1 peaks at
/// s = (E(n−2) − E(n)) / (2 (E(n−2) − 2E(n−1) + E(n))), clamped to (−½, ½). The points,
/// which stand where step n−1 left them, then move by s Δt v (this step's grid velocity,
/// nearly constant at a peak of the kinetic energy, where F·v = 0), and their stress and
/// volume with them, before the velocities are zeroed.
#[derive(Debug, Default)]
pub struct PeakWatch;

impl<D: Dim> System<D> for PeakWatch {
    fn name(&self) -> &str {
        "peak_watch"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let (interpolate, dt) = (ctx.numerics.peak_interpolation, ctx.numerics.dt);
        let s = &mut ctx.state;
        // The model's own masses (a body under load control) move beside the points.
        let own = ctx.model.kinetic_energy(&s.control);
        if own > 0.0 {
            s.energy.set(s.energy.current() + own);
        }
        if let Some([e2, e1, e0]) = s.energy.peak() {
            let curvature = e2 - 2.0 * e1 + e0;
            s.resets.fraction = if interpolate && e2 > 0.0 && curvature < 0.0 {
                ((e2 - e0) / (2.0 * curvature)).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            // The peak was the energy of the previous step, which ended at t − Δt.
            s.resets.peaks.push(Peak {
                time: s.clock.time - dt,
                energy: e1,
            });
            s.resets.count += 1;
            s.resets.this_step = true;
            s.energy.reset();
            for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
                col_mut::<Velocity<D::Vec>>(arch).fill(Velocity(D::Vec::ZERO));
            }
        } else {
            s.energy.push();
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        // A reset zeroes every point's velocity.
        Some(if ctx.state.resets.this_step {
            Traffic::NONE.write_points::<Velocity<D::Vec>>(&ctx.world)
        } else {
            Traffic::NONE
        })
    }
}
