//! Borrowing component columns as slices.
//!
//! Hot loops never look entities up one by one: they take the columns of an archetype as
//! `&[T]` / `&mut [T]` through these helpers and index them together.

use crate::components::NodeMass;
use crate::materials::{visit_states, MaterialState, StateVisitor};
use hecs::{Archetype, ArchetypeColumn, ArchetypeColumnMut, Component, World};

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

/// Appends the accumulated plastic strain of each point of `arch` to `out`, in row order:
/// from the column of its material's state, 0 where the points carry no state.
pub fn extend_plastic_strain(arch: &Archetype, out: &mut Vec<f64>) {
    struct Extend<'a>(&'a Archetype, &'a mut Vec<f64>, bool);
    impl StateVisitor for Extend<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let (false, Some(c)) = (self.2, self.0.get::<&S>()) {
                self.1.extend(c.iter().map(S::plastic_strain));
                self.2 = true;
            }
        }
    }
    let mut e = Extend(arch, out, false);
    visit_states(&mut e);
    if !e.2 {
        out.resize(out.len() + arch.len() as usize, 0.0);
    }
}

/// The first row of `arch` whose material state holds a value that is not finite.
pub fn first_non_finite_state(arch: &Archetype) -> Option<usize> {
    struct Find<'a>(&'a Archetype, Option<usize>);
    impl StateVisitor for Find<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let (None, Some(c)) = (self.1, self.0.get::<&S>()) {
                self.1 = c.iter().position(|s| !s.is_finite());
            }
        }
    }
    let mut f = Find(arch, None);
    visit_states(&mut f);
    f.1
}
