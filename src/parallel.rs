//! Deterministic parallel building blocks.
//!
//! Work is split into pieces whose boundaries depend only on the data (fixed-size chunks of
//! points, slabs of grid rows, groups of node layers), never on the number of threads, and
//! partial results are combined in piece order. So a run gives the same bits on 1 or 2
//! threads, and from run to run. No atomics are involved.

use crate::components::Position;
use crate::dim::Dim;
use crate::grid::{Grid, NodeBox};
use rayon::prelude::*;
use std::marker::PhantomData;
use std::ops::Range;

/// Points per chunk in point-local loops.
pub const CHUNK: usize = 2048;

/// A column that not every archetype has, cut into the [`CHUNK`]s of a loop over `len`
/// points: its chunks, or one `None` a chunk where the column is absent, to zip beside the
/// columns every archetype has.
pub fn optional_chunks<T>(column: Option<&mut [T]>, len: usize) -> Vec<Option<&mut [T]>> {
    match column {
        Some(c) => c.chunks_mut(CHUNK).map(Some).collect(),
        None => (0..len.div_ceil(CHUNK)).map(|_| None).collect(),
    }
}

/// Points grouped into slabs of one cell row along the grid's slab axis (its slowest), so
/// that each slab scatters into its own contiguous range of node ids.
#[derive(Debug, Default)]
pub struct Slabs {
    /// `order[offsets[s]..offsets[s + 1]]` are the point indices in slab `s`, ascending.
    offsets: Vec<usize>,
    order: Vec<u32>,
    /// Lowest and highest cell index holding a point, per axis.
    cells: ([usize; 3], [usize; 3]),
    /// Per chunk of points and slab: a count, then a position in `order` (set-up scratch).
    counts: Vec<u32>,
}

/// Slots of a vector that parallel tasks write to, each task to its own slots.
struct SharedSlots(*mut u32);

// SAFETY: tasks write disjoint slots (see `Slabs::build`); nothing reads during the writes.
unsafe impl Sync for SharedSlots {}

impl SharedSlots {
    /// # Safety
    /// `i` is in bounds and no other task writes slot `i`.
    unsafe fn write(&self, i: usize, value: u32) {
        unsafe { *self.0.add(i) = value };
    }
}

impl Slabs {
    /// Groups the `n` points whose positions `position(p)` gives into one slab per cell row.
    ///
    /// A counting sort in parallel over fixed chunks of points: every chunk counts its points
    /// per slab, the counts give every (slab, chunk) pair its own range of `order`, and the
    /// chunks fill their ranges. Within a slab points stay in ascending order, whatever the
    /// number of threads. The slab of a point is worked out twice rather than stored.
    pub fn build<D: Dim>(&mut self, grid: &Grid<D>, n: usize, position: impl Fn(usize) -> D::Vec + Sync) {
        let axis = grid.slab_axis;
        let rows = grid.axes[axis].cells;
        let chunk = |c: usize| c * CHUNK..((c + 1) * CHUNK).min(n);
        self.counts.clear();
        self.counts.resize(n.div_ceil(CHUNK) * rows, 0);
        let bounds: Vec<([usize; 3], [usize; 3])> = self
            .counts
            .par_chunks_mut(rows)
            .enumerate()
            .map(|(c, count)| {
                let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
                for p in chunk(c) {
                    let cell = grid.clamped_cell(position(p));
                    for a in 0..D::N {
                        lo[a] = lo[a].min(cell[a]);
                        hi[a] = hi[a].max(cell[a]);
                    }
                    count[cell[axis]] += 1;
                }
                (lo, hi)
            })
            .collect();
        self.cells = bounds.iter().fold(([usize::MAX; 3], [0; 3]), |(lo, hi), b| {
            (
                std::array::from_fn(|a| lo[a].min(b.0[a])),
                std::array::from_fn(|a| hi[a].max(b.1[a])),
            )
        });
        // Counts become the first index in `order` of each (chunk, slab) pair.
        self.offsets.clear();
        self.offsets.resize(rows + 1, 0);
        let mut next = 0usize;
        for s in 0..rows {
            self.offsets[s] = next;
            for count in self.counts.chunks_mut(rows) {
                let k = count[s] as usize;
                count[s] = next as u32;
                next += k;
            }
        }
        self.offsets[rows] = next;
        self.order.clear();
        self.order.resize(n, 0);
        let order = SharedSlots(self.order.as_mut_ptr());
        self.counts
            .par_chunks_mut(rows)
            .enumerate()
            .for_each(|(c, first)| {
                for p in chunk(c) {
                    let s = grid.clamped_cell_along(position(p), axis);
                    // SAFETY: `first[s]` walks the range of `order` that belongs to this chunk's
                    // points in slab `s` alone, and stays below `n`.
                    unsafe { order.write(first[s] as usize, p as u32) };
                    first[s] += 1;
                }
            });
    }

    /// Number of slabs.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no slabs.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The nodes the points reach with a support of `support` nodes per axis.
    pub fn reach<D: Dim>(&self, grid: &Grid<D>, support: usize) -> NodeBox {
        if self.order.is_empty() {
            return NodeBox::default();
        }
        grid.reach(self.cells.0, self.cells.1, support)
    }

    /// Point indices of slab `s`.
    pub fn points(&self, s: usize) -> &[u32] {
        &self.order[self.offsets[s]..self.offsets[s + 1]]
    }

    /// The node ids slab `s` can touch with a support of `support` nodes per axis: node
    /// layers `s − 1 .. s + support` (a stencil starts at the point's cell layer or the one
    /// below, both shape functions clamp it inside the grid, and it spans `support` layers).
    pub fn node_range<D: Dim>(grid: &Grid<D>, s: usize, support: usize) -> Range<usize> {
        let last = (s + support).min(grid.nodes[grid.slab_axis]);
        grid.layer_node_ids(s.saturating_sub(1)..last)
    }
}

/// Node columns that slabs write to, each slab its own contiguous range of node ids.
///
/// Implemented for [`Disjoint`] views of node columns and for tuples of them.
pub trait NodeTarget: Sync {
    /// The part of the columns one slab writes to, borrowed for one kernel call.
    type Part<'p>;

    /// The columns' entries for node ids `nodes`, for a lifetime the caller picks.
    ///
    /// # Safety
    /// Parts alive at the same time must cover disjoint node ranges, and no part may outlive
    /// the borrow of the columns the target was made from.
    unsafe fn part<'p>(&self, nodes: Range<usize>) -> Self::Part<'p>;
}

/// A node column lent to slabs that write to disjoint node ranges at the same time.
pub struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _column: PhantomData<&'a mut [T]>,
}

impl<'a, T> Disjoint<'a, T> {
    /// Lends `column` for the duration of one scatter.
    pub fn new(column: &'a mut [T]) -> Self {
        Disjoint {
            ptr: column.as_mut_ptr(),
            len: column.len(),
            _column: PhantomData,
        }
    }
}

// SAFETY: a `Disjoint` is only read through `NodeTarget::part`, whose contract keeps
// concurrently used parts apart, so it behaves as `&mut [T]` split among threads.
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}
unsafe impl<T: Send> Send for Disjoint<'_, T> {}

impl<T: Send + 'static> NodeTarget for Disjoint<'_, T> {
    type Part<'p> = &'p mut [T];

    unsafe fn part<'p>(&self, nodes: Range<usize>) -> &'p mut [T] {
        assert!(nodes.start <= nodes.end && nodes.end <= self.len);
        // SAFETY: in bounds (checked above); disjoint from other live parts by contract.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(nodes.start), nodes.len()) }
    }
}

impl<A: NodeTarget, B: NodeTarget> NodeTarget for (A, B) {
    type Part<'p> = (A::Part<'p>, B::Part<'p>);

    unsafe fn part<'p>(&self, nodes: Range<usize>) -> Self::Part<'p> {
        // SAFETY: forwarded contract.
        unsafe { (self.0.part(nodes.clone()), self.1.part(nodes)) }
    }
}

impl<A: NodeTarget, B: NodeTarget, C: NodeTarget> NodeTarget for (A, B, C) {
    type Part<'p> = (A::Part<'p>, B::Part<'p>, C::Part<'p>);

    unsafe fn part<'p>(&self, nodes: Range<usize>) -> Self::Part<'p> {
        // SAFETY: forwarded contract.
        unsafe {
            (
                self.0.part(nodes.clone()),
                self.1.part(nodes.clone()),
                self.2.part(nodes),
            )
        }
    }
}

/// Nodes of the box a grid-pass task covers at least: whole node layers are grouped up to
/// this many, so a small box runs as one task and a big one splits into many.
pub const NODES_PER_TASK: usize = 8192;

/// Sets `column`'s entries for every node of box `b` to `value`, a group of node layers a
/// task.
pub fn fill_box<D: Dim, T: Copy + Send + Sync + 'static>(
    grid: &Grid<D>,
    b: NodeBox,
    column: &mut [T],
    value: T,
) {
    grid_pass(grid, b, &Disjoint::new(column), |b, part, first| {
        for r in b.rows(grid) {
            part[r.start - first..r.end - first].fill(value);
        }
    });
}

/// Runs `kernel(part_box, part, first_node)` over the node box `b` in parallel and returns
/// the results in node order.
///
/// The box is cut across the slab axis into groups of whole node layers, each a contiguous
/// range of node ids starting at `first_node`; `part` is that range of `target` and
/// `part_box` the nodes of `b` inside it. The cut depends on the grid and the box alone,
/// never on the number of threads, so reductions over the results give the same bits on
/// any thread count.
pub fn grid_pass<D: Dim, T: NodeTarget, R: Send>(
    grid: &Grid<D>,
    b: NodeBox,
    target: &T,
    kernel: impl for<'p> Fn(NodeBox, T::Part<'p>, usize) -> R + Sync,
) -> Vec<R> {
    if b.is_empty() {
        return Vec::new();
    }
    let axis = grid.slab_axis;
    // Sized by the box's nodes in a layer, not the grid's: a body in a big grid then makes
    // as many tasks as in a grid of its own size, not many small ones.
    let box_layer = b.len() / (b.hi[axis] - b.lo[axis]);
    let per_task = NODES_PER_TASK.div_ceil(box_layer);
    let groups: Vec<Range<usize>> = (b.lo[axis]..b.hi[axis])
        .step_by(per_task)
        .map(|a| a..(a + per_task).min(b.hi[axis]))
        .collect();
    groups
        .into_par_iter()
        .map(|layers| {
            let mut part_box = b;
            (part_box.lo[axis], part_box.hi[axis]) = (layers.start, layers.end);
            let ids = grid.layer_node_ids(layers);
            let first = ids.start;
            // SAFETY: groups cover disjoint layer ranges, hence disjoint node ranges, and the
            // kernel cannot keep its part past the call.
            let part = unsafe { target.part(ids) };
            kernel(part_box, part, first)
        })
        .collect()
}

/// Runs `node(i, k, part)` for every node `i` of the box `b`, in parallel over the groups of
/// [`grid_pass`]: `part` is the group's range of `target` and `k` the node's index in it.
/// For grid passes that work node by node and return nothing.
#[inline(always)]
pub fn for_each_box_node<D: Dim, T: NodeTarget>(
    grid: &Grid<D>,
    b: NodeBox,
    target: &T,
    node: impl for<'p> Fn(usize, usize, &mut T::Part<'p>) + Sync,
) {
    grid_pass(grid, b, target, |part_box, mut part, first| {
        for i in part_box.rows(grid).flatten() {
            node(i, i - first, &mut part);
        }
    });
}

impl NodeTarget for () {
    type Part<'p> = ();

    unsafe fn part<'p>(&self, _: Range<usize>) -> Self::Part<'p> {}
}

/// The slabs of every point archetype, shared by all the scatters of a step.
///
/// A grouping depends on the cell of each point alone. It is built by the first scatter
/// after a point changed cell and reused by the others until one changes cell again: MUSL's
/// remap scatters with the slabs particle-to-grid built, a step's particle-to-grid with
/// those of the last volumetric smoothing, and in a body near rest one step with the last
/// step's. Every system that moves a point into another cell, or adds, removes or reorders
/// points, must call [`SlabCache::invalidate`]: stale slabs
/// give a stale box of active nodes and another order of the sums, or fail the bounds
/// check of a slab's node range (never a data race).
#[derive(Debug, Default)]
pub struct SlabCache {
    entries: Vec<CachedSlabs>,
}

/// One archetype's slabs.
#[derive(Debug, Default)]
struct CachedSlabs {
    /// Address and length of the archetype's position column, which name the archetype
    /// between two invalidations.
    column: (usize, usize),
    /// False once points moved since the slabs were built.
    fresh: bool,
    slabs: Slabs,
}

impl SlabCache {
    /// Marks every archetype's slabs stale (their allocations are kept for the rebuild).
    pub fn invalidate(&mut self) {
        for e in &mut self.entries {
            e.fresh = false;
        }
    }

    /// The slabs of the points whose positions are `x`, built unless still fresh.
    pub fn slabs<D: Dim>(&mut self, grid: &Grid<D>, x: &[Position<D::Vec>]) -> &Slabs {
        let column = (x.as_ptr() as usize, x.len());
        let k = match self.entries.iter().position(|e| e.column == column) {
            Some(k) => k,
            None => {
                // A stale entry gives its allocation to the new archetype.
                let k = match self.entries.iter().position(|e| !e.fresh) {
                    Some(k) => k,
                    None => {
                        self.entries.push(CachedSlabs::default());
                        self.entries.len() - 1
                    }
                };
                // Stale or new, so built below.
                self.entries[k].column = column;
                k
            }
        };
        let e = &mut self.entries[k];
        if !e.fresh {
            e.slabs.build(grid, x.len(), |p| x[p].0);
            e.fresh = true;
        }
        &e.slabs
    }
}

/// Where each of `threads` contiguous runs of slabs with `sizes` points starts, so that the
/// runs hold about as many points each: run t starts at the first slab whose middle lies at
/// or beyond t/threads of all the points. The last entry is `sizes.len()`.
fn balanced_cuts(sizes: &[usize], threads: usize) -> Vec<usize> {
    let total: usize = sizes.iter().sum();
    let mut cuts = Vec::with_capacity(threads + 1);
    cuts.push(0);
    let mut before = 0;
    for (k, &n) in sizes.iter().enumerate() {
        while cuts.len() < threads && (2 * before + n) * threads >= 2 * cuts.len() * total {
            cuts.push(k);
        }
        before += n;
    }
    cuts.resize(threads + 1, sizes.len());
    cuts
}

/// Runs of slabs a scatter's phase is cut into, per thread of the pool.
pub const RUNS_PER_THREAD: usize = 4;

/// A deterministic parallel scatter from points to nodes, straight into the node columns:
/// runs `kernel(points, part, first_node)` for every non-empty slab of `slabs`, where `part`
/// is the slab's range of `target` starting at node id `first_node` and `points` are point
/// indices. Returns the box of nodes the points reach with `support` nodes per axis.
///
/// A slab touches `support + 1` node layers, so slabs `support + 1` apart never share a
/// node: the scatter runs in `support + 1` phases, and within a phase every slab writes to
/// its own node range in parallel. A node therefore receives its contributions slab by slab
/// in phase order, and within a slab in point order, whatever the number of threads. No
/// per-thread buffers, no reduction pass.
///
/// Which thread runs which slab changes no sum, so each phase is cut into
/// [`RUNS_PER_THREAD`] contiguous runs of slabs a thread, each holding about as many points
/// (`balanced_cuts`: slabs differ in size wherever a body is not a box, the 2D slope's from
/// 270 points to 891, which a split by slab count left unbalanced), and the runs are handed
/// out as threads come free. A thread that the operating system has taken off its core
/// (another process on a shared machine) then holds a phase up for the run it is in only:
/// given a fixed run each, every phase waited for every thread to be scheduled, and a
/// scatter of a small scene took 5.9 ms instead of 30 µs beside a compile
/// (docs/performance.md, "Scatters on a busy machine").
///
/// The kernel takes each part for the length of one call (it is generic over the part's
/// lifetime), so no part can outlive its phase and meet a part of the next one.
pub fn scatter<D: Dim, T: NodeTarget>(
    slabs: &Slabs,
    grid: &Grid<D>,
    support: usize,
    target: &T,
    kernel: impl for<'p> Fn(&[u32], T::Part<'p>, usize) + Sync,
) -> NodeBox {
    let phases = support + 1;
    for phase in 0..phases {
        let members: Vec<usize> = (phase..slabs.len())
            .step_by(phases)
            .filter(|&s| !slabs.points(s).is_empty())
            .collect();
        for pair in members.windows(2) {
            let (a, b) = (
                Slabs::node_range(grid, pair[0], support),
                Slabs::node_range(grid, pair[1], support),
            );
            assert!(a.end <= b.start, "slabs of one phase share nodes");
        }
        let run = |s: usize| {
            let nodes = Slabs::node_range(grid, s, support);
            let first = nodes.start;
            // SAFETY: the slabs of one phase cover disjoint node ranges (asserted above),
            // and the kernel cannot keep its part past the call, so none survives into
            // the next phase.
            let part = unsafe { target.part(nodes) };
            kernel(slabs.points(s), part, first);
        };
        let sizes: Vec<usize> = members.iter().map(|&s| slabs.points(s).len()).collect();
        let runs = RUNS_PER_THREAD * rayon::current_num_threads();
        let cuts = balanced_cuts(&sizes, runs);
        (0..runs)
            .into_par_iter()
            .with_max_len(1)
            .for_each(|k| members[cuts[k]..cuts[k + 1]].iter().for_each(|&s| run(s)));
    }
    slabs.reach(grid, support)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Dim3;
    use glam::DVec3;

    /// Runs `f` on a pool of `threads` threads.
    fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(f)
    }

    #[test]
    fn phases_split_into_runs_of_about_equal_points_that_cover_every_slab_once() {
        // The 2D slope's slab sizes shrink from base to crest.
        let sizes: Vec<usize> = (0..10).map(|k| 891 - 60 * k).collect();
        let total: usize = sizes.iter().sum();
        for threads in 1..=5 {
            let cuts = balanced_cuts(&sizes, threads);
            assert_eq!(cuts.len(), threads + 1);
            assert_eq!((cuts[0], cuts[threads]), (0, sizes.len()));
            assert!(cuts.windows(2).all(|w| w[0] <= w[1]), "{cuts:?}");
            // Each run is off its share by less than one slab.
            for t in 0..threads {
                let run: usize = sizes[cuts[t]..cuts[t + 1]].iter().sum();
                let share = total as f64 / threads as f64;
                assert!((run as f64 - share).abs() < 891.0, "{threads} threads: {cuts:?}");
            }
        }
        // A heavy slab first: a split by count would give its thread two more slabs.
        assert_eq!(balanced_cuts(&[900, 100, 100, 100, 100], 2), vec![0, 1, 5]);
        // No slab, or fewer slabs than threads: the spare threads get empty runs.
        assert_eq!(balanced_cuts(&[], 2), vec![0, 0, 0]);
        assert_eq!(balanced_cuts(&[5], 3), vec![0, 0, 1, 1]);
    }

    #[test]
    fn grid_pass_visits_every_box_node_once_and_sums_the_same_bits_on_any_thread_count() {
        // 41 layers of 41 × 41 nodes; the box below has 35 × 39 nodes in a layer, so groups
        // of 7 layers, and its 33 layers make 5 groups.
        let grid = Grid::<Dim3>::new(DVec3::ZERO, 1.0, [40, 40, 40]);
        let b = NodeBox {
            lo: [3, 1, 2],
            hi: [38, 40, 35],
        };
        let values: Vec<f64> = (0..grid.node_count())
            .map(|i| ((i as f64) * 0.618).sin() * 1e3 + 1e-7 * i as f64)
            .collect();
        let pass = |threads| {
            on_threads(threads, || {
                let mut visits = vec![0u32; grid.node_count()];
                let sums = grid_pass(&grid, b, &Disjoint::new(&mut visits), |part_box, part, first| {
                    let mut sum = 0.0;
                    for i in part_box.rows(&grid).flatten() {
                        part[i - first] += 1;
                        sum += values[i];
                    }
                    sum
                });
                (sums.len(), sums.iter().sum::<f64>().to_bits(), visits)
            })
        };
        let (groups, one, visits) = pass(1);
        assert_eq!(groups, 5);
        let inside = |i: usize| {
            let ijk = grid.node_ijk(i);
            (0..3).all(|a| b.lo[a] <= ijk[a] && ijk[a] < b.hi[a])
        };
        for (i, &v) in visits.iter().enumerate() {
            assert_eq!(v, u32::from(inside(i)), "node {i} visited {v} times");
        }
        for _ in 0..3 {
            let (_, two, _) = pass(2);
            assert_eq!(one, two, "the sum depends on the thread count");
        }
    }
}
