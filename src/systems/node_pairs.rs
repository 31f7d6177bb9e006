//! Two sums a node, scattered from the points through the shape functions: the numerator
//! and denominator of a weighted nodal average (volumetric smoothing), or a weighted sum
//! and a maximum (mass scaling); or two sums a cell, kept at the cell's lowest node (the
//! cell means against locking). Shared by the systems that need such a field for one step.

use crate::components::{Position, VelocityGradient};
use crate::dim::Dim;
use crate::grid::{Grid, NodeBox};
use crate::infra::columns::{col, col_mut};
use crate::infra::comm::Comm;
use crate::infra::decomposition::Decomposition;
use crate::parallel::CHUNK;
use crate::parallel::{fill_box, for_each_box_node, scatter, Disjoint, SlabCache};
use crate::shape::{for_each_node, Shape};
use crate::systems::exchange::share_bands;
use hecs::Archetype;
use rayon::prelude::*;

/// Per node a pair `[f64; 2]`, zero outside the box the points reached since the last
/// [`NodePairs::clear`], so a step pays only for the nodes in use.
#[derive(Debug, Default)]
pub(crate) struct NodePairs {
    sums: Vec<[f64; 2]>,
    active: NodeBox,
    /// The window of nodes `sums` is numbered by ([`Grid::window`]).
    window: NodeBox,
}

impl NodePairs {
    /// Sizes the pairs for `grid`'s nodes: all zero again when its window moved (a rank
    /// whose cells were split anew).
    fn fit<D: Dim>(&mut self, grid: &Grid<D>) {
        if self.window != grid.window() {
            self.window = grid.window();
            self.sums.clear();
            self.active = NodeBox::default();
        }
        self.sums.resize(grid.node_count(), [0.0; 2]);
    }

    /// Adds the points at `x` (a column of one archetype): for each point p its value
    /// `value(p)`, computed once, goes into every node i it reaches with weight w_ip
    /// through `add(pair_i, w_ip, &value)`. Deterministic: the scatter's slabs fix each
    /// node's order of contributions.
    pub(crate) fn scatter<D: Dim, S: Shape, V>(
        &mut self,
        slabs: &mut SlabCache,
        grid: &Grid<D>,
        x: &[Position<D::Vec>],
        value: impl Fn(usize) -> V + Sync,
        add: impl Fn(&mut [f64; 2], f64, &V) + Sync,
    ) {
        self.each_point::<D, S>(slabs, grid, x, |p, sums, lo| {
            let v = value(p);
            for_each_node::<D, S>(grid, x[p].0, |i, w, _| add(&mut sums[i - lo], w, &v));
        });
    }

    /// Adds the points at `x` (a column of one archetype) cell by cell: `value(p)` goes into
    /// the pair of the lowest node of the cell that holds point p, whole. Deterministic as
    /// [`NodePairs::scatter`]: the slabs fix each cell's order of contributions (a slab lists
    /// its points in point order, so a cell's are added in point order), and a cell's
    /// lowest node lies in the node range of its point's slab whatever the shape.
    pub(crate) fn scatter_cells<D: Dim, S: Shape>(
        &mut self,
        slabs: &mut SlabCache,
        grid: &Grid<D>,
        x: &[Position<D::Vec>],
        value: impl Fn(usize) -> [f64; 2] + Sync,
    ) {
        self.scatter_cells_where::<D, S>(slabs, grid, x, |p| Some(value(p)));
    }

    /// [`NodePairs::scatter_cells`] of the points whose `value` is `Some`; the others add
    /// nothing.
    pub(crate) fn scatter_cells_where<D: Dim, S: Shape>(
        &mut self,
        slabs: &mut SlabCache,
        grid: &Grid<D>,
        x: &[Position<D::Vec>],
        value: impl Fn(usize) -> Option<[f64; 2]> + Sync,
    ) {
        self.each_point::<D, S>(slabs, grid, x, |p, sums, lo| {
            if let Some([a, b]) = value(p) {
                let pair = &mut sums[grid.cell_key(x[p].0) - lo];
                pair[0] += a;
                pair[1] += b;
            }
        });
    }

    /// The scatter both sums share: `add(p, pairs, first_node)` for every point p at `x`,
    /// slab by slab, with the pairs of the slab's node range starting at `first_node`.
    fn each_point<D: Dim, S: Shape>(
        &mut self,
        slabs: &mut SlabCache,
        grid: &Grid<D>,
        x: &[Position<D::Vec>],
        add: impl Fn(usize, &mut [[f64; 2]], usize) + Sync,
    ) {
        self.fit(grid);
        let reached = scatter(
            slabs.slabs(grid, x),
            grid,
            S::SUPPORT,
            &Disjoint::new(&mut self.sums),
            |points, sums, lo| {
                for &p in points {
                    add(p as usize, sums, lo);
                }
            },
        );
        self.active = self.active.union(reached);
    }

    /// The pair of the cell that holds `x`, after [`NodePairs::scatter_cells`].
    #[inline(always)]
    pub(crate) fn of_cell<D: Dim>(&self, grid: &Grid<D>, x: D::Vec) -> [f64; 2] {
        self.sums[grid.cell_key(x)]
    }

    /// The pair of node `node`, to change by hand (a node the points reached since the
    /// last [`NodePairs::clear`], or it is not cleared).
    pub(crate) fn at_mut(&mut self, node: usize) -> &mut [f64; 2] {
        &mut self.sums[node]
    }

    /// Replaces the pair of every node the points reached by `f(pair)`.
    pub(crate) fn map<D: Dim>(&mut self, grid: &Grid<D>, f: impl Fn([f64; 2]) -> [f64; 2] + Sync) {
        for_each_box_node(grid, self.active, &Disjoint::new(&mut self.sums), |_, k, sums| {
            sums[k] = f(sums[k]);
        });
    }

    /// The pairs, by node index.
    pub(crate) fn pairs(&self) -> &[[f64; 2]] {
        &self.sums
    }

    /// Over MPI ranks: the pairs of the node layers this rank shares with its neighbours
    /// made whole (both hold the lower rank's part plus the upper's, as
    /// [`crate::systems::exchange`] sums the node columns), those layers then counted as
    /// reached. Cell sums, kept at a cell's lowest node, are made whole alike: a point that
    /// crossed into the next rank's cell layers this step has not moved rank yet. With one
    /// rank nothing happens.
    pub(crate) fn sum_over_ranks<D: Dim>(
        &mut self,
        grid: &Grid<D>,
        comm: &Comm,
        decomposition: &Decomposition,
    ) {
        self.combine_over_ranks(grid, comm, decomposition, |l, u| [l[0] + u[0], l[1] + u[1]]);
    }

    /// Cell means of weighted sums: the pairs Σ w q, Σ w [`NodePairs::sum_over_ranks`],
    /// then each one [Σ w q / Σ w, Σ w]. Every cell a point was scattered into has Σ w > 0;
    /// the others read 0 and are never asked.
    pub(crate) fn means_over_ranks<D: Dim>(
        &mut self,
        grid: &Grid<D>,
        comm: &Comm,
        decomposition: &Decomposition,
    ) {
        self.sum_over_ranks(grid, comm, decomposition);
        self.map(grid, |s| [if s[1] > 0.0 { s[0] / s[1] } else { 0.0 }, s[1]]);
    }

    /// As [`NodePairs::sum_over_ranks`], each shared pair `combine(lower rank's, upper
    /// rank's)` (a sum and a largest value, for mass scaling).
    pub(crate) fn combine_over_ranks<D: Dim>(
        &mut self,
        grid: &Grid<D>,
        comm: &Comm,
        decomposition: &Decomposition,
        combine: impl Fn([f64; 2], [f64; 2]) -> [f64; 2],
    ) {
        if comm.size() == 1 {
            return;
        }
        self.fit(grid);
        let sums = std::cell::RefCell::new(&mut self.sums);
        let bands = share_bands(
            grid,
            comm,
            decomposition,
            |rows| {
                let sums = sums.borrow();
                rows.iter()
                    .flat_map(|r| sums[r.clone()].as_flattened())
                    .copied()
                    .collect()
            },
            |rows, lower, upper| {
                let mut sums = sums.borrow_mut();
                let pairs = rows.iter().flat_map(|r| r.clone());
                for ((i, l), u) in pairs.zip(lower.chunks_exact(2)).zip(upper.chunks_exact(2)) {
                    sums[i] = combine([l[0], l[1]], [u[0], u[1]]);
                }
            },
        );
        for b in bands {
            self.active = self.active.union(b);
        }
    }

    /// Zeroes the nodes the points reached, for the next step.
    pub(crate) fn clear<D: Dim>(&mut self, grid: &Grid<D>) {
        fill_box(grid, self.active, &mut self.sums, [0.0; 2]);
        self.active = NodeBox::default();
    }
}

/// L_p ← L_p + (θ_p − tr L_p) I / n for every point of `archetypes`, θ_p = `theta(x_p)`:
/// the point's rate of volume change replaced, its deviatoric rate and spin kept (the nodal
/// smoothing and the cell means, n = `Dim::STRAIN_AXES`).
pub(crate) fn set_volumetric_rates<'w, D: Dim>(
    archetypes: impl Iterator<Item = &'w Archetype>,
    theta: impl Fn(D::Vec) -> f64 + Sync,
) {
    for arch in archetypes {
        set_volumetric_rates_where::<D>(arch, |_, x| Some(theta(x)));
    }
}

/// [`set_volumetric_rates`] in one archetype, for the points p whose `theta(p, x_p)` is
/// `Some`; the others keep their own rate.
pub(crate) fn set_volumetric_rates_where<D: Dim>(
    arch: &Archetype,
    theta: impl Fn(usize, D::Vec) -> Option<f64> + Sync,
) {
    let n = D::STRAIN_AXES as f64;
    let xg = col::<Position<D::Vec>>(arch);
    let x: &[Position<D::Vec>] = &xg;
    let mut lg = col_mut::<VelocityGradient<D::Mat>>(arch);
    lg.par_chunks_mut(CHUNK).enumerate().for_each(|(c, l)| {
        for (k, lp) in l.iter_mut().enumerate() {
            let p = c * CHUNK + k;
            if let Some(theta) = theta(p, x[p].0) {
                let shift = (theta - D::volumetric_rate(&lp.0)) / n;
                D::add_identity(&mut lp.0, shift);
            }
        }
    });
}
