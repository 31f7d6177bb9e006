//! What every system reads and writes.

use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::grid::{Grid, NodeBox, RankNodes};
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
    /// The nodal velocity at each point, Σ_i w_ip v_i (m/s), where g2p gathers it for the
    /// system that moves the points (USL's kinematics, USF's `move_points`:
    /// [`crate::systems::g2p_gathers`]): the points of `points_with::<Velocity>` in order;
    /// empty otherwise.
    pub point_grid_velocity: Vec<D::Vec>,
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

    /// Sets this rank's cells to `d`'s and its grid's window to the nodes they hold
    /// ([`Context::node_window`]): with a new window the node columns are spawned afresh,
    /// zero, held as the model holds them, as after a grid reset.
    pub fn set_decomposition(&mut self, d: Decomposition) {
        self.decomposition = d;
        let window = self.node_window();
        if window == self.grid.window() {
            return;
        }
        self.grid = self.grid.windowed(window);
        let old: Vec<hecs::Entity> = self
            .world
            .query::<(hecs::Entity, &NodeMass)>()
            .iter()
            .map(|(e, _)| e)
            .collect();
        for e in old {
            self.world.despawn(e).expect("listed just now");
        }
        spawn_nodes::<D>(&mut self.world, self.model.node_fixity(&self.grid));
        self.state.active_nodes = NodeBox::default();
        self.slabs.invalidate();
    }

    /// The nodes this rank's grid numbers and its node columns hold: every node on one
    /// rank; over several, along each split axis the nodes its points can reach before they
    /// migrate (a point moves less than a cell a step, so from one cell layer below its
    /// cells to one above, [`Grid::reach`]), which hold the bands it shares
    /// ([`Decomposition::held_nodes`]); every node along the axis no split cuts.
    pub fn node_window(&self) -> NodeBox {
        node_window(&self.grid, &self.decomposition)
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

/// The nodes of `grid` a rank with cells `d` holds ([`Context::node_window`]).
pub fn node_window<D: Dim>(grid: &Grid<D>, d: &Decomposition) -> NodeBox {
    if d.ranks() == 1 {
        return grid.all_nodes();
    }
    if d.is_empty() {
        // No cells: the grid then numbers one node ([`Grid::windowed`]).
        return NodeBox::default();
    }
    let [slab, across] = [SLAB, ACROSS].map(|axis| {
        let (cells, held) = (d.cells_along(axis), d.held_nodes(axis));
        let (lo, hi) = (cells.start.saturating_sub(1), cells.end);
        let layers = grid.axes[[grid.slab_axis, grid.across_axis()][axis]].cells;
        let reach = lo.saturating_sub(1)..(hi.min(layers - 1) + d.support);
        reach.start.min(held.start)..reach.end.max(held.end)
    });
    grid.split_box(slab, across)
}

/// Spawns a grid's nodes into `world`, one archetype in id order, zero and held as
/// `fixity` (one entry a node, [`Model::node_fixity`]) says.
pub fn spawn_nodes<D: Dim>(world: &mut World, fixity: Vec<NodeFixity>) {
    let z = D::Vec::ZERO;
    world.spawn_batch(fixity.into_iter().map(|f| {
        (
            NodeMass(0.0),
            NodeMomentum(z),
            NodeForce(z),
            NodeExternalForce(z),
            NodeAcceleration(z),
            NodeVelocity(z),
            f,
        )
    }));
}
