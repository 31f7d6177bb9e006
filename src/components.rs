//! Component columns of the ECS world.
//!
//! Material points and grid nodes are entities of one `hecs::World`. Each component below is
//! one column; systems borrow whole columns of an archetype as plain slices
//! (`infra::columns`). A point carries only what its material and loads need: its
//! material's state column ([`crate::materials::Material::State`]) only where the model has
//! state, a [`PointLoad`] only on points that carry a load. Grid nodes all share one archetype, spawned in id order, so a node
//! column slice is indexed by node id.

/// Current position of a material point (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Position<V>(pub V);

/// Velocity of a material point (m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Velocity<V>(pub V);

/// Total displacement of a material point since the start (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Displacement<V>(pub V);

/// Where a material point was when the static check's window opened (m); points carry it
/// only in a scene with a `static_check`, and it moves with them between ranks and into
/// checkpoints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowStart<V>(pub V);

/// Mass of a material point (kg; per metre of thickness in plane strain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mass(pub f64);

/// Current volume of a material point (m³; m² × 1 m in plane strain).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volume(pub f64);

/// Cauchy stress of a material point (Pa, tension positive), stored as `S` =
/// [`crate::Dim::Stress`]: four components in plane strain, six in 3D.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stress<S>(pub S);

/// Velocity gradient L = ∂v/∂x of the last step (1/s), input of the stress and volume update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityGradient<M>(pub M);

/// Label of a material point (or load carrier), given at set-up in spawn order and kept
/// for the whole run. The spatial sort moves a point's data to another row of its
/// archetype, so this label, not the entity or the row, is what identifies a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PointId(pub u32);

impl PointId {
    /// Puts `value` at this id's index of `list`, growing the list with `gap` as needed:
    /// lists indexed by id hold the points in id order whatever rows they are stored in.
    /// A run's ids are dense (spawn order), so in one process such a list is no longer
    /// than the point set; a rank holds some of them (see [`id_order`]).
    #[inline]
    pub fn place<T: Clone>(self, list: &mut Vec<T>, value: T, gap: T) {
        let i = self.0 as usize;
        if list.len() <= i {
            list.resize(i + 1, gap);
        }
        list[i] = value;
    }
}

/// The rows of `ids` (the points' ids row by row, each id once) sorted by id, into
/// `order`. Its memory follows the rows' count, not the ids' range: a rank of a run over
/// MPI holds some of the run's ids, which start anywhere and, laid across two axes or
/// after migrations, leave wide gaps. Ids spanning at most twice the rows are placed
/// at their offset from the smallest (at most 8 B a row); sparser ones are sorted.
pub fn id_order(ids: impl Iterator<Item = u32> + Clone, order: &mut Vec<u32>) {
    order.clear();
    let (n, lo, hi) = (ids.clone()).fold((0usize, u32::MAX, 0u32), |(n, lo, hi), id| {
        (n + 1, lo.min(id), hi.max(id))
    });
    if n == 0 {
        return;
    }
    let span = (hi - lo) as usize + 1;
    if span <= 2 * n {
        order.resize(span, u32::MAX);
        for (row, id) in ids.enumerate() {
            order[(id - lo) as usize] = row as u32;
        }
        order.retain(|&r| r != u32::MAX);
    } else {
        let mut keys: Vec<u64> = ids
            .enumerate()
            .map(|(row, id)| u64::from(id) << 32 | row as u64)
            .collect();
        keys.sort_unstable();
        order.extend(keys.iter().map(|&k| k as u32));
    }
}

/// Index of the point's material in the simulation's material table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialId(pub u16);

/// A concentrated force carried by a point, applied to the grid each step (N).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad<V>(pub V);

/// Mass lumped at a grid node (kg).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct NodeMass(pub f64);

/// Momentum mapped to a grid node (kg·m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeMomentum<V>(pub V);

/// Out-of-balance force at a node, external plus internal, without damping (N).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeForce<V>(pub V);

/// External force at a node: gravity and point loads (N).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeExternalForce<V>(pub V);

/// Nodal acceleration of the current step, damping included (m/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeAcceleration<V>(pub V);

/// The nodal velocity that moves the points and strains them this step (m/s): the updated
/// velocity in USL, the remapped one in MUSL, the mapped one (for strain) in USF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeVelocity<V>(pub V);

/// Constrained velocity components of a node: bit `a` (0–2) set means axis `a` is held,
/// at zero, or, when the high four bits name a prescribed motion (its index + 1 in
/// [`crate::model::Control::drives`]) that drives the axis, at its velocity. Bit 3
/// ([`NodeFixity::FRICTION`]) marks a node on a `Friction` face.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct NodeFixity(pub u8);

impl NodeFixity {
    /// Most prescribed motions a scene may have.
    pub const MAX_DRIVES: usize = 15;

    /// The bit of a node on a `Friction` face ([`crate::model::Model::friction_faces`]).
    pub const FRICTION: u8 = 0b1000;

    /// True when axis `a` is held.
    #[inline(always)]
    pub fn is_fixed(self, axis: usize) -> bool {
        self.0 & (1 << axis) != 0
    }

    /// The prescribed motion that drives the held axes, if any.
    #[inline(always)]
    pub fn driver(self) -> Option<usize> {
        match self.0 >> 4 {
            0 => None,
            k => Some(k as usize - 1),
        }
    }

    /// Held on the axes of `mask` with prescribed motion `drive` (< [`Self::MAX_DRIVES`]);
    /// the motion's own axes ([`crate::model::Drive::axes`]) move with it, the others stay
    /// fixed.
    pub fn driven(mask: u8, drive: usize) -> NodeFixity {
        debug_assert!(drive < Self::MAX_DRIVES);
        NodeFixity((mask & 0b111) | ((drive as u8 + 1) << 4))
    }
}

/// Calls macro `$mac` with the list of every component type a point can carry in dimension
/// `$d`: the one list that the spatial sort (which moves them all) and checkpoints (which
/// save them all) work from. A new point component is added here; the materials' state
/// columns come from the material registry ([`materials!`](crate::materials!)).
#[macro_export]
#[doc(hidden)]
macro_rules! point_components {
    ($d:ty, $mac:ident) => {
        $crate::materials!([$crate::point_components_and_states] [$d, $mac])
    };
}

/// [`point_components!`] with the registry's materials: the fixed columns, then each
/// material's state (`()`, which no point carries, for a model without state).
#[macro_export]
#[doc(hidden)]
macro_rules! point_components_and_states {
    ([$d:ty, $mac:ident] $($variant:ident($spec:ty)),* $(,)?) => {
        $mac!(
            Position<<$d as Dim>::Vec>,
            Velocity<<$d as Dim>::Vec>,
            Displacement<<$d as Dim>::Vec>,
            PointLoad<<$d as Dim>::Vec>,
            VelocityGradient<<$d as Dim>::Mat>,
            Mass,
            Volume,
            Stress<<$d as Dim>::Stress>,
            MaterialId,
            PointId,
            WindowStart<<$d as Dim>::Vec>
            $(, <<$spec as $crate::materials::SceneMaterial>::Model as $crate::materials::Material>::State)*
        )
    };
}

#[cfg(test)]
mod tests {
    use super::id_order;

    fn sorted(ids: &[u32]) -> Vec<u32> {
        let mut order = vec![7; 3];
        id_order(ids.iter().copied(), &mut order);
        order
    }

    #[test]
    fn rows_come_in_id_order_whether_a_rank_holds_a_run_or_scattered_ids() {
        assert_eq!(sorted(&[]), Vec::<u32>::new());
        // A run of ids from far up, with a gap: placed at their offset.
        assert_eq!(sorted(&[1_000_003, 1_000_000, 1_000_001]), [1, 2, 0]);
        // Ids spread wider than twice the rows: sorted.
        assert_eq!(sorted(&[4_000_000, 9, 2_000_000, 0]), [3, 1, 2, 0]);
    }
}
