//! Deterministic parallel building blocks.
//!
//! Work is split into pieces whose boundaries depend only on the data (fixed-size chunks of
//! points, fixed slabs of grid rows), never on the number of threads, and partial results
//! are combined in piece order. So a run gives the same bits on 1 or 2 threads, and from
//! run to run. No atomics are involved.

use crate::dim::Dim;
use crate::grid::Grid;
use rayon::prelude::*;

/// Points per chunk in point-local loops.
pub const CHUNK: usize = 2048;

/// Sums `f(chunk_index, range)` over fixed chunks of `0..n` in parallel, adding the partial
/// sums in chunk order.
pub fn sum_chunks(n: usize, f: impl Fn(std::ops::Range<usize>) -> f64 + Sync) -> f64 {
    let parts: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| f(c * CHUNK..((c + 1) * CHUNK).min(n)))
        .collect();
    parts.iter().sum()
}

/// Points grouped into slabs of grid rows along the slowest axis (y in 2D, z in 3D), so that
/// each slab scatters into its own contiguous range of node ids.
#[derive(Debug, Default)]
pub struct Slabs {
    /// Cell rows per slab.
    rows: usize,
    /// `order[offsets[s]..offsets[s + 1]]` are the point indices in slab `s`, ascending.
    offsets: Vec<usize>,
    order: Vec<u32>,
    slab_of: Vec<u32>,
}

impl Slabs {
    /// Groups `positions` by slab. `rows` is the slab thickness in cells.
    pub fn build<D: Dim>(
        &mut self,
        grid: &Grid<D>,
        positions: impl ExactSizeIterator<Item = D::Vec>,
        rows: usize,
    ) {
        let axis = D::N - 1;
        let slabs = grid.cells[axis].div_ceil(rows);
        self.rows = rows;
        self.slab_of.clear();
        self.slab_of.extend(positions.map(|x| {
            let c = (grid.grid_coordinate(x, axis).max(0.0) as usize).min(grid.cells[axis] - 1);
            (c / rows) as u32
        }));
        self.offsets.clear();
        self.offsets.resize(slabs + 1, 0);
        for &s in &self.slab_of {
            self.offsets[s as usize + 1] += 1;
        }
        for s in 0..slabs {
            self.offsets[s + 1] += self.offsets[s];
        }
        let mut fill = self.offsets.clone();
        self.order.clear();
        self.order.resize(self.slab_of.len(), 0);
        for (p, &s) in self.slab_of.iter().enumerate() {
            self.order[fill[s as usize]] = p as u32;
            fill[s as usize] += 1;
        }
    }

    /// Number of slabs.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no slabs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Point indices of slab `s`.
    pub fn points(&self, s: usize) -> &[u32] {
        &self.order[self.offsets[s]..self.offsets[s + 1]]
    }

    /// The node ids slab `s` can touch with a support of `support` nodes per axis.
    pub fn node_range<D: Dim>(&self, grid: &Grid<D>, s: usize, support: usize) -> std::ops::Range<usize> {
        let axis = D::N - 1;
        let layer = grid.node_count() / grid.nodes[axis];
        let first = (s * self.rows).saturating_sub(1);
        let last = ((s + 1) * self.rows + support).min(grid.nodes[axis]);
        first * layer..last * layer
    }
}

/// A deterministic parallel scatter from points to nodes: the points' slabs and per-slab
/// node buffers, reused between steps.
#[derive(Debug)]
pub struct ScatterBuffers<T> {
    slabs: Slabs,
    buffers: Vec<(std::ops::Range<usize>, Vec<T>)>,
}

impl<T> Default for ScatterBuffers<T> {
    fn default() -> Self {
        ScatterBuffers {
            slabs: Slabs::default(),
            buffers: Vec::new(),
        }
    }
}

impl<T: Copy + Send + Sync> ScatterBuffers<T> {
    /// Groups the points at `positions` into slabs, then runs
    /// `scatter(points, buffer, first_node)` for every non-empty slab in parallel, each into
    /// a zeroed buffer that covers the slab's node ids from `first_node` on (`points` are
    /// indices into `positions`). Then hands every buffer entry to `target(node, value)` in
    /// slab order.
    pub fn scatter<D: Dim>(
        &mut self,
        grid: &Grid<D>,
        positions: impl ExactSizeIterator<Item = D::Vec>,
        support: usize,
        zero: T,
        scatter: impl Fn(&[u32], &mut [T], usize) + Sync,
        mut target: impl FnMut(usize, T),
    ) {
        self.slabs.build(grid, positions, slab_rows(grid, support));
        let slabs = &self.slabs;
        self.buffers.resize_with(slabs.len(), || (0..0, Vec::new()));
        self.buffers
            .par_iter_mut()
            .enumerate()
            .for_each(|(s, (range, buf))| {
                let points = slabs.points(s);
                if points.is_empty() {
                    *range = 0..0;
                    return;
                }
                *range = slabs.node_range(grid, s, support);
                buf.clear();
                buf.resize(range.len(), zero);
                scatter(points, buf, range.start);
            });
        for (range, buf) in &self.buffers {
            for (k, v) in buf.iter().enumerate().take(range.len()) {
                target(range.start + k, *v);
            }
        }
    }
}

/// Slab thickness for a grid: at least the shape support, and about 64 slabs at most.
pub fn slab_rows<D: Dim>(grid: &Grid<D>, support: usize) -> usize {
    grid.cells[D::N - 1].div_ceil(64).max(support)
}
