//! The bytes a system moves through the point and node columns in one call: the byte budget
//! of a step (docs/performance.md, "The byte budget"), shown by `kdmpm run --profile`.
//!
//! Counted as STREAM counts its kernels: every element of a column that a pass reads counts
//! once as read, every element it writes once as written (a read-modify-write counts both),
//! however often the caches serve the same node to neighbouring points. That is the traffic
//! a pass cannot avoid; a pass whose rate is far below the machine's stream rate is bound
//! by something else (arithmetic, gathers, dependent stores). Small per-step state, the
//! scatters' regrouping of points when they change cell and a write's read for ownership
//! are not counted.

use hecs::{Component, World};
use std::ops::AddAssign;

/// Bytes read and written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Traffic {
    /// Bytes read.
    pub read: u64,
    /// Bytes written.
    pub written: u64,
}

impl AddAssign for Traffic {
    fn add_assign(&mut self, other: Traffic) {
        self.read += other.read;
        self.written += other.written;
    }
}

/// The points that have column `T`.
fn point_rows<T: Component>(world: &World) -> u64 {
    crate::infra::columns::points_with::<T>(world)
        .map(|a| u64::from(a.len()))
        .sum()
}

/// Bytes of column `T` over the points that have it.
fn point_bytes<T: Component>(world: &World) -> u64 {
    point_rows::<T>(world) * std::mem::size_of::<T>() as u64
}

/// Bytes of column `T` over `nodes` nodes.
fn node_bytes<T: Component>(nodes: usize) -> u64 {
    (nodes * std::mem::size_of::<T>()) as u64
}

impl Traffic {
    /// Nothing moved (a step the system skips, a system that keeps to its own state).
    pub const NONE: Traffic = Traffic { read: 0, written: 0 };

    /// Bytes read and written together.
    pub fn total(self) -> u64 {
        self.read + self.written
    }

    /// Column `T` of every point that has it, read.
    pub fn read_points<T: Component>(mut self, world: &World) -> Self {
        self.read += point_bytes::<T>(world);
        self
    }

    /// Column `T` of every point that has it, written without being read.
    pub fn write_points<T: Component>(mut self, world: &World) -> Self {
        self.written += point_bytes::<T>(world);
        self
    }

    /// Column `T` of every point that has it, read and written.
    pub fn update_points<T: Component>(self, world: &World) -> Self {
        self.read_points::<T>(world).write_points::<T>(world)
    }

    /// A value of type `V` kept beside the columns (a system's scratch) for every point
    /// that has column `T`, read.
    pub fn read_per_point<T: Component, V>(mut self, world: &World) -> Self {
        self.read += point_rows::<T>(world) * std::mem::size_of::<V>() as u64;
        self
    }

    /// A value of type `V` kept beside the columns for every point that has column `T`,
    /// written without being read.
    pub fn write_per_point<T: Component, V>(mut self, world: &World) -> Self {
        self.written += point_rows::<T>(world) * std::mem::size_of::<V>() as u64;
        self
    }

    /// Column `T` of `nodes` nodes, read.
    pub fn read_nodes<T: Component>(mut self, nodes: usize) -> Self {
        self.read += node_bytes::<T>(nodes);
        self
    }

    /// Column `T` of `nodes` nodes, written without being read.
    pub fn write_nodes<T: Component>(mut self, nodes: usize) -> Self {
        self.written += node_bytes::<T>(nodes);
        self
    }

    /// Column `T` of `nodes` nodes, read and written.
    pub fn update_nodes<T: Component>(self, nodes: usize) -> Self {
        self.read_nodes::<T>(nodes).write_nodes::<T>(nodes)
    }

    /// The scatters' order of the points that have column `T`: a `u32` row index a point
    /// ([`crate::SlabCache`]), read.
    pub fn read_order<T: Component>(mut self, world: &World) -> Self {
        self.read += point_rows::<T>(world) * std::mem::size_of::<u32>() as u64;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::{Mass, NodeMass, Position};
    use glam::DVec3;

    #[test]
    fn counts_point_columns_over_point_archetypes_only() {
        let mut world = World::new();
        for k in 0..5 {
            world.spawn((Position(DVec3::splat(k as f64)), Mass(1.0)));
        }
        world.spawn((Position(DVec3::ZERO),));
        // A node: its columns are not points'.
        world.spawn((NodeMass(0.0), Mass(1.0)));
        let t = Traffic::NONE
            .read_points::<Position<DVec3>>(&world)
            .update_points::<Mass>(&world)
            .write_nodes::<NodeMass>(3);
        assert_eq!(t.read, 6 * 24 + 5 * 8);
        assert_eq!(t.written, 5 * 8 + 3 * 8);
        assert_eq!(t.total(), 6 * 24 + 10 * 8 + 24);
    }
}
