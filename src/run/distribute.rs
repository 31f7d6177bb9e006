//! Joining a rank's part of a simulation to the run over MPI ranks
//! ([`crate::infra::decomposition`]).
//!
//! Each rank builds its part of the scene ([`crate::scene::build_part`]): the same split,
//! found from every body's layer counts, and the points of its own layers with their
//! one-rank ids. From then on the step maps into shared node bands and sums them
//! ([`crate::systems::exchange`]), reduces the global figures in rank order, and moves points
//! that leave a rank to its neighbour ([`crate::systems::migrate`]).

use crate::dim::Dim;
use crate::infra::comm::Comm;
use crate::simulation::Simulation;
use crate::systems::migrate::Migrate;
use std::sync::Arc;

/// Joins `sim`, this rank's part of the scene, to the run over `comm`'s ranks: the split it
/// was built with must be over as many ranks. With one rank nothing changes.
pub fn join<D: Dim>(sim: &mut Simulation<D>, comm: Arc<Comm>) {
    let ranks = sim.ctx.decomposition.ranks();
    assert_eq!(
        ranks,
        comm.size(),
        "a part built for {ranks} rank(s) joins a run over {}",
        comm.size()
    );
    // Points that leave a rank move at the end of every step.
    if comm.size() > 1 {
        sim.schedule.push(Migrate);
    }
    let ctx = &mut sim.ctx;
    ctx.comm = comm;
    ctx.slabs.invalidate();
}
