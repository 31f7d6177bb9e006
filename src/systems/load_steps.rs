//! Load control: a load applied in equal increments, each relaxed by kinetic damping to its
//! static state and recorded as a row of the load–displacement curve (`curve.csv`).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, points_with};
use crate::model::{CurvePoint, LoadSteps};
use crate::schedule::System;
use crate::state::StopReason;
use crate::systems::shared::set_point_loads;

/// Sets each incremental load to its present fraction before the first step and, at each
/// static state, records the curve and raises the loads that have increments left.
///
/// A row's displacement is the mean displacement of the loaded points along the load, and
/// its pressure the load's fraction of the full traction. Increments that find no static
/// state end the run at its time or step limit: the curve's last row is then the largest
/// load the body was seen to carry, the next increment one it did not.
#[derive(Debug, Default)]
pub struct LoadControl;

/// Mean displacement of the loaded points along the load (m).
fn settlement<D: Dim>(ctx: &Context<D>, load: &LoadSteps) -> f64 {
    let total: [f64; 3] = load
        .points
        .iter()
        .fold([0.0; 3], |s, p| std::array::from_fn(|a| s[a] + p.1[a]));
    let size = total.iter().map(|c| c * c).sum::<f64>().sqrt();
    let dir = total.map(|c| c / size);
    let (mut sum, mut count) = (0.0, 0usize);
    for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
        let (Some(u), ids) = (arch.get::<&Displacement<D::Vec>>(), col::<PointId>(arch)) else {
            continue;
        };
        for (id, u) in ids.iter().zip(u.iter()) {
            if load.points.binary_search_by_key(&id.0, |p| p.0).is_ok() {
                let u = D::vec_to3(u.0);
                sum += (0..3).map(|a| u[a] * dir[a]).sum::<f64>();
                count += 1;
            }
        }
    }
    // Over several ranks, every rank's loaded points (rank order).
    let mut both = [sum, count as f64];
    ctx.comm.sum(&mut both);
    both[0] / both[1].max(1.0)
}

impl<D: Dim> System<D> for LoadControl {
    fn name(&self) -> &str {
        "load_steps"
    }

    fn prepare(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = ctx.model.load_steps.len();
        ctx.state.control.load_increments.resize(n, 0);
        for (load, &done) in ctx
            .model
            .load_steps
            .iter()
            .zip(&ctx.state.control.load_increments)
        {
            let k = (done + 1).min(load.increments);
            set_point_loads(ctx, &load.points, k as f64 / load.increments as f64);
        }
        Ok(())
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if ctx.state.stop != Some(StopReason::Converged) {
            return Ok(());
        }
        let mut more = false;
        for (k, load) in ctx.model.load_steps.iter().enumerate() {
            let done = ctx.state.control.load_increments[k];
            if done >= load.increments {
                continue;
            }
            let fraction = (done + 1) as f64 / load.increments as f64;
            let force = load
                .points
                .iter()
                .fold([0.0; 3], |s, p| std::array::from_fn(|a| s[a] + p.1[a] * fraction));
            let displacement = settlement(ctx, load);
            let s = &mut ctx.state;
            s.control.curve.push(CurvePoint {
                name: load.name.clone(),
                step: s.clock.step,
                time: s.clock.time,
                displacement,
                force,
                pressure: Some(load.pressure * fraction),
            });
            s.control.load_increments[k] = done + 1;
            s.control.milestone = true;
            if done + 1 < load.increments {
                set_point_loads(ctx, &load.points, (done + 2) as f64 / load.increments as f64);
                more = true;
            }
        }
        if more {
            ctx.state.go_on(&ctx.numerics);
        }
        Ok(())
    }
}
