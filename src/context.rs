//! What every system reads and writes.

use crate::dim::Dim;
use crate::grid::Grid;
use crate::materials::MaterialModel;
use crate::parallel::SlabCache;
use crate::state::{Settings, SolverState};
use hecs::World;

/// Everything the systems read and write: the world (points and nodes), the grid, the
/// material table and the solver-wide state.
pub struct Context<D: Dim> {
    /// Points and nodes.
    pub world: World,
    /// Background grid geometry.
    pub grid: Grid<D>,
    /// Materials, indexed by [`MaterialId`](crate::components::MaterialId).
    pub materials: Vec<MaterialModel>,
    /// Fixed settings.
    pub settings: Settings,
    /// Quantities updated every step.
    pub state: SolverState,
    /// Points grouped by slab of cells for the scatters, kept until points move.
    pub slabs: SlabCache,
}
