//! Kinetic damping: watch the kinetic energy and zero all velocities at a peak (paper §2.2,
//! step 5). Scheduled only with kinetic damping.

use crate::columns::{col_mut, points_with};
use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::schedule::System;
use crate::simulation::Context;
use crate::state::Peak;

/// When E_k(n) < E_k(n−1) the energy peaked in the previous step: every point velocity is
/// set to zero, the points do not move in this step, and the stored energy becomes 0 so
/// that the next step cannot count as a peak.
#[derive(Debug, Default)]
pub struct PeakWatch;

impl<D: Dim> System<D> for PeakWatch {
    fn name(&self) -> &str {
        "peak_watch"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let s = &mut ctx.state;
        if s.kinetic_energy < s.previous_kinetic_energy {
            // The peak was the energy of the previous step, which ended at t − Δt.
            s.peaks.push(Peak {
                time: s.time - s.dt,
                energy: s.previous_kinetic_energy,
            });
            s.resets += 1;
            s.reset_this_step = true;
            s.kinetic_energy = 0.0;
            s.previous_kinetic_energy = 0.0;
            for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
                col_mut::<Velocity<D::Vec>>(arch).fill(Velocity(D::Vec::ZERO));
            }
        } else {
            s.previous_kinetic_energy = s.kinetic_energy;
        }
        Ok(())
    }
}
