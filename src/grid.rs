//! The structured background grid: geometry and node numbering.
//!
//! Nodes sit at `origin + h·(i, j, k)` for `i ≤ cells[0]` and so on. x runs fastest (stride
//! 1, the inner loop of every stencil); of y and z, the axis with more cells runs slowest: it
//! is the axis that parallel scatters cut into slabs, each slab a contiguous range of node
//! ids (see `parallel`), so a long thin 3D slab between rollers still splits into many.
//! In 2D the third count is zero, so a 2D grid has one layer of nodes.
//!
//! A grid numbers (and a world stores) the nodes of its *window*, a box of them: the whole
//! grid on one rank, the nodes a rank holds in a run over MPI ranks (its own layers and the
//! bands it shares, [`crate::infra::decomposition`]), so that a rank's node columns shrink
//! with its part. Node `(i, j, k)` of the window has id `(i − lo_0)·stride[0] + (j −
//! lo_1)·stride[1] + (k − lo_2)·stride[2]`, the strides those of the window. Cells, faces and
//! positions stay the whole grid's: a window only renumbers.

use crate::dim::{Dim, Vector};

/// A face of the grid's bounding box.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Face {
    /// x = x_min.
    XMin,
    /// x = x_max.
    XMax,
    /// y = y_min.
    YMin,
    /// y = y_max.
    YMax,
    /// z = z_min (3D only).
    ZMin,
    /// z = z_max (3D only).
    ZMax,
}

impl Face {
    /// The axis normal to the face and whether it is the upper end.
    pub fn axis_side(self) -> (usize, bool) {
        match self {
            Face::XMin => (0, false),
            Face::XMax => (0, true),
            Face::YMin => (1, false),
            Face::YMax => (1, true),
            Face::ZMin => (2, false),
            Face::ZMax => (2, true),
        }
    }
}

/// A box of nodes, `lo[a] ≤ ijk[a] < hi[a]` on every axis: the nodes the points reach.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NodeBox {
    /// First node index on each axis.
    pub lo: [usize; 3],
    /// One past the last node index on each axis (`lo == hi`: empty).
    pub hi: [usize; 3],
}

impl NodeBox {
    /// True when the box holds no node.
    pub fn is_empty(&self) -> bool {
        (0..3).any(|a| self.hi[a] <= self.lo[a])
    }

    /// The smallest box holding both.
    pub fn union(self, other: NodeBox) -> NodeBox {
        if self.is_empty() {
            return other;
        }
        if other.is_empty() {
            return self;
        }
        let mut b = self;
        for a in 0..3 {
            b.lo[a] = b.lo[a].min(other.lo[a]);
            b.hi[a] = b.hi[a].max(other.hi[a]);
        }
        b
    }

    /// Number of nodes in the box.
    pub fn len(&self) -> usize {
        (0..3).map(|a| self.hi[a].saturating_sub(self.lo[a])).product()
    }

    /// The box's nodes as runs of consecutive node ids (one run per row along x), in
    /// ascending id order.
    pub fn rows<D: Dim>(self, grid: &Grid<D>) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
        let (lo, hi) = (self.lo, self.hi);
        let (s, m) = (grid.slab_axis, 3 - grid.slab_axis);
        let width = if self.is_empty() { 0 } else { hi[0] - lo[0] };
        let (outer, inner) = if width == 0 {
            (0..0, 0..0)
        } else {
            (lo[s]..hi[s], lo[m]..hi[m])
        };
        outer.flat_map(move |a| {
            inner.clone().map(move |b| {
                let mut ijk = [lo[0]; 3];
                (ijk[s], ijk[m]) = (a, b);
                let first = grid.node_id(ijk);
                first..first + width
            })
        })
    }
}

/// The nodes of a rank in a run over MPI ranks (those it owns, or those it holds whole):
/// node layers along the slab axis and along the second split axis, every node along the
/// third ([`crate::infra::decomposition`]).
#[derive(Clone, Debug)]
pub struct RankNodes {
    /// The node ids of the slab-axis layers (ids run layer by layer).
    ids: std::ops::Range<usize>,
    /// The layers along the second split axis, with its stride and node count; `None` when
    /// they are all of them.
    across: Option<(std::ops::Range<usize>, usize, usize)>,
}

impl RankNodes {
    /// True when node `id` is one of them.
    #[inline]
    pub fn contains(&self, id: &usize) -> bool {
        self.ids.contains(id)
            && self
                .across
                .as_ref()
                .is_none_or(|(r, stride, n)| r.contains(&((id / stride) % n)))
    }
}

/// Geometry of a uniform background grid of square (cubic) cells.
#[derive(Clone, Debug)]
pub struct Grid<D: Dim> {
    /// Position of node (0, 0, 0) (m).
    pub origin: D::Vec,
    /// Cell edge length h (m).
    pub cell_size: f64,
    /// 1 / h (1/m). Each [`Axis`] holds it too, for the shape functions' slopes; this copy is
    /// what [`Grid::grid_coordinate`] scales by, since reading `axes[0]`'s there instead
    /// lengthened the transfer kernels' code (docs/performance.md).
    pub inv_h: f64,
    /// Each axis as cell indices and shape functions use it: its cells and 1/h (unused
    /// axes: no cells).
    pub axes: [Axis; 3],
    /// Nodes along each axis (`cells + 1`; unused axes: 1).
    pub nodes: [usize; 3],
    /// Node-id step along each axis.
    pub strides: [usize; 3],
    /// The axis with the largest stride (y in 2D; y or z in 3D).
    pub slab_axis: usize,
    /// The nodes this grid numbers (see the module's notes): all of them unless
    /// [`Grid::windowed`].
    window: NodeBox,
    /// `Σ window.lo[a]·strides[a]`: subtracted from a node's `Σ ijk[a]·strides[a]` to give
    /// its id (0 for the whole grid).
    offset: usize,
}

impl<D: Dim> Grid<D> {
    /// A grid with `cells` cells of size `cell_size` starting at `origin`.
    pub fn new(origin: D::Vec, cell_size: f64, cells: [usize; 3]) -> Self {
        let mut c = [0usize; 3];
        c[..D::N].copy_from_slice(&cells[..D::N]);
        let nodes = [c[0] + 1, c[1] + 1, c[2] + 1];
        let slab_axis = if D::N == 3 && c[2] >= c[1] { 2 } else { 1 };
        let window = NodeBox {
            lo: [0; 3],
            hi: nodes,
        };
        Grid {
            origin,
            cell_size,
            inv_h: 1.0 / cell_size,
            axes: c.map(|n| Axis::new(n, 1.0 / cell_size)),
            nodes,
            strides: window_strides(window, slab_axis),
            slab_axis,
            window,
            offset: 0,
        }
    }

    /// The same grid numbering only the nodes of `window` (clipped to the grid; a box
    /// holding no node numbers the first node alone, so that a rank without cells still
    /// has a node column).
    pub fn windowed(&self, window: NodeBox) -> Self {
        let mut w = window;
        for a in 0..3 {
            w.hi[a] = w.hi[a].min(self.nodes[a]);
            w.lo[a] = w.lo[a].min(w.hi[a]);
        }
        if w.is_empty() {
            w = NodeBox {
                lo: [0; 3],
                hi: [1; 3],
            };
        }
        let strides = window_strides(w, self.slab_axis);
        Grid {
            strides,
            window: w,
            offset: (0..3).map(|a| w.lo[a] * strides[a]).sum(),
            ..self.clone()
        }
    }

    /// The same grid numbering every node (ids then name nodes alike on every rank).
    pub fn whole(&self) -> Self {
        self.windowed(self.all_nodes())
    }

    /// Every node of the grid, whatever the window.
    pub fn all_nodes(&self) -> NodeBox {
        NodeBox {
            lo: [0; 3],
            hi: self.nodes,
        }
    }

    /// The nodes this grid numbers.
    pub fn window(&self) -> NodeBox {
        self.window
    }

    /// True when the grid numbers every node.
    pub fn is_whole(&self) -> bool {
        self.window == self.all_nodes()
    }

    /// True when node (i, j, k) is in the window.
    pub fn numbers(&self, ijk: [usize; 3]) -> bool {
        (0..3).all(|a| (self.window.lo[a]..self.window.hi[a]).contains(&ijk[a]))
    }

    /// The id of node (i, j, k), `None` outside the window.
    pub fn checked_node_id(&self, ijk: [usize; 3]) -> Option<usize> {
        self.numbers(ijk).then(|| self.node_id(ijk))
    }

    /// Cells along each axis (unused axes: 0).
    #[inline(always)]
    pub fn cells(&self) -> [usize; 3] {
        self.axes.map(|a| a.cells)
    }

    /// Number of nodes the grid numbers (its window's; every node unless windowed).
    pub fn node_count(&self) -> usize {
        self.window.len()
    }

    /// Id of node (i, j, k), which must be in the window.
    #[inline(always)]
    pub fn node_id(&self, ijk: [usize; 3]) -> usize {
        debug_assert!(
            self.numbers(ijk),
            "node {ijk:?} outside the window {:?}",
            self.window
        );
        (ijk[0] * self.strides[0] + ijk[1] * self.strides[1] + ijk[2] * self.strides[2])
            .wrapping_sub(self.offset)
    }

    /// What [`Grid::node_id`] subtracts from `Σ ijk[a]·strides[a]` (0 for the whole grid):
    /// the stencils take it off once a point.
    #[inline(always)]
    pub fn id_offset(&self) -> usize {
        self.offset
    }

    /// Nodes in one layer of the window across the slab axis (the slab axis's stride).
    pub fn layer(&self) -> usize {
        self.strides[self.slab_axis]
    }

    /// The node ids of node `layers` along the slab axis (ids run layer by layer), those in
    /// the window.
    pub fn layer_node_ids(&self, layers: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let (layer, s) = (self.layer(), self.slab_axis);
        let (lo, hi) = (self.window.lo[s], self.window.hi[s]);
        let local = |l: usize| l.clamp(lo, hi) - lo;
        local(layers.start) * layer..local(layers.end.max(layers.start)) * layer
    }

    /// Integer coordinates of a node id.
    #[inline]
    pub fn node_ijk(&self, id: usize) -> [usize; 3] {
        let (s, m) = (self.slab_axis, 3 - self.slab_axis);
        let lo = self.window.lo;
        let mut ijk = [0; 3];
        ijk[s] = lo[s] + id / self.strides[s];
        let rest = id % self.strides[s];
        ijk[m] = lo[m] + rest / self.strides[m];
        ijk[0] = lo[0] + rest % self.strides[m];
        ijk
    }

    /// Share of a full cell volume h^D that node `id` stands for: ½ for each grid face it
    /// lies on. A node on a face (or an edge, a corner) can gather at most this share of the
    /// mass of an interior node in the same material.
    #[inline]
    pub fn node_share(&self, id: usize) -> f64 {
        self.share_at(self.node_ijk(id))
    }

    /// [`Grid::node_share`] of the node at `ijk`.
    #[inline]
    fn share_at(&self, ijk: [usize; 3]) -> f64 {
        let mut share = 1.0;
        for (a, &i) in ijk.iter().enumerate().take(D::N) {
            if i == 0 || i == self.axes[a].cells {
                share *= 0.5;
            }
        }
        share
    }

    /// True when node `id` with mass `m` (kg) carries degrees of freedom: `m` exceeds
    /// `cutoff` (kg, for an interior node) times the node's share.
    #[inline(always)]
    pub fn carries(&self, id: usize, m: f64, cutoff: f64) -> bool {
        // The share is only worked out for the few nodes between the two bounds.
        m > cutoff || (m > cutoff * 0.5f64.powi(D::N as i32) && m > cutoff * self.node_share(id))
    }

    /// True when node `id` with mass `m` (kg) counts in the force ratio K_F: it carries
    /// degrees of freedom ([`Grid::carries`]) and, in axisymmetry, `m` exceeds `cutoff`
    /// times its share of a full node at its own radius, r/h times the reference at r = h
    /// (volumes per radian grow with r). A node at r = 10 h that gathers a thousandth of the
    /// reference holds a ten-thousandth of a full node beside it; next to a loaded face such
    /// a node holds a force, from the gradients of the few points that reach it, which no
    /// motion of its own balances, and K_F waited on it (the spherical cavity,
    /// docs/verification.md). It still carries its degrees of freedom: left out of
    /// the grid, its share of Σ∇w = 0 acts on the points as a spurious force.
    #[inline(always)]
    pub fn counts_in_balance(&self, id: usize, m: f64, cutoff: f64) -> bool {
        if !D::AXISYMMETRIC {
            return self.carries(id, m, cutoff);
        }
        let ijk = self.node_ijk(id);
        let r = D::vec_to3(self.node_position(ijk))[0];
        m > cutoff * self.share_at(ijk) * (r * self.inv_h).max(1.0)
    }

    /// Mass (kg) that accelerates node `id` of mass `m`: at least `floor` (kg, for an interior
    /// node) times the node's share.
    #[inline(always)]
    pub fn inertia(&self, id: usize, m: f64, floor: f64) -> f64 {
        if m >= floor {
            m
        } else {
            m.max(floor * self.node_share(id))
        }
    }

    /// Index of the cell holding `x` along each axis, clamped into the grid.
    #[inline(always)]
    pub fn clamped_cell(&self, x: D::Vec) -> [usize; 3] {
        let mut c = [0usize; 3];
        for (a, ca) in c.iter_mut().enumerate().take(D::N) {
            *ca = self.clamped_cell_along(x, a);
        }
        c
    }

    /// The second axis a split over MPI ranks cuts ([`crate::infra::decomposition`]): the
    /// middle axis in 3D, x in 2D.
    pub fn across_axis(&self) -> usize {
        if D::N == 3 {
            3 - self.slab_axis
        } else {
            0
        }
    }

    /// The cell holding `x` as its layers along the slab axis and the second split axis,
    /// clamped into the grid.
    #[inline]
    pub fn split_cell(&self, x: D::Vec) -> [usize; 2] {
        [
            self.clamped_cell_along(x, self.slab_axis),
            self.clamped_cell_along(x, self.across_axis()),
        ]
    }

    /// The box of node layers `slab` along the slab axis and `across` along the second
    /// split axis, every node along the third.
    pub fn split_box(&self, slab: std::ops::Range<usize>, across: std::ops::Range<usize>) -> NodeBox {
        let mut b = NodeBox::default();
        for a in 0..3 {
            (b.lo[a], b.hi[a]) = (0, self.nodes[a]);
        }
        (b.lo[self.slab_axis], b.hi[self.slab_axis]) = (slab.start, slab.end);
        let m = self.across_axis();
        (b.lo[m], b.hi[m]) = (across.start, across.end);
        b
    }

    /// The nodes in node layers `slab` along the slab axis and `across` along the second
    /// split axis (those in the window), as a membership test on node ids.
    pub fn rank_nodes(&self, slab: std::ops::Range<usize>, across: std::ops::Range<usize>) -> RankNodes {
        let m = self.across_axis();
        let (lo, hi) = (self.window.lo[m], self.window.hi[m]);
        let local = |l: usize| l.clamp(lo, hi) - lo;
        let across = local(across.start)..local(across.end.max(across.start));
        let all = across.start == 0 && across.end >= hi - lo;
        RankNodes {
            ids: self.layer_node_ids(slab),
            across: (!all).then_some((across, self.strides[m], hi - lo)),
        }
    }

    /// Index of the cell holding `x` along `axis`, clamped into the grid.
    #[inline(always)]
    pub fn clamped_cell_along(&self, x: D::Vec, axis: usize) -> usize {
        cell_index(self.grid_coordinate(x, axis), &self.axes[axis])
    }

    /// Where a point that moves from `from` to `to` (m) lands: `None` outside the grid (as
    /// [`Grid::contains`]), otherwise whether it left its cell. Cells are compared in cell
    /// units rounded down, which agrees with [`Grid::clamped_cell`] except for a point on an
    /// upper face (or outside), which the clamp puts in the last cell: a move between it and
    /// the last cell is called a change. A change is never missed.
    #[inline(always)]
    pub fn landing(&self, from: D::Vec, to: D::Vec) -> Option<bool> {
        let mut left = false;
        for k in 0..D::N {
            let xi = self.grid_coordinate(to, k);
            if !self.axes[k].spans(xi) {
                return None;
            }
            left |= xi.floor() != self.grid_coordinate(from, k).floor();
        }
        Some(left)
    }

    /// The nodes a stencil of `support` nodes per axis can reach from cells `lo ..= hi`: it
    /// starts at the point's cell or the one below and never leaves the grid.
    pub fn reach(&self, lo: [usize; 3], hi: [usize; 3], support: usize) -> NodeBox {
        let mut b = NodeBox {
            lo: [0; 3],
            hi: [1; 3],
        };
        for a in 0..D::N {
            b.lo[a] = lo[a].saturating_sub(1);
            b.hi[a] = (hi[a] + support).min(self.nodes[a]);
        }
        b
    }

    /// Position of node (i, j, k) (m).
    pub fn node_position(&self, ijk: [usize; 3]) -> D::Vec {
        let mut x = self.origin;
        for (a, &i) in ijk.iter().enumerate().take(D::N) {
            x.set(a, x.get(a) + i as f64 * self.cell_size);
        }
        x
    }

    /// Upper corner of the grid (m).
    pub fn max_corner(&self) -> D::Vec {
        self.node_position(self.cells())
    }

    /// Position in cell units from the origin along `axis`.
    #[inline(always)]
    pub fn grid_coordinate(&self, x: D::Vec, axis: usize) -> f64 {
        (x.get(axis) - self.origin.get(axis)) * self.inv_h
    }

    /// Index of the cell holding `x` along each axis, or `None` outside the grid.
    /// A point on the upper face belongs to the last cell.
    pub fn cell_of(&self, x: D::Vec) -> Option<[usize; 3]> {
        let mut c = [0usize; 3];
        for (a, ca) in c.iter_mut().enumerate().take(D::N) {
            let xi = self.grid_coordinate(x, a);
            if !self.axes[a].spans(xi) {
                return None;
            }
            *ca = cell_index(xi, &self.axes[a]);
        }
        Some(c)
    }

    /// Sort key of the cell holding `x` (clamped into the grid): the id of the cell's lowest
    /// node, so that cells come in the order nodes are numbered, slab axis slowest.
    #[inline(always)]
    pub fn cell_key(&self, x: D::Vec) -> usize {
        self.node_id(self.clamped_cell(x))
    }

    /// True when `x` lies inside the grid's bounding box (faces included).
    pub fn contains(&self, x: D::Vec) -> bool {
        self.cell_of(x).is_some()
    }
}

/// The node-id steps of a window of nodes: x fastest, then the middle axis, the slab axis
/// slowest.
fn window_strides(window: NodeBox, slab_axis: usize) -> [usize; 3] {
    let n = |a: usize| window.hi[a] - window.lo[a];
    let middle = 3 - slab_axis;
    let mut strides = [1usize; 3];
    strides[middle] = n(0);
    strides[slab_axis] = n(0) * n(middle);
    strides
}

/// One axis of a grid as cell indices and shape functions use it, with the bounds they clamp
/// to already in floating point (converting the cell count on every call showed in a
/// step's time; docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    /// Number of cells.
    pub cells: usize,
    /// Grid coordinate of the upper face: `cells` as a float (cell units).
    pub end: f64,
    /// Index of the last cell, `cells − 1`, as a float.
    pub last_cell: f64,
    /// 1 / h (1/m).
    pub inv_h: f64,
    /// Half-width of a point's box along this axis (cell units) for uniform GIMP shape
    /// functions: 1/(2n) for n points a cell side. Other shapes ignore it.
    pub particle_half_width: f64,
}

impl Axis {
    /// An axis of `cells` cells of inverse size `inv_h` (1/m).
    pub fn new(cells: usize, inv_h: f64) -> Axis {
        Axis {
            cells,
            end: cells as f64,
            last_cell: cells as f64 - 1.0,
            inv_h,
            particle_half_width: 0.25,
        }
    }

    /// True when grid coordinate `xi` (cell units) lies on the axis, faces included (false
    /// for NaN).
    #[inline(always)]
    pub fn spans(&self, xi: f64) -> bool {
        xi >= 0.0 && xi <= self.end
    }
}

/// A cell or node index as a float. Through i64: one conversion instruction, where usize → f64
/// needs a fix-up sequence (for values no index reaches), and stencils convert on every call.
#[inline(always)]
pub fn index_to_f64(k: usize) -> f64 {
    k as i64 as f64
}

/// Index of the cell holding grid coordinate `xi` (cell units from the origin) on `axis`,
/// clamped into `0 .. cells`: a point on the upper face belongs to the last cell, one below
/// the lower face to the first.
#[inline(always)]
pub fn cell_index(xi: f64, axis: &Axis) -> usize {
    // This runs ~20 times a point every step, so it is kept to a compare-and-select per
    // bound and one truncation: clamped in floating point first, the unchecked conversion
    // needs none of the saturating cast's fix-ups. The result is the one truncating then
    // clamping gives for every `xi`, infinities and NaN (cell 0) included.
    let c = clamped_coordinate(xi, axis);
    // SAFETY: `c` lies in 0 ..= cells − 1 (a NaN fails `xi > 0` and becomes 0), so it is
    // finite and fits an i64.
    unsafe { c.to_int_unchecked::<i64>() as usize }
}

/// The cell index of `xi` as a float: `index_to_f64(cell_index(xi, axis))`, bit for bit.
///
/// Where the build has SSE4.1 it is one rounding instruction on the clamped coordinate
/// (non-negative, so floor is truncation) instead of a conversion to an integer and back: a
/// point's weights wait on it in every transfer, and the integer index then only picks nodes.
#[inline(always)]
pub fn cell_floor(xi: f64, axis: &Axis) -> f64 {
    if cfg!(target_feature = "sse4.1") {
        clamped_coordinate(xi, axis).floor()
    } else {
        index_to_f64(cell_index(xi, axis))
    }
}

/// `xi` clamped into [0, cells − 1] (NaN to 0), the coordinate whose truncation is the cell.
#[inline(always)]
fn clamped_coordinate(xi: f64, axis: &Axis) -> f64 {
    let c = if xi > 0.0 { xi } else { 0.0 };
    if c < axis.last_cell {
        c
    } else {
        axis.last_cell
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{Dim2, Dim3, DimAxi};
    use glam::{DVec2, DVec3};

    #[test]
    fn cell_index_truncates_then_clamps_into_the_grid_for_any_coordinate_as_does_cell_floor() {
        // The plain definition: truncate toward zero (saturating), then clamp.
        let reference = |xi: f64, cells: usize| (xi as i64).max(0).min(cells as i64 - 1) as usize;
        let mut coordinates = vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 1e300, -1e300];
        coordinates.extend((-400..=1600).map(|k| k as f64 * 0.0125));
        for cells in [1, 2, 7, 13] {
            let c = cells as f64;
            coordinates.extend([c, c - 1e-12, c + 1e-12, f64::EPSILON, -f64::EPSILON]);
            for &xi in &coordinates {
                let axis = Axis::new(cells, 1.0);
                assert_eq!(
                    cell_index(xi, &axis),
                    reference(xi, cells),
                    "xi = {xi}, {cells} cells"
                );
                let as_float = index_to_f64(reference(xi, cells));
                assert_eq!(cell_floor(xi, &axis).to_bits(), as_float.to_bits(), "xi = {xi}");
            }
        }
    }

    #[test]
    fn a_landing_never_misses_a_cell_change_and_calls_one_only_on_an_upper_face() {
        // A 2 × 3 × 4 grid of 0.5 m cells from (−1, 0, 2) m; points on a lattice of 0.1 m
        // steps reaching 0.3 m beyond every face, moved by small and cell-sized steps.
        let grid = Grid::<Dim3>::new(DVec3::new(-1.0, 0.0, 2.0), 0.5, [2, 3, 4]);
        let (lo, hi) = (grid.origin - 0.3, grid.max_corner() + 0.3);
        let lattice = |a: usize| {
            let n = ((hi[a] - lo[a]) / 0.1).round() as usize;
            (0..=n).map(move |k| lo[a] + k as f64 * 0.1)
        };
        let steps = [0.0, 1e-9, -1e-9, 0.04, -0.07, 0.5, -0.5];
        let (mut called_left, mut kept) = (0, 0);
        for x in lattice(0) {
            for y in lattice(1) {
                for z in lattice(2) {
                    let from = DVec3::new(x, y, z);
                    if !grid.contains(from) {
                        continue;
                    }
                    for (i, &d) in steps.iter().enumerate() {
                        let to = from + DVec3::new(d, steps[(i + 2) % 7], steps[(i + 5) % 7]);
                        match grid.landing(from, to) {
                            None => assert!(!grid.contains(to), "{from} → {to} is inside"),
                            Some(left) => {
                                assert!(grid.contains(to), "{from} → {to} is outside");
                                let same = grid.clamped_cell(from) == grid.clamped_cell(to);
                                let on_upper_face =
                                    |p: DVec3| (0..3).any(|a| grid.grid_coordinate(p, a) == grid.axes[a].end);
                                if on_upper_face(from) || on_upper_face(to) {
                                    assert!(left || same, "{from} → {to}: change missed");
                                } else {
                                    assert_eq!(left, !same, "{from} → {to}");
                                }
                                if left {
                                    called_left += 1;
                                } else {
                                    kept += 1;
                                }
                            }
                        }
                    }
                }
            }
        }
        assert!(
            called_left > 1000 && kept > 1000,
            "{called_left} left, {kept} kept"
        );
    }

    #[test]
    fn node_ids_round_trip() {
        for cells in [[4, 3, 2], [4, 2, 3]] {
            let g = Grid::<Dim3>::new(DVec3::ZERO, 0.5, cells);
            assert_eq!(g.node_count(), 5 * 4 * 3);
            for id in 0..g.node_count() {
                assert_eq!(g.node_id(g.node_ijk(id)), id);
            }
        }
    }

    #[test]
    fn a_window_numbers_its_nodes_alone_and_keeps_the_whole_grids_places() {
        for cells in [[6, 5, 7], [6, 7, 5]] {
            let whole = Grid::<Dim3>::new(DVec3::new(-1.0, 0.0, 2.0), 0.5, cells);
            let mut window = whole.split_box(2..5, 1..4);
            window.lo[0] = 0;
            let g = whole.windowed(window);
            assert_eq!(g.node_count(), window.len());
            assert!(!g.is_whole() && whole.is_whole() && g.whole().window() == whole.window());
            // Ids run 0.. over the window's nodes, each at its own place in the grid.
            for id in 0..g.node_count() {
                let ijk = g.node_ijk(id);
                assert!(g.numbers(ijk), "{ijk:?}");
                assert_eq!(g.node_id(ijk), id);
                assert_eq!(g.checked_node_id(ijk), Some(id));
                assert_eq!(g.node_position(ijk), whole.node_position(ijk));
                assert_eq!(g.node_share(id), whole.node_share(whole.node_id(ijk)));
            }
            assert_eq!(g.checked_node_id([0, 0, 0]), None);
            // A box's rows and a range of layers name the same nodes in both numberings.
            let b = g.reach([1, 2, 2], [3, 3, 3], 3);
            let b = NodeBox {
                lo: b.lo.map(|l| l.max(1)),
                hi: b.hi,
            };
            let b = NodeBox {
                lo: std::array::from_fn(|a| b.lo[a].max(window.lo[a])),
                hi: std::array::from_fn(|a| b.hi[a].min(window.hi[a])),
            };
            let here: Vec<[usize; 3]> = b.rows(&g).flatten().map(|i| g.node_ijk(i)).collect();
            let there: Vec<[usize; 3]> = b.rows(&whole).flatten().map(|i| whole.node_ijk(i)).collect();
            assert_eq!(here, there);
            let s = g.slab_axis;
            let layers: Vec<usize> = g.layer_node_ids(3..5).map(|i| g.node_ijk(i)[s]).collect();
            assert!(layers.iter().all(|l| (3..5).contains(l)) && layers.len() == 2 * g.layer());
            // A rank's nodes by layers along both split axes, as a test on the window's ids.
            let (slab, across) = (3..5, 2..3);
            let mine = g.rank_nodes(slab.clone(), across.clone());
            let m = g.across_axis();
            for id in 0..g.node_count() {
                let ijk = g.node_ijk(id);
                assert_eq!(
                    mine.contains(&id),
                    slab.contains(&ijk[s]) && across.contains(&ijk[m]),
                    "{ijk:?}"
                );
            }
        }
        // A window of no node numbers one, so a rank without cells keeps its columns.
        let g = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [4, 3, 0]);
        assert_eq!(g.windowed(NodeBox::default()).node_count(), 1);
    }

    #[test]
    fn the_longer_of_y_and_z_runs_slowest() {
        let thin = Grid::<Dim3>::new(DVec3::ZERO, 1.0, [180, 45, 2]);
        assert_eq!((thin.slab_axis, thin.strides), (1, [1, 181 * 3, 181]));
        let block = Grid::<Dim3>::new(DVec3::ZERO, 1.0, [50, 50, 52]);
        assert_eq!((block.slab_axis, block.strides), (2, [1, 51, 51 * 51]));
        let plane = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [180, 45, 0]);
        assert_eq!((plane.slab_axis, plane.strides[..2].to_vec()), (1, vec![1, 181]));
    }

    #[test]
    fn a_2d_grid_has_one_layer_of_nodes() {
        let g = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [3, 2, 7]);
        assert_eq!(g.cells(), [3, 2, 0]);
        assert_eq!(g.node_count(), 4 * 3);
        assert_eq!(g.cell_of(DVec2::new(3.0, 2.0)), Some([2, 1, 0]));
        assert_eq!(g.cell_of(DVec2::new(3.01, 1.0)), None);
    }

    #[test]
    fn node_box_rows_cover_the_box_once() {
        let g = Grid::<Dim3>::new(DVec3::ZERO, 1.0, [5, 4, 3]);
        let b = g.reach([1, 0, 2], [2, 1, 2], 2);
        assert_eq!(
            b,
            NodeBox {
                lo: [0, 0, 1],
                hi: [4, 3, 4]
            }
        );
        let ids: Vec<usize> = b.rows(&g).flatten().collect();
        assert_eq!(ids.len(), b.len());
        for id in ids {
            let [i, j, k] = g.node_ijk(id);
            assert!(i < 4 && j < 3 && (1..4).contains(&k));
        }
        assert_eq!(NodeBox::default().rows(&g).count(), 0);
        let g2 = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [5, 4, 0]);
        assert_eq!(g2.reach([0, 3, 0], [4, 3, 0], 3).len(), 6 * 3);
    }

    #[test]
    fn node_share_halves_per_grid_face() {
        let g = Grid::<Dim3>::new(DVec3::ZERO, 1.0, [4, 3, 2]);
        assert_eq!(g.node_share(g.node_id([2, 1, 1])), 1.0);
        assert_eq!(g.node_share(g.node_id([0, 1, 1])), 0.5);
        assert_eq!(g.node_share(g.node_id([4, 3, 1])), 0.25);
        assert_eq!(g.node_share(g.node_id([0, 0, 2])), 0.125);
        let g2 = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [4, 3, 0]);
        assert_eq!(g2.node_share(g2.node_id([4, 1, 0])), 0.5);
        assert_eq!(g2.node_share(g2.node_id([2, 1, 0])), 1.0);
        // Between the two bounds the share decides.
        assert!(g.carries(g.node_id([0, 1, 1]), 0.6, 1.0));
        assert!(!g.carries(g.node_id([2, 1, 1]), 0.6, 1.0));
        assert_eq!(g.inertia(g.node_id([0, 0, 2]), 0.1, 1.0), 0.125);
    }

    #[test]
    fn an_axisymmetric_node_counts_in_k_f_by_a_full_node_at_its_radius() {
        // Per radian a full node at radius r holds r/h times the mass of one at r = h, the
        // reference of the cut-off: at r = 6 h a node must hold 6 times the cut-off (3 on
        // a grid face) to count, while it carries degrees of freedom from 1 times.
        let g = Grid::<DimAxi>::new(DVec2::ZERO, 0.5, [20, 4, 0]);
        let (at_6h, face_6h, at_h) = (g.node_id([6, 2, 0]), g.node_id([6, 0, 0]), g.node_id([1, 2, 0]));
        assert!(g.carries(at_6h, 2e-3, 1e-3) && !g.counts_in_balance(at_6h, 2e-3, 1e-3));
        assert!(g.counts_in_balance(at_6h, 6.1e-3, 1e-3));
        assert!(!g.counts_in_balance(face_6h, 2.9e-3, 1e-3) && g.counts_in_balance(face_6h, 3.1e-3, 1e-3));
        assert!(g.counts_in_balance(at_h, 1.1e-3, 1e-3));
        assert!(g.counts_in_balance(g.node_id([0, 2, 0]), 0.6e-3, 1e-3));
        // Off the axis the plane grid's rule is unchanged.
        let g2 = Grid::<Dim2>::new(DVec2::ZERO, 0.5, [20, 4, 0]);
        assert!(g2.counts_in_balance(g2.node_id([6, 2, 0]), 2e-3, 1e-3));
    }
}
