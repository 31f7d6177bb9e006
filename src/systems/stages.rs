//! Loading stages: a scene's `stages` run one after another, each to the static stop; a
//! stage changes materials (e.g. elastic soil for the geostatic state, then its
//! Mohr-Coulomb strength), gravity, point loads, tractions and the water's piezometric
//! surfaces when it begins, and may zero the displacements. The water's unit weight
//! follows the stage's gravity.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::model::{Gravity, LoadStage, StageResult};
use crate::schedule::System;
use crate::state::StopReason;
use crate::systems::shared::set_point_loads;

/// Moves to the next stage at each static state until the last: records the finished
/// stage (`stages.csv`), applies the next one's changes and lets the run go on from the
/// state reached. Its kinetic-damping record starts afresh; the external work goes on
/// accumulating, since a stage may release energy stored before it (a freed side, an
/// unloading) rather than add any.
#[derive(Debug, Default)]
pub struct Stages;

/// Sets the materials and loads of `stage` (the whole of it: applying it twice is applying
/// it once).
fn apply<D: Dim>(ctx: &mut Context<D>, stage: &LoadStage, start: f64) {
    if let Some(g) = stage.gravity {
        ctx.model.gravity = Some(Gravity { start, ..g });
    }
    if let Some(faces) = &stage.faces {
        // A motion's nodes keep its axes and its name.
        ctx.model.faces = faces.clone();
        let fixity = ctx.model.node_fixity(&ctx.grid);
        col_mut::<NodeFixity>(nodes(&ctx.world)).copy_from_slice(&fixity);
    }
    for (id, model) in &stage.materials {
        ctx.materials[*id as usize] = model.clone();
    }
    if let Some(w) = &stage.water {
        ctx.model.water = Some(w.clone());
    }
    // γ_w = ρ_w |g| follows the gravity in force (a centrifuge stage doubles both).
    if let (Some(w), Some(g)) = (ctx.model.water.as_mut(), ctx.model.gravity) {
        w.follow_gravity(g.acceleration);
    }
    set_point_loads(ctx, &stage.loads, 1.0);
}

/// Weighs again the points `stage`'s water moves across a surface: ρ_sat below the new
/// surface, ρ_dry above it ([`crate::water::Water::density_ratio`], judged at each point's
/// current place). Called once as the stage begins, before [`apply`] sets the new water.
fn rewet<D: Dim>(ctx: &mut Context<D>, stage: &LoadStage) {
    let (Some(old), Some(new)) = (&ctx.model.water, &stage.water) else {
        return;
    };
    for arch in points_with::<MaterialId>(&ctx.world) {
        let ids = col::<MaterialId>(arch);
        let xs = col::<Position<D::Vec>>(arch);
        let vs = col::<Volume>(arch);
        let mut mass = col_mut::<Mass>(arch);
        for (((m, id), x), v) in mass.iter_mut().zip(ids.iter()).zip(xs.iter()).zip(vs.iter()) {
            m.0 *= old.density_ratio(new, id.0, D::vec_to3(x.0), v.0);
        }
    }
}

/// Scales the mass of every point whose material `stage` gives another dry density by
/// ρ_new/ρ_old (its volume is what it is; its mass, and with it its weight, change); below
/// a piezometric surface the saturated density stays the scene's
/// ([`crate::water::Water::reweigh_ratio`]). Called once as the stage begins, before
/// [`apply`] replaces the models: unlike `apply` it is not idempotent, and a resumed run's
/// masses are already those of its stage.
fn reweigh<D: Dim>(ctx: &mut Context<D>, stage: &LoadStage) {
    let changes: Vec<(u16, f64, f64)> = stage
        .materials
        .iter()
        .map(|(id, model)| (*id, ctx.materials[*id as usize].density(), model.density()))
        .filter(|&(_, old, new)| old != new)
        .collect();
    if changes.is_empty() {
        return;
    }
    let water = ctx.model.water.as_ref();
    for arch in points_with::<MaterialId>(&ctx.world) {
        let ids = col::<MaterialId>(arch);
        let xs = col::<Position<D::Vec>>(arch);
        let vs = col::<Volume>(arch);
        let mut mass = col_mut::<Mass>(arch);
        for (((m, id), x), v) in mass.iter_mut().zip(ids.iter()).zip(xs.iter()).zip(vs.iter()) {
            if let Some(&(_, old, new)) = changes.iter().find(|(k, _, _)| *k == id.0) {
                m.0 *= match water {
                    Some(w) => w.reweigh_ratio(id.0, D::vec_to3(x.0), v.0, old, new),
                    None => new / old,
                };
            }
        }
    }
}

impl<D: Dim> System<D> for Stages {
    fn name(&self) -> &str {
        "stages"
    }

    fn prepare(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // The stages so far, in order (a resumed run starts inside one).
        let stages = ctx.model.stages.clone();
        for (k, stage) in stages[..=ctx.state.control.stage.min(stages.len() - 1)]
            .iter()
            .enumerate()
        {
            // A stage starts when the one before it ended.
            let start = k.checked_sub(1).map_or(0.0, |j| ctx.state.control.stages[j].time);
            // A fresh run begins in the first stage with the scene's masses; a resumed one
            // has the masses of its stage in its checkpoint. `prepare` runs inside the
            // first step, whose clock already reads 1 (a checkpoint taken before any step
            // holds the scene's masses too).
            if k == 0 && ctx.state.clock.step <= 1 {
                reweigh(ctx, stage);
                rewet(ctx, stage);
            }
            apply(ctx, stage, start);
        }
        Ok(())
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if ctx.state.stop != Some(StopReason::Converged) {
            return Ok(());
        }
        let s = &mut ctx.state;
        let stages = &ctx.model.stages;
        s.control.stages.push(StageResult {
            name: stages[s.control.stage].name.clone(),
            step: s.clock.step,
            time: s.clock.time,
            force_ratio: s.convergence.force_ratio(ctx.numerics.force_norm),
            energy_ratio: s.convergence.energy_ratio,
            resets: s.resets.count,
        });
        s.control.milestone = true;
        if s.control.stage + 1 >= stages.len() {
            return Ok(());
        }
        s.control.stage += 1;
        s.go_on(&ctx.numerics);
        ctx.model
            .start_stage(&stages[s.control.stage].name, &mut s.control);
        s.energy.reset();
        let stage = stages[s.control.stage].clone();
        let start = ctx.state.clock.time;
        reweigh(ctx, &stage);
        rewet(ctx, &stage);
        apply(ctx, &stage, start);
        if stage.reset_displacements {
            for arch in points_with::<Displacement<D::Vec>>(&ctx.world) {
                col_mut::<Displacement<D::Vec>>(arch).fill(Displacement(D::Vec::ZERO));
            }
        }
        Ok(())
    }
}
