//! Prescribed motion of grid nodes (displacement control): a rigid footing pushed into the
//! ground, a wall moved, with the reaction on it and a load–displacement curve of static
//! states.
//!
//! The nodes on or inside a box are held at the motion's velocity on its given axes
//! (`boundary` does the holding and sums the reaction). The motion travels its distance in
//! increments: it moves one increment, then holds still while kinetic damping relaxes the
//! body to a static state (the run's own stopping rule), records that state as a row of the
//! curve, and moves on. While it moves, no state counts as static.
//!
//! Kinetic damping and a motion: a reset zeroes the points' velocities, not the motion's.
//! The driven nodes take their velocity again at the next step; a reset step moves no
//! point, and the motion travels nothing in it.

use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::model::{CurvePoint, MotionSpec};
use crate::schedule::System;
use crate::state::StopReason;
use crate::systems::increments::Increments;

/// Drives the scene's motions (their nodes are marked where the nodes are spawned,
/// [`crate::model::Model::node_fixity`]): after each step's convergence check it advances
/// their travel, holds them at the end of an increment and, at the static state that
/// follows, records the curve and starts the next increment.
#[derive(Debug)]
pub struct PrescribedMotion {
    motions: Vec<MotionSpec>,
}

impl PrescribedMotion {
    /// The system for these motions (in scene order: [`crate::model::Control::drives`]).
    pub fn new(motions: Vec<MotionSpec>) -> Self {
        PrescribedMotion { motions }
    }
}

impl<D: Dim> System<D> for PrescribedMotion {
    fn name(&self) -> &str {
        "prescribed_motion"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let s = &mut ctx.state;
        let dt = s.resets.motion_dt(ctx.numerics.dt).unwrap_or(0.0);
        for (m, d) in self.motions.iter().zip(&mut s.control.drives) {
            if d.velocity == [0.0; 3] {
                continue;
            }
            Increments::new(m.vector(), m.travel, m.increment).advance(
                &mut d.velocity,
                &mut d.travel,
                d.increments,
                dt,
                ctx.numerics.dt,
            );
        }
        if s.stop != Some(StopReason::Converged) {
            return Ok(());
        }
        // Every motion holds (a moving one blocks convergence): a static state.
        let mut more = false;
        for (m, d) in self.motions.iter().zip(&mut s.control.drives) {
            let v = m.vector().map(|c| c / m.speed());
            let along: f64 = (0..3).map(|a| d.reaction[a] * v[a]).sum();
            s.control.curve.push(CurvePoint {
                name: m.name.clone(),
                step: s.clock.step,
                time: s.clock.time,
                displacement: d.travel,
                force: d.reaction,
                pressure: m.area.map(|a| along / a),
            });
            d.increments += 1;
            s.control.milestone = true;
            if d.travel < m.travel * (1.0 - 1e-9) {
                d.velocity = m.vector();
                more = true;
            }
        }
        if more {
            s.go_on(&ctx.numerics);
        }
        Ok(())
    }
}
