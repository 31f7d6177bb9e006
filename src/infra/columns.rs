//! Borrowing component columns as slices.
//!
//! Hot loops never look entities up one by one: they take the columns of an archetype as
//! `&[T]` / `&mut [T]` through these helpers and index them together.

use crate::components::NodeMass;
use hecs::{Archetype, ArchetypeColumn, ArchetypeColumnMut, ColumnBatchBuilder, Component, World};

/// Read access to column `T` of `arch`. Panics if the archetype lacks it: systems only ask
/// for columns that the archetype filter guarantees.
#[inline]
pub fn col<T: Component>(arch: &Archetype) -> ArchetypeColumn<'_, T> {
    arch.get::<&T>()
        .unwrap_or_else(|| panic!("archetype lacks column {}", std::any::type_name::<T>()))
}

/// Write access to column `T` of `arch` (see [`col`]).
#[inline]
pub fn col_mut<T: Component>(arch: &Archetype) -> ArchetypeColumnMut<'_, T> {
    arch.get::<&mut T>()
        .unwrap_or_else(|| panic!("archetype lacks column {}", std::any::type_name::<T>()))
}

/// The archetype holding the grid nodes (all nodes share it, in id order).
pub fn nodes(world: &World) -> &Archetype {
    world
        .archetypes()
        .find(|a| a.has::<NodeMass>() && !a.is_empty())
        .expect("world has no grid nodes")
}

/// Non-empty archetypes that hold component `T` and are not grid nodes: the material-point
/// archetypes a system visits.
pub fn points_with<T: Component>(world: &World) -> impl Iterator<Item = &Archetype> {
    world
        .archetypes()
        .filter(|a| a.has::<T>() && !a.is_empty() && !a.has::<NodeMass>())
}

/// Writes `values` into the column of `T` of a batch of points about to be spawned, if the
/// batch has one (the set-up's spawn, a checkpoint's points spawned again on their rank).
pub fn fill<T: Component>(batch: &ColumnBatchBuilder, values: impl Iterator<Item = T>) {
    if let Some(mut w) = batch.writer::<T>() {
        for v in values {
            if w.push(v).is_err() {
                unreachable!("a batch holds exactly its points");
            }
        }
    }
}
