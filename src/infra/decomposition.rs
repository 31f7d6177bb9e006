//! Domain decomposition of the grid's cells over MPI ranks: slabs along the grid's slab axis
//! (its slowest), each cut again along a second axis when asked or when the slabs alone
//! cannot hold the ranks.
//!
//! The ranks form a grid of `slabs × across` parts, rank r at (r / across, r % across). Along
//! each of the two split axes a part holds a contiguous range of cell layers and the node
//! layers from its first cell layer up to (not including) the next part's; the last part
//! also holds the top node layer. A point in cell layer c reaches node layers c − 1 to
//! c + SUPPORT − 1 along each axis (quadratic B-splines and GIMP start one layer below their
//! cell, linear shapes at it), so two parts meeting at layer L both reach node layers L − 1
//! to L + SUPPORT − 1: that band is what they exchange. Parts that hold cells are at least
//! SUPPORT + 1 layers wide along each split axis, so only neighbours share nodes (four at a
//! corner of a two-axis split); a part may hold none (a one-layer bar on four ranks), and is
//! then skipped by its neighbours.
//!
//! The second split axis is the grid's middle axis in 3D and x in 2D ([`Grid::across_axis`]).
//!
//! [`Grid::across_axis`]: crate::grid::Grid::across_axis

use std::ops::Range;

/// The two axes a decomposition cuts: the grid's slab axis, then the second split axis.
pub const SLAB: usize = 0;
/// See [`SLAB`].
pub const ACROSS: usize = 1;

/// The cell layers of every rank along the two split axes, and which rank this one is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decomposition {
    /// Slab i holds cell layers `bounds[i]..bounds[i + 1]` along the slab axis; `bounds[0]`
    /// is 0 and the last entry the grid's cell count along that axis.
    pub bounds: Vec<usize>,
    /// Part j of a slab holds cell layers `across[j]..across[j + 1]` along the second split
    /// axis (`[0, cells]` when the ranks are slabs only).
    pub across: Vec<usize>,
    /// This rank.
    pub rank: usize,
    /// Nodes per axis in a point's support (the shape functions').
    pub support: usize,
}

/// How many parts the ranks make along each split axis: `[slabs, across]`.
pub type Split = [usize; 2];

impl Decomposition {
    /// One rank owning every cell: `layers` along the slab axis and `across` along the
    /// second split axis.
    pub fn whole(layers: usize, across: usize, support: usize) -> Decomposition {
        Decomposition {
            bounds: vec![0, layers],
            across: vec![0, across],
            rank: 0,
            support,
        }
    }

    /// The parts along each axis for `ranks` ranks over `layers` cell layers along the slab
    /// axis and `across` along the second: the one asked for, else the layout that keeps the
    /// most ranks holding cells (a part must be `support + 1` layers wide), with the fewest
    /// cuts across among those: slabs alone while they hold the ranks.
    pub fn split_for(
        ranks: usize,
        layers: usize,
        across: usize,
        support: usize,
        asked: Option<Split>,
    ) -> Split {
        if let Some(s) = asked {
            return s;
        }
        let busy = |parts: usize, cells: usize| parts.min(cells / (support + 1)).max(1);
        let cuts = (1..=ranks.max(1)).filter(|a| ranks.max(1).is_multiple_of(*a));
        let a = cuts
            .max_by_key(|&a| (busy(ranks / a, layers) * busy(a, across), std::cmp::Reverse(a)))
            .unwrap_or(1);
        [ranks.max(1) / a, a]
    }

    /// Splits cells holding `counts[SLAB][c]` points in slab-axis layer c and
    /// `counts[ACROSS][c]` in layer c of the second axis into `split[SLAB] × split[ACROSS]`
    /// parts of nearly equal point count along each axis ([`Decomposition::cuts`]). The split
    /// depends only on the counts, so every rank finds the same one.
    pub fn balanced(counts: [&[u64]; 2], split: Split, rank: usize, support: usize) -> Decomposition {
        Decomposition {
            bounds: Self::cuts(counts[SLAB], split[SLAB], support),
            across: Self::cuts(counts[ACROSS], split[ACROSS], support),
            rank,
            support,
        }
    }

    /// Cuts layers holding `counts[c]` points each into `parts` contiguous ranges of nearly
    /// equal point count, each holding cells at least `support + 1` layers wide; a grid too
    /// thin for the parts leaves the last ones empty. Gives the `parts + 1` bounds.
    pub fn cuts(counts: &[u64], parts: usize, support: usize) -> Vec<usize> {
        let layers = counts.len();
        let min_width = support + 1;
        let total: u64 = counts.iter().sum();
        // Parts that can hold cells: at most one per `min_width` layers.
        let busy = parts.min(layers / min_width).max(1);
        if parts > 1 && layers < min_width && total > 0 {
            // Everything in part 0; the others hold nothing.
            let mut bounds = vec![0, layers];
            bounds.extend(std::iter::repeat_n(layers, parts - 1));
            return bounds;
        }
        let mut bounds = vec![0];
        let mut prefix = 0u64;
        let mut next = 0usize;
        for r in 1..busy {
            // The first layer at which the points below reach r/busy of the total, kept
            // far enough from the last bound and from the top.
            let target = total as u128 * r as u128 / busy as u128;
            let lo = bounds[r - 1] + min_width;
            let hi = layers - (busy - r) * min_width;
            while next < layers && (prefix as u128) < target {
                prefix += counts[next];
                next += 1;
            }
            bounds.push(next.clamp(lo, hi));
        }
        bounds.push(layers);
        // Parts beyond the busy ones hold nothing (at the top).
        bounds.extend(std::iter::repeat_n(layers, parts - busy));
        bounds
    }

    /// The bounds along split axis `axis` ([`SLAB`] or [`ACROSS`]).
    fn cuts_of(&self, axis: usize) -> &[usize] {
        if axis == SLAB {
            &self.bounds
        } else {
            &self.across
        }
    }

    /// The parts along each split axis.
    pub fn split(&self) -> Split {
        [self.bounds.len() - 1, self.across.len() - 1]
    }

    /// The number of ranks.
    pub fn ranks(&self) -> usize {
        let [s, a] = self.split();
        s * a
    }

    /// Rank r's part along each split axis.
    pub fn part_of(&self, r: usize) -> [usize; 2] {
        let across = self.split()[ACROSS];
        [r / across, r % across]
    }

    /// The rank of the part at `part` along each split axis.
    pub fn rank_at(&self, part: [usize; 2]) -> usize {
        part[SLAB] * self.split()[ACROSS] + part[ACROSS]
    }

    /// This rank's cell layers along split axis `axis`.
    pub fn cells_along(&self, axis: usize) -> Range<usize> {
        let (b, k) = (self.cuts_of(axis), self.part_of(self.rank)[axis]);
        b[k]..b[k + 1]
    }

    /// True when this rank holds cell `c` (its layers along the two split axes).
    pub fn holds(&self, c: [usize; 2]) -> bool {
        self.cells_along(SLAB).contains(&c[SLAB]) && self.cells_along(ACROSS).contains(&c[ACROSS])
    }

    /// True when this rank holds no cell.
    pub fn is_empty(&self) -> bool {
        self.cells_along(SLAB).is_empty() || self.cells_along(ACROSS).is_empty()
    }

    /// The rank owning the cell at layers `c` along the two split axes (clamped to the
    /// grid).
    pub fn owner_of_cell(&self, c: [usize; 2]) -> usize {
        let part = [SLAB, ACROSS].map(|axis| {
            let b = self.cuts_of(axis);
            let last = *b.last().expect("bounds are never empty");
            let c = c[axis].min(last.saturating_sub(1));
            // The last part whose range starts at or below c and is not empty.
            (0..b.len() - 1)
                .rev()
                .find(|&k| b[k] <= c && b[k] < b[k + 1])
                .unwrap_or(0)
        });
        self.rank_at(part)
    }

    /// The node layers along split axis `axis` this rank owns (of one more than the cell
    /// layers): each node is owned by exactly one rank, so sums over owned nodes add up.
    pub fn owned_nodes(&self, axis: usize) -> Range<usize> {
        if self.is_empty() {
            return 0..0;
        }
        let r = self.cells_along(axis);
        let top = *self.cuts_of(axis).last().expect("bounds are never empty");
        let end = if r.end == top { top + 1 } else { r.end };
        r.start..end
    }

    /// The nearest ranks below and above along split axis `axis` that hold cells, if any.
    pub fn neighbours(&self, axis: usize) -> (Option<usize>, Option<usize>) {
        if self.is_empty() {
            return (None, None);
        }
        let (b, me) = (self.cuts_of(axis), self.part_of(self.rank)[axis]);
        let busy = |k: &usize| b[*k] < b[*k + 1];
        let below = (0..me).rev().find(busy).map(|k| self.rank_along(axis, k));
        let above = (me + 1..b.len() - 1).find(busy).map(|k| self.rank_along(axis, k));
        (below, above)
    }

    /// The rank of the part at index `k` along split axis `axis` in this rank's row along
    /// it (the same part as this rank's along the other axis).
    pub fn rank_along(&self, axis: usize, k: usize) -> usize {
        let mut p = self.part_of(self.rank);
        p[axis] = k;
        self.rank_at(p)
    }

    /// The node layers this rank shares with a neighbour whose range meets its own at cell
    /// layer `at`, for shapes reaching `support` nodes: `at − 1 .. at + support`.
    pub fn band(at: usize, support: usize) -> Range<usize> {
        at.saturating_sub(1)..at + support
    }

    /// The bands this rank shares with its neighbours below and above along split axis
    /// `axis`, as (neighbour, node layers along that axis), clipped to the grid's node
    /// layers.
    pub fn bands(&self, axis: usize) -> [Option<(usize, Range<usize>)>; 2] {
        let (below, above) = self.neighbours(axis);
        let top = *self.cuts_of(axis).last().expect("bounds are never empty") + 1;
        let clip = |r: Range<usize>| r.start..r.end.min(top);
        let cells = self.cells_along(axis);
        [
            below.map(|b| (b, clip(Self::band(cells.start, self.support)))),
            above.map(|a| (a, clip(Self::band(cells.end, self.support)))),
        ]
    }

    /// The node layers along split axis `axis` whose whole sums this rank holds once the
    /// shared bands are summed: the layers it owns and the bands it shares with its
    /// neighbours (empty when it holds no cells).
    pub fn held_nodes(&self, axis: usize) -> Range<usize> {
        let owned = self.owned_nodes(axis);
        if owned.is_empty() {
            return owned;
        }
        self.bands(axis)
            .into_iter()
            .flatten()
            .fold(owned, |r, (_, b)| r.start.min(b.start)..r.end.max(b.end))
    }

    /// The points of each rank when `counts[i][j]` points lie in slab i's layers and part j's
    /// layers across (a histogram over cells `[slab layer][across layer]`, row-major).
    pub fn points_per_rank(&self, counts: &[u64], across_layers: usize) -> Vec<u64> {
        let mut per = vec![0u64; self.ranks()];
        for (c, &n) in counts.iter().enumerate() {
            if n > 0 {
                per[self.owner_of_cell([c / across_layers, c % across_layers])] += n;
            }
        }
        per
    }

    /// Largest point count of a rank over the mean (1 is perfect balance).
    pub fn imbalance(points_per_rank: &[u64]) -> f64 {
        let total: u64 = points_per_rank.iter().sum();
        let largest = points_per_rank.iter().copied().max().unwrap_or(0);
        if total == 0 {
            return 1.0;
        }
        largest as f64 * points_per_rank.len() as f64 / total as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ranks_of(counts: &[u64], ranks: usize, support: usize) -> Vec<Decomposition> {
        (0..ranks)
            .map(|r| Decomposition::balanced([counts, &[1]], [ranks, 1], r, support))
            .collect()
    }

    #[test]
    fn a_uniform_body_splits_into_equal_ranges() {
        let d = &ranks_of(&[10; 40], 4, 3)[0];
        assert_eq!(d.bounds, vec![0, 10, 20, 30, 40]);
    }

    #[test]
    fn the_split_follows_the_points_not_the_layers() {
        // A slope: many points low down, few high up.
        let counts: Vec<u64> = (0..40).map(|c| 400 - 10 * c).collect();
        let d = &ranks_of(&counts, 2, 3)[0];
        let below: u64 = counts[..d.bounds[1]].iter().sum();
        let total: u64 = counts.iter().sum();
        assert!((below as f64 / total as f64 - 0.5).abs() < 0.02, "{:?}", d.bounds);
    }

    #[test]
    fn every_busy_rank_is_wide_enough_that_only_neighbours_share_nodes() {
        // All the points in two layers: the ranks still get support + 1 layers each.
        let mut counts = vec![0u64; 20];
        counts[9] = 1000;
        counts[10] = 1000;
        for d in ranks_of(&counts, 4, 3) {
            for r in 0..d.ranks() {
                let w = d.bounds[r + 1] - d.bounds[r];
                assert!(w == 0 || w >= 4, "{:?}", d.bounds);
            }
            assert_eq!(*d.bounds.last().unwrap(), 20);
        }
    }

    #[test]
    fn a_grid_too_thin_for_the_ranks_leaves_the_extra_ones_empty() {
        // The bar: one cell layer along the slab axis, four ranks.
        let all = ranks_of(&[24], 4, 2);
        assert_eq!(all[0].bounds, vec![0, 1, 1, 1, 1]);
        assert!(!all[0].is_empty() && all[1..].iter().all(Decomposition::is_empty));
        assert_eq!(all[0].neighbours(SLAB), (None, None));
        assert_eq!(all[0].owned_nodes(SLAB), 0..2);
        // Seven layers, linear shapes (support 2, width ≥ 3): two busy ranks of four.
        let seven = ranks_of(&[5; 7], 4, 2);
        assert_eq!(seven[0].bounds, vec![0, 4, 7, 7, 7]);
        assert_eq!(seven[1].neighbours(SLAB), (Some(0), None));
    }

    #[test]
    fn each_node_layer_has_one_owner_and_each_cell_one_rank() {
        let all = ranks_of(&[7; 30], 3, 3);
        assert_eq!(all[1].bands(SLAB), [Some((0, 9..13)), Some((2, 19..23))]);
        let mut owners = vec![0; 31];
        for d in &all {
            for k in d.owned_nodes(SLAB) {
                owners[k] += 1;
            }
            for c in d.cells_along(SLAB) {
                assert_eq!(d.owner_of_cell([c, 0]), d.rank);
            }
        }
        assert!(owners.iter().all(|&n| n == 1), "{owners:?}");
        assert_eq!(Decomposition::band(10, 3), 9..13);
    }

    /// Four ranks as 2 × 2 over 20 × 12 cells: rank r at (r / 2, r % 2), each node owned
    /// once, each cell on one rank, and the neighbours along each axis the ones beside.
    #[test]
    fn a_two_axis_split_owns_each_node_once_and_finds_its_neighbours_along_both_axes() {
        let (slab, across) = (vec![5u64; 20], vec![5u64; 12]);
        let all: Vec<_> = (0..4)
            .map(|r| Decomposition::balanced([&slab, &across], [2, 2], r, 3))
            .collect();
        assert_eq!(
            (all[0].bounds.clone(), all[0].across.clone()),
            (vec![0, 10, 20], vec![0, 6, 12])
        );
        assert_eq!(all[3].part_of(3), [1, 1]);
        assert_eq!(all[0].neighbours(SLAB), (None, Some(2)));
        assert_eq!(all[0].neighbours(ACROSS), (None, Some(1)));
        assert_eq!(all[3].neighbours(SLAB), (Some(1), None));
        assert_eq!(all[3].neighbours(ACROSS), (Some(2), None));
        assert_eq!(all[1].bands(ACROSS), [Some((0, 5..9)), None]);
        assert_eq!(all[1].held_nodes(ACROSS), 5..13);
        let mut owners = vec![[0; 13]; 21];
        for d in &all {
            for i in d.owned_nodes(SLAB) {
                for j in d.owned_nodes(ACROSS) {
                    owners[i][j] += 1;
                }
            }
            for i in 0..20 {
                for j in 0..12 {
                    assert_eq!(d.owner_of_cell([i, j]) == d.rank, d.holds([i, j]));
                }
            }
        }
        assert!(owners.iter().flatten().all(|&n| n == 1), "{owners:?}");
        let counts: Vec<u64> = vec![1; 20 * 12];
        assert_eq!(all[0].points_per_rank(&counts, 12), vec![60; 4]);
    }

    #[test]
    fn the_split_keeps_the_most_ranks_busy_with_the_fewest_cuts_across() {
        // 50 layers of B-splines hold 12 slabs of 4 layers.
        assert_eq!(Decomposition::split_for(4, 50, 50, 3, None), [4, 1]);
        assert_eq!(Decomposition::split_for(12, 50, 50, 3, None), [12, 1]);
        assert_eq!(Decomposition::split_for(16, 50, 50, 3, None), [8, 2]);
        assert_eq!(Decomposition::split_for(4, 50, 50, 3, Some([2, 2])), [2, 2]);
        // A 500 × 50-layer slope on 1 024 ranks: 128 × 8, of which 125 × 8 hold cells.
        assert_eq!(Decomposition::split_for(1024, 500, 50, 3, None), [128, 8]);
        // The one-layer bar (24 cells along x, linear shapes) is cut along x only.
        assert_eq!(Decomposition::split_for(4, 1, 24, 2, None), [1, 4]);
        // Nothing helps a grid of one cell: slabs, the extra ranks empty.
        assert_eq!(Decomposition::split_for(4, 1, 1, 2, None), [4, 1]);
    }

    #[test]
    fn imbalance_is_the_largest_share_over_the_mean() {
        assert_eq!(Decomposition::imbalance(&[10, 10]), 1.0);
        assert_eq!(Decomposition::imbalance(&[15, 5]), 1.5);
        assert_eq!(Decomposition::imbalance(&[0, 0]), 1.0);
    }
}
