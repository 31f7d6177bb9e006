//! Domain decomposition along the grid's slab axis (its slowest), for runs over MPI ranks.
//!
//! Each rank owns a contiguous range of cell layers and the points in them, and the node
//! layers from its first cell layer up to (not including) the next rank's; the last rank
//! also owns the top node layer. A point in cell layer c reaches node layers c − 1 to
//! c + SUPPORT − 1 (quadratic B-splines and GIMP start one layer below their cell, linear
//! shapes at it), so two ranks meeting at layer L both reach node layers L − 1 to
//! L + SUPPORT − 1: that band is what they exchange. A rank that holds cells is at least
//! SUPPORT + 1 layers wide, so that only neighbours share nodes; a rank may hold none (a
//! one-layer bar on four ranks), and is then skipped by its neighbours.

use std::ops::Range;

/// The cell layers of every rank along the slab axis, and which rank this one is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decomposition {
    /// Rank r owns cell layers `bounds[r]..bounds[r + 1]`; `bounds[0]` is 0 and the last
    /// entry the grid's cell count along the slab axis.
    pub bounds: Vec<usize>,
    /// This rank.
    pub rank: usize,
    /// Nodes per axis in a point's support (the shape functions').
    pub support: usize,
}

impl Decomposition {
    /// One rank owning every one of `layers` cell layers.
    pub fn whole(layers: usize, support: usize) -> Decomposition {
        Decomposition {
            bounds: vec![0, layers],
            rank: 0,
            support,
        }
    }

    /// Splits cell layers holding `counts[c]` points each into `ranks` contiguous ranges of
    /// nearly equal point count, each holding cells at least `support + 1` layers wide; a
    /// grid too thin for the ranks leaves the last ones empty. The split depends only on the
    /// counts, so every rank finds the same one.
    pub fn balanced(counts: &[u64], ranks: usize, rank: usize, support: usize) -> Decomposition {
        let layers = counts.len();
        let min_width = support + 1;
        let total: u64 = counts.iter().sum();
        // Ranks that can hold cells: at most one per `min_width` layers.
        let busy = ranks.min(layers / min_width).max(1);
        if ranks > 1 && layers < min_width && total > 0 {
            // Everything on rank 0; the others hold nothing.
            let mut bounds = vec![0, layers];
            bounds.extend(std::iter::repeat_n(layers, ranks - 1));
            return Decomposition {
                bounds,
                rank,
                support,
            };
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
        // Ranks beyond the busy ones hold nothing (at the top).
        bounds.extend(std::iter::repeat_n(layers, ranks - busy));
        Decomposition {
            bounds,
            rank,
            support,
        }
    }

    /// The number of ranks.
    pub fn ranks(&self) -> usize {
        self.bounds.len() - 1
    }

    /// This rank's cell layers.
    pub fn cells(&self) -> Range<usize> {
        self.bounds[self.rank]..self.bounds[self.rank + 1]
    }

    /// True when this rank holds no cell layer.
    pub fn is_empty(&self) -> bool {
        self.cells().is_empty()
    }

    /// The rank owning cell layer `c` (clamped to the grid).
    pub fn owner_of_cell(&self, c: usize) -> usize {
        let last = *self.bounds.last().expect("bounds are never empty");
        let c = c.min(last.saturating_sub(1));
        // The last rank whose range starts at or below c and is not empty.
        (0..self.ranks())
            .rev()
            .find(|&r| self.bounds[r] <= c && self.bounds[r] < self.bounds[r + 1])
            .unwrap_or(0)
    }

    /// The node layers this rank owns (of `node_layers`, one more than the cell layers):
    /// each node layer is owned by exactly one rank, so sums over owned nodes add up.
    pub fn owned_nodes(&self) -> Range<usize> {
        let r = self.cells();
        if r.is_empty() {
            return r;
        }
        let top = *self.bounds.last().expect("bounds are never empty");
        let end = if r.end == top { top + 1 } else { r.end };
        r.start..end
    }

    /// The nearest ranks below and above that hold cells, if any.
    pub fn neighbours(&self) -> (Option<usize>, Option<usize>) {
        if self.is_empty() {
            return (None, None);
        }
        let busy = |r: &usize| self.bounds[*r] < self.bounds[*r + 1];
        let below = (0..self.rank).rev().find(busy);
        let above = (self.rank + 1..self.ranks()).find(busy);
        (below, above)
    }

    /// The node layers this rank shares with a neighbour whose range meets its own at cell
    /// layer `at`, for shapes reaching `support` nodes: `at − 1 .. at + support`.
    pub fn band(at: usize, support: usize) -> Range<usize> {
        at.saturating_sub(1)..at + support
    }

    /// The bands this rank shares with its neighbours below and above, as (neighbour, node
    /// layers), clipped to the grid's node layers.
    pub fn bands(&self) -> [Option<(usize, Range<usize>)>; 2] {
        let (below, above) = self.neighbours();
        let top = *self.bounds.last().expect("bounds are never empty") + 1;
        let clip = |r: Range<usize>| r.start..r.end.min(top);
        let cells = self.cells();
        [
            below.map(|b| (b, clip(Self::band(cells.start, self.support)))),
            above.map(|a| (a, clip(Self::band(cells.end, self.support)))),
        ]
    }

    /// The node layers whose whole sums this rank holds once the shared bands are summed:
    /// the layers it owns and the bands it shares with its neighbours (empty when it holds
    /// no cells).
    pub fn held_nodes(&self) -> Range<usize> {
        let owned = self.owned_nodes();
        if owned.is_empty() {
            return owned;
        }
        self.bands()
            .into_iter()
            .flatten()
            .fold(owned, |r, (_, b)| r.start.min(b.start)..r.end.max(b.end))
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
            .map(|r| Decomposition::balanced(counts, ranks, r, support))
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
        assert_eq!(all[0].neighbours(), (None, None));
        assert_eq!(all[0].owned_nodes(), 0..2);
        // Seven layers, linear shapes (support 2, width ≥ 3): two busy ranks of four.
        let seven = ranks_of(&[5; 7], 4, 2);
        assert_eq!(seven[0].bounds, vec![0, 4, 7, 7, 7]);
        assert_eq!(seven[1].neighbours(), (Some(0), None));
    }

    #[test]
    fn each_node_layer_has_one_owner_and_each_cell_one_rank() {
        let all = ranks_of(&[7; 30], 3, 3);
        assert_eq!(all[1].bands(), [Some((0, 9..13)), Some((2, 19..23))]);
        let mut owners = vec![0; 31];
        for d in &all {
            for k in d.owned_nodes() {
                owners[k] += 1;
            }
            for c in d.cells() {
                assert_eq!(d.owner_of_cell(c), d.rank);
            }
        }
        assert!(owners.iter().all(|&n| n == 1), "{owners:?}");
        assert_eq!(Decomposition::band(10, 3), 9..13);
    }

    #[test]
    fn imbalance_is_the_largest_share_over_the_mean() {
        assert_eq!(Decomposition::imbalance(&[10, 10]), 1.0);
        assert_eq!(Decomposition::imbalance(&[15, 5]), 1.5);
        assert_eq!(Decomposition::imbalance(&[0, 0]), 1.0);
    }
}
