//! Sums of node columns over the ranks that share nodes (runs over MPI).
//!
//! Two neighbouring ranks both map into the band of node layers around the cell layer where
//! their ranges meet ([`crate::infra::decomposition`]); each holds a partial sum there. Each sends
//! its band to the other, and both then hold lower rank's part + upper rank's part, added in
//! that order: the same bits on both, so both update those nodes alike and their points read
//! the same field. Sends go up the ranks, then down, so no rank waits on a chain.
//!
//! With one rank every function here returns at once.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::grid::{Grid, NodeBox};
use crate::infra::columns::{col, col_mut, nodes};
use crate::infra::comm::Comm;
use crate::infra::decomposition::{Decomposition, ACROSS, SLAB};
use std::ops::Range;

/// Node mass.
pub const MASS: u8 = 1;
/// Node momentum.
pub const MOMENTUM: u8 = 2;
/// Node force (internal and external, as mapped).
pub const FORCE: u8 = 4;
/// Node external force.
pub const EXTERNAL: u8 = 8;

/// Sums the columns of `what` not yet summed this step over the ranks sharing them.
pub fn exchange<D: Dim>(ctx: &mut Context<D>, what: u8) {
    let todo = what & !ctx.exchanged;
    if todo != 0 {
        exchange_again(ctx, todo);
        ctx.exchanged |= todo;
    }
}

/// Sums the columns of `what` over the ranks sharing them, whether or not they were this
/// step (the MUSL remap maps momentum a second time).
pub fn exchange_again<D: Dim>(ctx: &mut Context<D>, what: u8) {
    if ctx.comm.size() == 1 {
        return;
    }
    let bands = share_bands(
        &ctx.grid,
        &ctx.comm,
        &ctx.decomposition,
        |ids| pack::<D>(ctx, what, ids),
        |ids, lower, upper| {
            let sum: Vec<f64> = lower.iter().zip(upper).map(|(l, u)| l + u).collect();
            unpack::<D>(ctx, what, ids, &sum)
        },
    );
    // The shared bands are part of this rank's grid from now on in the step: reset, updated
    // and read like the nodes its own points reach.
    for b in bands {
        ctx.state.active_nodes = ctx.state.active_nodes.union(b);
    }
}

/// The partial values of the node layers this rank shares with its neighbours, made whole:
/// `pack(rows)` gives this rank's values at a band's nodes (runs of consecutive node ids,
/// any number of values a node, the same layout on both sides), `unpack(rows, lower,
/// upper)` gets the lower rank's part and the upper rank's and combines them (added in that
/// order, the same bits on both ranks). Returns the bands' boxes.
///
/// A two-axis split sums along the slab axis first, over the layers this rank holds across
/// (its own and its bands there), then across, over the layers it holds along the slab
/// axis, the first sums included: a node at a corner of four ranks ends as (lower-left +
/// upper-left) + (lower-right + upper-right) on all four.
pub(crate) fn share_bands<D: Dim>(
    grid: &Grid<D>,
    comm: &Comm,
    decomposition: &Decomposition,
    pack: impl Fn(&[Range<usize>]) -> Vec<f64>,
    mut unpack: impl FnMut(&[Range<usize>], &[f64], &[f64]),
) -> Vec<NodeBox> {
    let mut boxes = Vec::new();
    for axis in [SLAB, ACROSS] {
        let [below, above] = band_boxes(grid, decomposition, axis);
        let (box_below, box_above) = (below.map(|b| b.1), above.map(|a| a.1));
        let rows = |b: Option<NodeBox>| b.map(|b| runs(b.rows(grid)));
        let (rows_below, rows_above) = (rows(box_below), rows(box_above));
        let mine_below = rows_below.as_deref().map(&pack).unwrap_or_default();
        let mine_above = rows_above.as_deref().map(&pack).unwrap_or_default();
        let (rank_below, rank_above) = (below.map(|b| b.0), above.map(|a| a.0));
        let from_below = comm.exchange(rank_above, &mine_above, rank_below);
        let from_above = comm.exchange(rank_below, &mine_below, rank_above);
        if let Some(r) = &rows_below {
            unpack(r, &from_below, &mine_below);
        }
        if let Some(r) = &rows_above {
            unpack(r, &mine_above, &from_above);
        }
        boxes.extend(box_below.into_iter().chain(box_above));
    }
    boxes
}

/// The bands this rank shares with its neighbours below and above along split axis `axis`,
/// as (neighbour, box of nodes): the band's node layers along `axis` and, along the other
/// split axis, every layer this rank holds (its own and its bands there).
pub(crate) fn band_boxes<D: Dim>(
    grid: &Grid<D>,
    decomposition: &Decomposition,
    axis: usize,
) -> [Option<(usize, NodeBox)>; 2] {
    let other = decomposition.held_nodes(1 - axis);
    decomposition.bands(axis).map(|b| {
        b.map(|(rank, l)| {
            let b = match axis {
                SLAB => grid.split_box(l, other.clone()),
                _ => grid.split_box(other.clone(), l),
            };
            (rank, b)
        })
    })
}

/// Runs of consecutive node ids, neighbouring runs joined (a band across the whole grid is
/// one run).
fn runs(rows: impl Iterator<Item = Range<usize>>) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::new();
    for r in rows {
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

/// The values of the columns of `what` at node ids `ids`, in node order, column after
/// column (mass, momentum, force, external force).
fn pack<D: Dim>(ctx: &Context<D>, what: u8, rows: &[Range<usize>]) -> Vec<f64> {
    let n = nodes(&ctx.world);
    let mut out = Vec::new();
    let each = || rows.iter().flat_map(|r| r.clone());
    if what & MASS != 0 {
        let m = col::<NodeMass>(n);
        out.extend(each().map(|i| m[i].0));
    }
    let vectors = |out: &mut Vec<f64>, v: &mut dyn Iterator<Item = D::Vec>| {
        for v in v {
            out.extend_from_slice(&D::vec_to3(v)[..D::N]);
        }
    };
    if what & MOMENTUM != 0 {
        let p = col::<NodeMomentum<D::Vec>>(n);
        vectors(&mut out, &mut each().map(|i| p[i].0));
    }
    if what & FORCE != 0 {
        let f = col::<NodeForce<D::Vec>>(n);
        vectors(&mut out, &mut each().map(|i| f[i].0));
    }
    if what & EXTERNAL != 0 {
        let f = col::<NodeExternalForce<D::Vec>>(n);
        vectors(&mut out, &mut each().map(|i| f[i].0));
    }
    out
}

/// Puts `values` (as [`pack`] lays them out) into the columns of `what` at the nodes of
/// `rows`.
fn unpack<D: Dim>(ctx: &Context<D>, what: u8, rows: &[Range<usize>], values: &[f64]) {
    let n = nodes(&ctx.world);
    let mut at = 0;
    let mut next = |k: usize| {
        let v = &values[at..at + k];
        at += k;
        v
    };
    let vec = |v: &[f64]| {
        let mut c = [0.0; 3];
        c[..D::N].copy_from_slice(v);
        D::vec_from(c)
    };
    let each = || rows.iter().flat_map(|r| r.clone());
    if what & MASS != 0 {
        let mut m = col_mut::<NodeMass>(n);
        each().for_each(|i| m[i].0 = next(1)[0]);
    }
    if what & MOMENTUM != 0 {
        let mut p = col_mut::<NodeMomentum<D::Vec>>(n);
        each().for_each(|i| p[i].0 = vec(next(D::N)));
    }
    if what & FORCE != 0 {
        let mut f = col_mut::<NodeForce<D::Vec>>(n);
        each().for_each(|i| f[i].0 = vec(next(D::N)));
    }
    if what & EXTERNAL != 0 {
        let mut f = col_mut::<NodeExternalForce<D::Vec>>(n);
        each().for_each(|i| f[i].0 = vec(next(D::N)));
    }
}
