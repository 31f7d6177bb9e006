//! What every system reads and writes.

use crate::dim::Dim;
use crate::grid::{Grid, RankNodes};
use crate::infra::comm::Comm;
use crate::infra::decomposition::{Decomposition, ACROSS, SLAB};
use crate::materials::MaterialModel;
use crate::model::Model;
use crate::parallel::SlabCache;
use crate::state::{Numerics, SolverState};
use hecs::World;
use std::sync::Arc;

/// Everything the systems read and write: the world (points and nodes), the grid, the
/// material table, the numerics, the model and the solver-wide state.
pub struct Context<D: Dim> {
    /// Points and nodes.
    pub world: World,
    /// Background grid geometry.
    pub grid: Grid<D>,
    /// Materials, indexed by [`MaterialId`](crate::components::MaterialId).
    pub materials: Vec<MaterialModel>,
    /// How the model is solved: time step, scheme, damping, stopping rule.
    pub numerics: Numerics,
    /// What is solved: gravity, water, rigid bodies, motions, stages, loads.
    pub model: Model,
    /// Quantities updated every step.
    pub state: SolverState,
    /// Points grouped by slab of cells for the scatters, kept until points move.
    pub slabs: SlabCache,
    /// The ranks of the run (one without MPI).
    pub comm: Arc<Comm>,
    /// This rank's cell and node layers (one rank: all of them).
    pub decomposition: Decomposition,
    /// Node columns already summed over the ranks this step (bits of
    /// [`crate::systems::exchange`]); cleared by the grid reset.
    pub exchanged: u8,
}

impl<D: Dim> Context<D> {
    /// The time over which this step moves the points and integrates their strain (s): Δt,
    /// a fraction of it at an interpolated kinetic-damping reset, `None` at a plain reset
    /// ([`crate::state::Resets::motion_dt`]).
    pub fn motion_dt(&self) -> Option<f64> {
        self.state.resets.motion_dt(self.numerics.dt)
    }

    /// The node ids this rank owns when the run has several ranks (each node is owned by
    /// one rank, so sums over owned nodes add up over the ranks); `None` with one rank.
    pub fn owned_node_ids(&self) -> Option<RankNodes> {
        if self.comm.size() == 1 {
            return None;
        }
        let d = &self.decomposition;
        Some(self.grid.rank_nodes(d.owned_nodes(SLAB), d.owned_nodes(ACROSS)))
    }

    /// The node ids whose values this rank holds whole when the run has several ranks
    /// (its own and the bands it shares, once summed: [`Decomposition::held_nodes`]);
    /// `None` with one rank.
    pub fn held_node_ids(&self) -> Option<RankNodes> {
        if self.comm.size() == 1 {
            return None;
        }
        let d = &self.decomposition;
        Some(self.grid.rank_nodes(d.held_nodes(SLAB), d.held_nodes(ACROSS)))
    }
}
