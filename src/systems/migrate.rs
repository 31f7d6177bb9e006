//! Points that left this rank's cells move to the neighbouring rank (runs over MPI).
//!
//! [`Migrate`] ends every step of a run over several ranks (`distribute::join` adds
//! it): a point moves less than a cell a step, so at the next mapping every point lies in
//! its rank's layers and maps only into that rank's nodes and the bands it shares. A point goes
//! with every column it has (the list of `point_components!`,
//! its material's state and its [`PointId`] included) and is spawned again on the other
//! side, so a run's points are the same set whatever the rank count.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, points_with};
use crate::infra::decomposition::{Decomposition, ACROSS, SLAB};
use crate::schedule::System;
use hecs::{Entity, EntityBuilder, World};

/// The last system of a step over several ranks: [`migrate`], then [`rebalance`].
#[derive(Debug, Default)]
pub struct Migrate;

impl<D: Dim> System<D> for Migrate {
    fn name(&self) -> &str {
        "migrate"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        migrate(ctx);
        rebalance(ctx);
        Ok(())
    }
}

/// Steps between two looks at the ranks' balance.
pub const REBALANCE_EVERY: u64 = 100;

/// Largest point count of a rank over the mean above which the layers are split again.
pub const IMBALANCE_LIMIT: f64 = 1.2;

/// Every [`REBALANCE_EVERY`] steps, splits the cells again by point count when the ranks'
/// loads differ by more than [`IMBALANCE_LIMIT`] (a failing slope moves its points down and
/// out), and moves the points to their new ranks; true when it did. A collective.
pub fn rebalance<D: Dim>(ctx: &mut Context<D>) -> bool {
    if ctx.comm.size() == 1 || !ctx.state.clock.step.is_multiple_of(REBALANCE_EVERY) {
        return false;
    }
    let d = &ctx.decomposition;
    let split = d.split();
    // Layers across count only when the ranks are cut across.
    let across = if split[ACROSS] > 1 {
        ctx.grid.axes[ctx.grid.across_axis()].cells
    } else {
        1
    };
    let mut counts: Vec<f64> = cell_counts(ctx, across).iter().map(|&c| c as f64).collect();
    ctx.comm.sum(&mut counts);
    let counts: Vec<u64> = counts.iter().map(|&c| c as u64).collect();
    if Decomposition::imbalance(&d.points_per_rank(&counts, across)) <= IMBALANCE_LIMIT {
        return false;
    }
    // Each axis cut again on the points in its layers.
    let slab: Vec<u64> = counts.chunks(across).map(|row| row.iter().sum()).collect();
    let next = Decomposition {
        bounds: Decomposition::cuts(&slab, split[SLAB], d.support),
        across: if split[ACROSS] > 1 {
            let columns: Vec<u64> = (0..across)
                .map(|j| counts.iter().skip(j).step_by(across).sum())
                .collect();
            Decomposition::cuts(&columns, split[ACROSS], d.support)
        } else {
            d.across.clone()
        },
        ..d.clone()
    };
    if next == *d {
        return false;
    }
    ctx.set_decomposition(next);
    ctx.state.ranks.rebalances += 1;
    migrate(ctx);
    true
}

/// This rank's points in each cell's layers along the slab axis and the second split axis,
/// `[slab layer][across layer]` row-major over `across` layers across (1: the slab axis
/// alone).
pub fn cell_counts<D: Dim>(ctx: &Context<D>, across: usize) -> Vec<u64> {
    let grid = &ctx.grid;
    let mut counts = vec![0u64; grid.axes[grid.slab_axis].cells * across];
    for arch in points_with::<Position<D::Vec>>(&ctx.world) {
        for x in col::<Position<D::Vec>>(arch).iter() {
            let [i, j] = grid.split_cell(x.0);
            counts[i * across + if across > 1 { j } else { 0 }] += 1;
        }
    }
    counts
}

/// Sends this rank's points outside its cells towards the ranks that own them and spawns
/// the points the others send, until every point is on its owner; true when points came or
/// went (rows moved: slabs and traced points must be found again). A collective.
///
/// Points move along the slab axis first, then across: the neighbours along the slab axis
/// hold the same layers across, so a point that crossed a corner reaches its owner in two
/// hops.
pub fn migrate<D: Dim>(ctx: &mut Context<D>) -> bool {
    if ctx.comm.size() == 1 {
        return false;
    }
    let mut moved = false;
    for axis in [SLAB, ACROSS] {
        if ctx.decomposition.split()[axis] == 1 {
            continue;
        }
        // A point hops one rank at a time, so one that must cross an empty rank (or
        // several, after a new decomposition) takes more than one round.
        loop {
            let (left, came, astray) = migrate_once(ctx, axis);
            moved |= left + came > 0;
            if !ctx.comm.any(astray) {
                break;
            }
        }
    }
    if moved {
        ctx.slabs.invalidate();
        ctx.state.points_reordered = true;
    }
    moved
}

/// One round along split axis `axis`: points below this rank's layers along it go to the
/// part below, points above to the part above, and the points they send come in. Returns
/// the points sent, the points received and whether a received point is still outside this
/// rank's layers along that axis.
fn migrate_once<D: Dim>(ctx: &mut Context<D>, axis: usize) -> (usize, usize, bool) {
    let d = &ctx.decomposition;
    let [parts, me] = [d.split()[axis], d.part_of(d.rank)[axis]];
    let below = me.checked_sub(1).map(|k| d.rank_along(axis, k));
    let above = (me + 1 < parts).then(|| d.rank_along(axis, me + 1));
    let cells = d.cells_along(axis);
    let grid = &ctx.grid;
    let (mut down, mut up): (Vec<Entity>, Vec<Entity>) = (Vec::new(), Vec::new());
    for (e, x) in ctx.world.query::<(Entity, &Position<D::Vec>)>().iter() {
        let c = grid.split_cell(x.0)[axis];
        if c < cells.start {
            down.push(e);
        } else if c >= cells.end {
            up.push(e);
        }
    }
    let pack = |world: &World, list: &[Entity]| -> Vec<f64> {
        let mut bytes = Vec::new();
        for &e in list {
            write_point::<D>(world, e, &mut bytes);
        }
        words(bytes)
    };
    let (to_below, to_above) = (pack(&ctx.world, &down), pack(&ctx.world, &up));
    for e in down.iter().chain(&up) {
        ctx.world.despawn(*e).expect("a point found above");
    }
    ctx.state.ranks.migrations += (down.len() + up.len()) as u64;
    let from_below = ctx.comm.exchange(above, &to_above, below);
    let from_above = ctx.comm.exchange(below, &to_below, above);
    let (mut came, mut astray) = (0, false);
    for message in [from_below, from_above] {
        let bytes: &[u8] = bytemuck::cast_slice(&message);
        let mut at = 0;
        loop {
            let mut builder = EntityBuilder::new();
            let Some(x) = read_point::<D>(bytes, &mut at, &mut builder) else {
                break;
            };
            astray |= !cells.contains(&ctx.grid.split_cell(x)[axis]);
            ctx.world.spawn(builder.build());
            came += 1;
        }
    }
    (down.len() + up.len(), came, astray)
}

/// Bytes as whole f64 words (zero-padded), the unit [`crate::infra::comm::Comm::exchange`] sends.
fn words(mut bytes: Vec<u8>) -> Vec<f64> {
    bytes.resize(bytes.len().div_ceil(8) * 8, 0);
    bytes
        .chunks_exact(8)
        .map(|w| f64::from_ne_bytes(w.try_into().expect("8 bytes")))
        .collect()
}

/// Appends point `e`: a mask of the components it has (bit k: the k-th of
/// `point_components!`), then each one's bytes.
fn write_point<D: Dim>(world: &World, e: Entity, out: &mut Vec<u8>) {
    let point = world.entity(e).expect("a point found above");
    let at = out.len();
    out.extend_from_slice(&0u64.to_le_bytes());
    let mut mask = 0u64;
    let mut bit = 0;
    macro_rules! write {
        ($($t:ty),*) => {$(
            if let Some(c) = point.get::<&$t>() {
                mask |= 1 << bit;
                // SAFETY: every point component is a plain struct of f64, u32 or u16 fields
                // without padding (checkpoint's `point_components_have_no_padding`, and the
                // `Pod` bound of a material's state), so each of its bytes is initialised.
                out.extend_from_slice(unsafe { value_bytes::<$t>(&c) });
            }
            bit += 1;
        )*};
    }
    point_components!(D, write);
    let _ = bit;
    out[at..at + 8].copy_from_slice(&mask.to_le_bytes());
    // Keep the next point on an 8-byte boundary, as the padding of the message does.
    out.resize(out.len().div_ceil(8) * 8, 0);
}

/// Reads the point at `*at` (as [`write_point`] wrote it) into `builder` and returns its
/// position; `None` at the message's end.
fn read_point<D: Dim>(bytes: &[u8], at: &mut usize, builder: &mut EntityBuilder) -> Option<D::Vec> {
    if *at + 8 > bytes.len() {
        return None;
    }
    let mask = u64::from_le_bytes(bytes[*at..*at + 8].try_into().expect("8 bytes"));
    if mask == 0 {
        return None;
    }
    // Every point has a position, the first of the list.
    let mut position = None;
    *at += 8;
    let mut bit = 0;
    macro_rules! read {
        ($($t:ty),*) => {$(
            if mask & (1 << bit) != 0 {
                let n = std::mem::size_of::<$t>();
                // SAFETY: the bytes were written by `write_point` from a value of this type,
                // a plain struct for which every bit pattern it was written with is valid;
                // the read is unaligned-safe.
                let v: $t = unsafe { std::ptr::read_unaligned(bytes[*at..*at + n].as_ptr().cast::<$t>()) };
                if bit == 0 {
                    debug_assert_eq!(n, std::mem::size_of::<Position<D::Vec>>());
                    // SAFETY: as above; the first component of the list is the position.
                    position = Some(unsafe {
                        std::ptr::read_unaligned(bytes[*at..*at + n].as_ptr().cast::<Position<D::Vec>>())
                    });
                }
                builder.add(v);
                *at += n;
            }
            bit += 1;
        )*};
    }
    point_components!(D, read);
    let _ = bit;
    *at = (*at).div_ceil(8) * 8;
    Some(position.expect("every point has a position").0)
}

/// The bytes of one value.
///
/// # Safety
/// `T` must have no padding bytes.
unsafe fn value_bytes<T>(v: &T) -> &[u8] {
    // SAFETY: the caller guarantees every byte is initialised; the length is the value's.
    unsafe { std::slice::from_raw_parts((v as *const T).cast::<u8>(), std::mem::size_of::<T>()) }
}
