//! Kinetic damping: watch the kinetic energy and zero all velocities at a peak (paper §2.2,
//! step 5). Scheduled only with kinetic damping.

use crate::columns::{col_mut, points_with};
use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::schedule::System;
use crate::state::Peak;

/// When E_k(n) < E_k(n−1) the energy peaked in the previous step: every point velocity is
/// set to zero, the points do not move in this step, and the stored energy becomes 0 so
/// that the next step cannot count as a peak.
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
        let interpolate = ctx.settings.peak_interpolation;
        let s = &mut ctx.state;
        if s.kinetic_energy < s.previous_kinetic_energy {
            let (e2, e1, e0) = (
                s.earlier_kinetic_energy,
                s.previous_kinetic_energy,
                s.kinetic_energy,
            );
            let curvature = e2 - 2.0 * e1 + e0;
            s.reset_fraction = if interpolate && e2 > 0.0 && curvature < 0.0 {
                ((e2 - e0) / (2.0 * curvature)).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            // The peak was the energy of the previous step, which ended at t − Δt.
            s.peaks.push(Peak {
                time: s.time - s.dt,
                energy: s.previous_kinetic_energy,
            });
            s.resets += 1;
            s.reset_this_step = true;
            s.kinetic_energy = 0.0;
            s.previous_kinetic_energy = 0.0;
            s.earlier_kinetic_energy = 0.0;
            for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
                col_mut::<Velocity<D::Vec>>(arch).fill(Velocity(D::Vec::ZERO));
            }
        } else {
            s.earlier_kinetic_energy = s.previous_kinetic_energy;
            s.previous_kinetic_energy = s.kinetic_energy;
        }
        Ok(())
    }
}
