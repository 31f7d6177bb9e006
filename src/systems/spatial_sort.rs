//! Spatial sort: the points put back in cell order every few steps.
//!
//! The scatters group points by slab of cells every step, but read each point's data
//! wherever it is stored. Points start in cell order; once a flow mixes them, neighbours in
//! space end up far apart in memory and every transfer misses the cache. Reordering the
//! columns by cell every `sort_every` steps keeps neighbours together.
//!
//! Set-up sorts too: bodies are filled row of points by row of points, so the points of one
//! cell start far apart in memory, and cell order is worth about a third of the block's
//! throughput (`cargo bench -p kdmpm-bench --bench throughput`).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, points_with};
use crate::schedule::System;
use hecs::{Archetype, World};
use rayon::prelude::*;
use std::any::TypeId;

/// Every `every` steps, puts the points in cell order ([`sort_points`]). Set-up leaves
/// them so too.
#[derive(Debug)]
pub struct SpatialSort {
    every: u64,
}

impl SpatialSort {
    /// A sort every `every` steps (≥ 1).
    pub fn new(every: u64) -> Self {
        SpatialSort { every: every.max(1) }
    }
}

/// A point archetype holds a component added outside kdmpm, which a sort could not move
/// along with the point's other data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ForeignComponent;

/// Reorders each point archetype's rows by the id of the cell holding the point (a stable
/// counting sort, so points of one cell keep their relative order). Returns whether any
/// point moved to another row.
///
/// All columns of an archetype move together, so the state is the same set of points with
/// the same data; entities and row indices change meaning, [`PointId`] does not.
pub fn sort_points<D: Dim>(world: &World, grid: &Grid<D>) -> Result<bool, ForeignComponent> {
    let (mut order, mut counts) = (Vec::new(), Vec::new());
    let mut moved = false;
    for arch in points_with::<Position<D::Vec>>(world) {
        if has_foreign_component::<D>(arch) {
            return Err(ForeignComponent);
        }
        let sorted = {
            let x = col::<Position<D::Vec>>(arch);
            cell_order(grid, &x, &mut counts, &mut order)
        };
        if !sorted {
            reorder_columns::<D>(arch, &order);
            moved = true;
        }
    }
    // The buffers are as large as the point set and live only for this call, so that they
    // do not add to the memory a point costs for the whole run.
    Ok(moved)
}

impl<D: Dim> System<D> for SpatialSort {
    fn name(&self) -> &str {
        "spatial_sort"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        ctx.state.points_reordered = false;
        if !ctx.state.clock.step.is_multiple_of(self.every) {
            return Ok(());
        }
        let sorted = sort_points(&ctx.world, &ctx.grid);
        if sorted != Ok(false) {
            ctx.slabs.invalidate();
        }
        ctx.state.points_reordered = sorted.map_err(|ForeignComponent| StepError::Unsortable {
            step: ctx.state.clock.step,
        })?;
        Ok(())
    }
}

/// Fills `order` with the rows of `x` in cell order (stable). Returns true when the rows
/// already are in that order, so nothing needs to move.
fn cell_order<D: Dim>(
    grid: &Grid<D>,
    x: &[Position<D::Vec>],
    counts: &mut Vec<u32>,
    order: &mut Vec<u32>,
) -> bool {
    // Slab axis slowest: a slab's points end up contiguous.
    let key = |p: &Position<D::Vec>| grid.cell_key(p.0);
    if x.windows(2).all(|w| key(&w[0]) <= key(&w[1])) {
        return true;
    }
    counts.clear();
    counts.resize(grid.node_count() + 1, 0);
    for p in x {
        counts[key(p) + 1] += 1;
    }
    for k in 1..counts.len() {
        counts[k] += counts[k - 1];
    }
    order.clear();
    order.resize(x.len(), 0);
    for (row, p) in x.iter().enumerate() {
        let slot = &mut counts[key(p)];
        order[*slot as usize] = row as u32;
        *slot += 1;
    }
    false
}

/// A column whose rows can be permuted in place.
trait Reorder: Send {
    /// Row `r` receives the old row `order[r]`.
    fn reorder(&mut self, order: &[u32]);
}

impl<T: Copy + Send> Reorder for &mut [T] {
    fn reorder(&mut self, order: &[u32]) {
        // Cycle by cycle, so the only extra memory is one bit a row.
        let mut done = vec![0u64; order.len().div_ceil(64)];
        for start in 0..order.len() {
            if done[start / 64] & (1 << (start % 64)) != 0 {
                continue;
            }
            let first = self[start];
            let mut row = start;
            loop {
                done[row / 64] |= 1 << (row % 64);
                let from = order[row] as usize;
                if from == start {
                    self[row] = first;
                    break;
                }
                self[row] = self[from];
                row = from;
            }
        }
    }
}

/// True when `arch` holds a component that is none of the point components above (added
/// by user code): the sort could not move it along with the rest.
fn has_foreign_component<D: Dim>(arch: &Archetype) -> bool {
    macro_rules! known {
        ($($t:ty),*) => { [$(TypeId::of::<$t>()),*] };
    }
    let known = point_components!(D, known);
    arch.component_types().any(|t| !known.contains(&t))
}

/// Moves every column of `arch` by `order`, one column per task.
fn reorder_columns<D: Dim>(arch: &Archetype, order: &[u32]) {
    macro_rules! borrow_all {
        (@push $g:ident $jobs:ident; $($t:ty),*) => {
            borrow_all!(@zip $g $jobs; [0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15] [$($t),*])
        };
        (@zip $g:ident $jobs:ident; [$i:tt $($is:tt)*] [$t:ty $(, $ts:ty)*]) => {
            if let Some(c) = $g.$i.as_deref_mut() {
                $jobs.push(Box::new(c));
            }
            borrow_all!(@zip $g $jobs; [$($is)*] [$($ts),*])
        };
        (@zip $g:ident $jobs:ident; [$($is:tt)*] []) => {};
        ($($t:ty),*) => {{
            // The column borrows live here, on this thread; the tasks get plain slices.
            let mut guards = ($(arch.get::<&mut $t>(),)*);
            let mut jobs: Vec<Box<dyn Reorder + '_>> = Vec::new();
            borrow_all!(@push guards jobs; $($t),*);
            jobs.into_par_iter().for_each(|mut j| j.reorder(order));
        }};
    }
    point_components!(D, borrow_all);
}
