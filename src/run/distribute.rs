//! Splitting a built simulation across MPI ranks ([`crate::infra::decomposition`]).
//!
//! Every rank builds the whole scene (the same points with the same ids), counts the points
//! of each cell layer along the slab axis, finds the same [`Decomposition`] and keeps the
//! points of its own layers. From then on the step maps into shared node bands and sums them
//! ([`crate::systems::exchange`]), reduces the global figures in rank order, and moves points
//! that leave a rank to its neighbour ([`crate::systems::migrate`]).

use crate::components::Position;
use crate::dim::Dim;
use crate::infra::comm::Comm;
use crate::infra::decomposition::Decomposition;
use crate::simulation::Simulation;
use crate::systems::migrate::{layer_counts, Migrate};
use hecs::Entity;
use std::sync::Arc;

/// Gives `sim` its part of the run: the decomposition of its points over `comm`'s ranks,
/// and only the points of this rank's cell layers. With one rank nothing changes.
pub fn decompose<D: Dim>(sim: &mut Simulation<D>, comm: Arc<Comm>) {
    let ctx = &mut sim.ctx;
    let axis = ctx.grid.slab_axis;
    // Every rank holds the whole scene here: its counts are everyone's.
    let counts = layer_counts(ctx);
    let d = Decomposition::balanced(&counts, comm.size(), comm.rank(), ctx.decomposition.support);
    let cells = d.cells();
    let away: Vec<Entity> = ctx
        .world
        .query::<(Entity, &Position<D::Vec>)>()
        .iter()
        .filter(|(_, x)| !cells.contains(&ctx.grid.clamped_cell_along(x.0, axis)))
        .map(|(e, _)| e)
        .collect();
    for e in away {
        ctx.world.despawn(e).expect("a point found above");
    }
    ctx.decomposition = d;
    // Points that leave a rank move at the end of every step.
    if comm.size() > 1 {
        sim.schedule.push(Migrate);
    }
    let ctx = &mut sim.ctx;
    ctx.comm = comm;
    ctx.slabs.invalidate();
    for t in &mut sim.traced {
        if let Some(e) = t.find(&sim.ctx.world) {
            t.entity = e;
        }
    }
}
