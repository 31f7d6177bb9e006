//! Displacement control of the rigid bodies: each travels its distance in increments, and
//! the static state that ends an increment is a row of the curve.
//!
//! A body moves one increment at its velocity, then holds still while kinetic damping
//! relaxes the soil to a static state (the run's own stopping rule); the state is recorded
//! (`curve.csv`: travel, the soil's resistance on the body, the mean pressure over its
//! `area`, and a row per part for a body of several) and the next increment starts. A
//! kinetic-damping reset zeroes the soil's velocities, never the body's: a plain reset
//! step moves nothing, and the body travels nothing in it.
//!
//! Grid contact holds the soil's velocity at the nodes inside a body, so the points near
//! its surface move with a field that does not enter it; a point whose centre still ends a
//! step inside (by less than a cell: the nodes around it straddle the surface) is put back
//! on the surface along the normal. The count and the deepest entry are kept
//! ([`crate::rigid::BodyState::entries`]).

use crate::components::{Displacement, Position};
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col_mut, points_with};
use crate::rigid::RigidBodySpec;
use crate::schedule::System;
use crate::state::{CurvePoint, StopReason};
use crate::systems::increments::Increments;

/// Moves the bodies, holds them at the end of an increment and, at the static state that
/// follows, records the curve and starts the next increment.
#[derive(Debug)]
pub struct RigidControl {
    bodies: Vec<RigidBodySpec>,
}

impl RigidControl {
    /// The system for these bodies (in scene order).
    pub fn new(bodies: Vec<RigidBodySpec>) -> Self {
        RigidControl { bodies }
    }
}

/// Puts every point whose centre lies inside a body back on its surface (along the
/// normal), moving its displacement with it. Returns (points moved, deepest entry in m)
/// per body.
fn push_out<D: Dim>(ctx: &mut Context<D>, bodies: &[RigidBodySpec]) -> Vec<(u64, f64)> {
    let mut out = vec![(0, 0.0); bodies.len()];
    for (b, body) in bodies.iter().enumerate() {
        let offset = ctx.state.control.bodies[b].offset;
        let (lo, hi) = body.bounds(D::N);
        for arch in points_with::<Position<D::Vec>>(&ctx.world) {
            let mut x = col_mut::<Position<D::Vec>>(arch);
            let mut u = arch.get::<&mut Displacement<D::Vec>>();
            for (p, xp) in x.iter_mut().enumerate() {
                let at: [f64; 3] = std::array::from_fn(|a| D::vec_to3(xp.0)[a] - offset[a]);
                if (0..D::N).any(|a| at[a] < lo[a] || at[a] > hi[a]) {
                    continue;
                }
                let (phi, normal, _) = body.distance(at, D::N);
                if phi >= 0.0 {
                    continue;
                }
                let shift = D::vec_from(normal.map(|c| -phi * c));
                xp.0 += shift;
                if let Some(u) = u.as_mut() {
                    u[p].0 += shift;
                }
                out[b].0 += 1;
                out[b].1 = f64::max(out[b].1, -phi);
            }
        }
    }
    out
}

impl<D: Dim> System<D> for RigidControl {
    fn name(&self) -> &str {
        "rigid_control"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let s = &mut ctx.state;
        let dt = s.resets.motion_dt(ctx.settings.dt).unwrap_or(0.0);
        for (spec, b) in self.bodies.iter().zip(&mut s.control.bodies) {
            let Some(m) = &spec.motion else { continue };
            if b.velocity == [0.0; 3] {
                continue;
            }
            let moved = Increments::from(m).advance(
                &mut b.velocity,
                &mut b.travel,
                b.increments,
                dt,
                ctx.settings.dt,
            );
            for a in 0..3 {
                b.offset[a] += moved[a];
            }
        }
        for (b, (count, depth)) in push_out(ctx, &self.bodies).into_iter().enumerate() {
            let state = &mut ctx.state.control.bodies[b];
            state.entries += count;
            state.deepest_entry = state.deepest_entry.max(depth);
        }
        let s = &mut ctx.state;
        // A static state: the run's stop, or one `prescribed_motion` took this step.
        if s.stop != Some(StopReason::Converged) && !s.control.milestone {
            return Ok(());
        }
        let stages: Vec<&str> = ctx.settings.stages.iter().map(|t| t.name.as_str()).collect();
        // Every body holds (a moving one blocks convergence): a static state.
        let mut more = false;
        for (spec, b) in self.bodies.iter().zip(&mut s.control.bodies) {
            // The mean pressure along the motion, or, for a body that holds its place, of
            // the whole force.
            let along = |f: [f64; 3]| -> f64 {
                match &spec.motion {
                    Some(m) => (0..3).map(|a| f[a] * m.vector()[a] / m.speed()).sum(),
                    None => f.iter().map(|c| c * c).sum::<f64>().sqrt(),
                }
            };
            s.control.curve.push(CurvePoint {
                name: spec.name.clone(),
                step: s.clock.step,
                time: s.clock.time,
                displacement: b.travel,
                force: b.reaction,
                pressure: spec.area.map(|a| along(b.reaction) / a),
            });
            if spec.parts.len() > 1 {
                for (part, f) in spec.parts.iter().zip(&b.parts) {
                    s.control.curve.push(CurvePoint {
                        name: format!("{}.{}", spec.name, part.name),
                        step: s.clock.step,
                        time: s.clock.time,
                        displacement: b.travel,
                        force: *f,
                        pressure: part.area.map(|a| along(*f) / a),
                    });
                }
            }
            let Some(m) = &spec.motion else { continue };
            if !spec.moves_in(s.control.stage, &stages) {
                continue;
            }
            b.increments += 1;
            s.control.milestone = true;
            if b.travel < m.travel * (1.0 - 1e-9) {
                b.velocity = m.vector();
                more = true;
            }
        }
        if more {
            s.go_on(&ctx.settings);
        }
        Ok(())
    }
}
