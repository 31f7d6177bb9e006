//! Shape functions: the weights w_ip and gradients ∇w_ip that connect point p to node i.
//!
//! Each shape is a tensor product of a 1D function ([`Shape::eval_1d`]); [`for_each_node`] is
//! the single place where the product is formed and node ids are computed, so every transfer
//! (particle-to-grid, grid-to-particle, remap, kinematics) uses the same weights.

mod bspline;
mod gimp;
mod linear;

pub use bspline::QuadraticBSpline;
pub use gimp::UniformGimp;
pub use linear::Linear;

use crate::dim::{Dim, Vector};
use crate::grid::{Axis, Grid};
use crate::infra::lanes::{F64x4, Lanes};
use crate::tensor::Sym3;

/// The 1D weights of one point along one axis: nodes `base .. base + SUPPORT`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stencil1 {
    /// Index of the first node of the stencil along this axis.
    pub base: usize,
    /// Weights (dimensionless).
    pub w: [f64; 3],
    /// Derivatives of the weights along the axis (1/m).
    pub dw: [f64; 3],
}

/// The stencil of three-node weights `w`, `dw` on nodes `k`, `k + 1`, `k + 2` (with
/// `t = xi − ½`, `k` its cell index), moved inside the grid at its faces: a ghost node
/// beyond a face takes the linear extrapolation of the two nodes inside
/// (v_ghost = 2v_0 − v_1), which folds its weight onto them, N_0 += 2N_ghost and
/// N_1 −= N_ghost. Partition of unity and linear reproduction are kept. Shared by the
/// quadratic B-spline and uniform GIMP.
#[inline(always)]
pub(crate) fn fold_ghosts(t: f64, k: usize, cells: usize, w: [f64; 3], dw: [f64; 3]) -> Stencil1 {
    let ([w0, w1, w2], [g0, g1, g2]) = (w, dw);
    if t < 0.0 {
        // Ghost node at −1: nodes 0, 1, 2.
        Stencil1 {
            base: 0,
            w: [w1 + 2.0 * w0, w2 - w0, 0.0],
            dw: [g1 + 2.0 * g0, g2 - g0, 0.0],
        }
    } else if k + 2 > cells {
        // Ghost node at cells + 1: nodes cells − 2, cells − 1, cells.
        Stencil1 {
            base: cells - 2,
            w: [0.0, w0 - w2, w1 + 2.0 * w2],
            dw: [0.0, g0 - g2, g1 + 2.0 * g2],
        }
    } else {
        Stencil1 { base: k, w, dw }
    }
}

/// A 1D shape function family, extended to 2D/3D by tensor product.
pub trait Shape: Copy + Send + Sync + Default + std::fmt::Debug + 'static {
    /// Name used in scenes and reports.
    const NAME: &'static str;
    /// Nodes per axis that a point touches.
    const SUPPORT: usize;
    /// Weights for a point at grid coordinate `xi` (cell units from the origin) on `axis`.
    /// The caller guarantees `0 ≤ xi ≤ cells`.
    fn eval_1d(xi: f64, axis: &Axis) -> Stencil1;

    /// The velocity gradient Σ_i v_i ⊗ ∇w_ip (1/s) and the velocity Σ_i w_ip v_i (m/s) that
    /// the nodal field `v` (node id → m/s) gives a point at `x` inside the grid.
    #[inline(always)]
    fn gather_with_gradient<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
    ) -> (D::Mat, D::Vec) {
        Self::gather_with_gradient_visiting(grid, x, v, |_, _, _| {})
    }

    /// [`Shape::gather_with_gradient`], calling `visit(sx, first_node, w_r)` on each row of
    /// the point's nodes ([`for_each_row`]) as it goes, so that a caller sums more over the
    /// same visit.
    ///
    /// The default visits the rows, then sums node by node ([`gather_node_by_node`]); a
    /// shape may use its own structure to do the same sums with less work, in one visit.
    #[inline(always)]
    fn gather_with_gradient_visiting<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
        visit: impl FnMut(&Stencil1, usize, f64),
    ) -> (D::Mat, D::Vec) {
        let mut visit = visit;
        for_each_row::<D, Self>(grid, x, |sx, first, w, _, _| visit(sx, first, w));
        gather_node_by_node::<D, Self>(grid, x, v)
    }

    /// [`Shape::gather_with_gradient`] of `v` and, in the same visit of the nodes,
    /// Σ_i w_ip a_i of a second field `a` (node id → any unit), summed node by node in
    /// [`for_each_node`]'s order: the same bits as a loop of its own, with the weights
    /// formed once (USL's g2p gathers the accelerations beside kinematics' velocities).
    #[inline(always)]
    fn gather_with_gradient_and<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
        a: impl Fn(usize) -> D::Vec,
    ) -> (D::Mat, D::Vec, D::Vec) {
        let mut sum = D::Vec::ZERO;
        let (l, vel) = Self::gather_with_gradient_visiting(grid, x, v, |sx, first, w| {
            for i in 0..Self::SUPPORT {
                sum = a(first + i).madd(sx.w[i] * w, sum);
            }
        });
        (l, vel, sum)
    }

    /// Calls `add(node_id, w_ip m, w_ip q, −V σ·∇w_ip)` for every node in the support of a
    /// point at `x` inside the grid: the point's share of nodal mass (kg), momentum (kg·m/s)
    /// and internal force (N) for mass `m`, momentum `q`, stress `s` (Pa) and `neg_vol` = −V
    /// (m³, or m² a unit thickness in plane strain). The transpose of
    /// [`Shape::gather_with_gradient`], and like it node by node by default
    /// ([`scatter_node_by_node`]).
    #[inline(always)]
    fn scatter_with_gradient<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        m: f64,
        q: D::Vec,
        s: &Sym3,
        neg_vol: f64,
        add: impl FnMut(usize, f64, D::Vec, D::Vec),
    ) {
        scatter_node_by_node::<D, Self>(grid, x, m, q, s, neg_vol, add)
    }
}

/// [`Shape::gather_with_gradient`] from every node's weight and gradient ([`for_each_node`]):
/// the default, and the reference a shape's own form is tested against.
#[inline(always)]
pub fn gather_node_by_node<D: Dim, S: Shape>(
    grid: &Grid<D>,
    x: D::Vec,
    v: impl Fn(usize) -> D::Vec,
) -> (D::Mat, D::Vec) {
    let mut acc = GradientSum::default();
    for_each_node::<D, S>(grid, x, |i, w, grad| {
        acc.add::<D>(in_lanes::<D>(v(i)), grad, w);
    });
    acc.finish::<D>()
}

/// A vector in the lanes of one register: (x, y, z, 0), z = 0 in 2D.
///
/// The transfers keep their per-point vectors so: as glam vectors each takes two registers in
/// 3D (xy and z), and the compiler ran short of registers and spilled to the stack.
#[inline(always)]
pub(crate) fn in_lanes<D: Dim>(v: D::Vec) -> F64x4 {
    let [x, y, z] = D::vec_to3(v);
    F64x4::new([x, y, z, 0.0])
}

/// The vector in the first N lanes of `v` (the inverse of [`in_lanes`]).
#[inline(always)]
pub(crate) fn from_lanes<D: Dim>(v: F64x4) -> D::Vec {
    let [x, y, z, _] = v.to_array();
    D::vec_from([x, y, z])
}

/// The running sums of a gather: the columns of Σ v_i ⊗ g_i and Σ w_i v_i, each in lanes
/// ([`in_lanes`]).
///
/// As glam vectors the twelve sums of a 3D gather did not all stay in registers, and every
/// node's multiply-add waited on a store and a reload (the 3D kinematics' hottest
/// instruction). Four registers hold them, and each lane rounds as the scalar
/// [`crate::infra::lanes::madd`], so the bits are those of the glam form.
#[derive(Clone, Copy, Default)]
pub(crate) struct GradientSum {
    /// Column j of the velocity gradient (1/s).
    cols: [F64x4; 3],
    /// The velocity (m/s).
    vel: F64x4,
}

impl GradientSum {
    /// Adds `v ⊗ g` to the gradient and `w v` to the velocity.
    #[inline(always)]
    pub(crate) fn add<D: Dim>(&mut self, v: F64x4, g: D::Vec, w: f64) {
        for j in 0..D::N {
            self.add_column(j, v, g.get(j));
        }
        self.add_velocity(v, w);
    }

    /// Adds one x-row of nodes ([`for_each_row`]): `x_part · x_factor` to the x column,
    /// where the row's x-slopes live, and the row's weighted velocity `mean` times ∂w_r/∂y,
    /// ∂w_r/∂z and w_r to the other columns and to the velocity.
    #[inline(always)]
    pub(crate) fn add_row<D: Dim>(
        &mut self,
        (x_part, x_factor): (F64x4, f64),
        mean: F64x4,
        (w, dw_dy, dw_dz): (f64, f64, f64),
    ) {
        self.add_column(0, x_part, x_factor);
        self.add_column(1, mean, dw_dy);
        if D::N == 3 {
            self.add_column(2, mean, dw_dz);
        }
        self.add_velocity(mean, w);
    }

    /// Adds `v k` to column `j` of the gradient.
    #[inline(always)]
    fn add_column(&mut self, j: usize, v: F64x4, k: f64) {
        self.cols[j] = Lanes::madd(v, F64x4::splat(k), self.cols[j]);
    }

    /// Adds `v w` to the velocity.
    #[inline(always)]
    fn add_velocity(&mut self, v: F64x4, w: f64) {
        self.vel = Lanes::madd(v, F64x4::splat(w), self.vel);
    }

    /// The velocity gradient and the velocity.
    #[inline(always)]
    pub(crate) fn finish<D: Dim>(self) -> (D::Mat, D::Vec) {
        let c = &self.cols;
        let cols = [
            from_lanes::<D>(c[0]),
            from_lanes::<D>(c[1]),
            from_lanes::<D>(c[2]),
        ];
        (D::mat_from_cols(cols), from_lanes::<D>(self.vel))
    }
}

/// [`Shape::scatter_with_gradient`] from every node's weight and gradient
/// ([`for_each_node`]): the default, and the reference a shape's own form is tested against.
#[inline(always)]
pub fn scatter_node_by_node<D: Dim, S: Shape>(
    grid: &Grid<D>,
    x: D::Vec,
    m: f64,
    q: D::Vec,
    s: &Sym3,
    neg_vol: f64,
    mut add: impl FnMut(usize, f64, D::Vec, D::Vec),
) {
    let (sigma, q, k) = (StressColumns::of(s, 1.0), in_lanes::<D>(q), F64x4::splat);
    for_each_node::<D, S>(grid, x, |i, w, grad| {
        let f = sigma.dot::<D>(grad) * k(neg_vol);
        add(i, w * m, from_lanes::<D>(q * k(w)), from_lanes::<D>(f));
    });
}

/// The columns of k σ in lanes (see [`in_lanes`]), for (kσ)·n at each node of a point.
#[derive(Clone, Copy)]
pub(crate) struct StressColumns([F64x4; 3]);

impl StressColumns {
    /// The columns of `k` σ (k = 1 leaves σ's bits; k = −V gives the columns of −Vσ).
    #[inline(always)]
    pub(crate) fn of(s: &Sym3, k: f64) -> Self {
        let col = |a: f64, b: f64, c: f64| F64x4::new([a * k, b * k, c * k, 0.0]);
        StressColumns([
            col(s.xx, s.xy, s.zx),
            col(s.xy, s.yy, s.yz),
            col(s.zx, s.yz, s.zz),
        ])
    }

    /// Column `j` (0 = x, 1 = y, 2 = z).
    #[inline(always)]
    pub(crate) fn column(&self, j: usize) -> F64x4 {
        self.0[j]
    }

    /// (kσ)·n with the in-plane components alone in 2D (Pa · m² = N per unit of n).
    #[inline(always)]
    pub(crate) fn dot<D: Dim>(&self, n: D::Vec) -> F64x4 {
        let [nx, ny, nz] = D::vec_to3(n);
        Lanes::madd(self.0[0], F64x4::splat(nx), self.dot_yz::<D>(ny, nz))
    }

    /// The y and z terms of [`StressColumns::dot`]: (kσ)_y n_y + (kσ)_z n_z (n_z unused in
    /// 2D). The row forms apply them once a row, with n_y, n_z the row's ∂w_r/∂y, ∂w_r/∂z.
    #[inline(always)]
    pub(crate) fn dot_yz<D: Dim>(&self, ny: f64, nz: f64) -> F64x4 {
        let [_, cy, cz] = self.0;
        let k = F64x4::splat;
        if D::N == 3 {
            Lanes::madd(cy, k(ny), cz * k(nz))
        } else {
            cy * k(ny)
        }
    }
}

/// Calls `f(node_id, w, ∇w)` for every node in the support of a point at `x`.
///
/// The point must lie inside the grid (the kinematics system guarantees this).
#[inline(always)]
pub fn for_each_node<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec, mut f: impl FnMut(usize, f64, D::Vec)) {
    for_each_row::<D, S>(grid, x, |sx, first, w, dw_dy, dw_dz| {
        for i in 0..S::SUPPORT {
            let grad = D::vec_from([sx.dw[i] * w, sx.w[i] * dw_dy, sx.w[i] * dw_dz]);
            f(first + i, sx.w[i] * w, grad);
        }
    });
}

/// Calls `row(sx, first_node, w_r, ∂w_r/∂y, ∂w_r/∂z)` for every x-row of the nodes in the
/// support of a point at `x` inside the grid (`SUPPORT` rows in 2D, `SUPPORT²` in 3D). A row's
/// nodes are `first_node` and the next `SUPPORT − 1`; node i of the row has weight
/// `sx.w[i]`·w_r and gradient (`sx.dw[i]`·w_r, `sx.w[i]`·∂w_r/∂y, `sx.w[i]`·∂w_r/∂z), where
/// w_r is the product of the y and z weights (∂w_r/∂z = 0 in 2D).
///
/// The nodes of a row share w_r and its derivatives, so the transfers work a row at a time
/// and leave the x-weights to the last, cheapest factor.
#[inline(always)]
pub fn for_each_row<D: Dim, S: Shape>(
    grid: &Grid<D>,
    x: D::Vec,
    mut row: impl FnMut(&Stencil1, usize, f64, f64, f64),
) {
    let sx = S::eval_1d(grid.grid_coordinate(x, 0), &grid.axes[0]);
    let sy = S::eval_1d(grid.grid_coordinate(x, 1), &grid.axes[1]);
    let [_, stride_y, stride_z] = grid.strides;
    // Ids count from the grid's window (0 off a whole grid), which holds the stencil.
    debug_assert!({
        let sz = if D::N == 3 {
            S::eval_1d(grid.grid_coordinate(x, 2), &grid.axes[2]).base
        } else {
            0
        };
        let last = |b: usize, a: usize| if a < D::N { b + S::SUPPORT - 1 } else { b };
        grid.numbers([sx.base, sy.base, sz])
            && grid.numbers([last(sx.base, 0), last(sy.base, 1), last(sz, 2)])
    });
    let x_base = sx.base.wrapping_sub(grid.id_offset());
    if D::N == 2 {
        for j in 0..S::SUPPORT {
            row(
                &sx,
                ((sy.base + j) * stride_y).wrapping_add(x_base),
                sy.w[j],
                sy.dw[j],
                0.0,
            );
        }
    } else {
        let sz = S::eval_1d(grid.grid_coordinate(x, 2), &grid.axes[2]);
        for k in 0..S::SUPPORT {
            for j in 0..S::SUPPORT {
                row(
                    &sx,
                    ((sz.base + k) * stride_z + (sy.base + j) * stride_y).wrapping_add(x_base),
                    sy.w[j] * sz.w[k],
                    sy.dw[j] * sz.w[k],
                    sy.w[j] * sz.dw[k],
                );
            }
        }
    }
}

/// The shape function family chosen by a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ShapeKind {
    /// Linear (bilinear in 2D, trilinear in 3D) hat functions: 2 nodes per axis.
    #[default]
    Linear,
    /// Quadratic B-splines, modified at the grid boundary: 3 nodes per axis.
    QuadraticBSpline,
    /// Uniform GIMP: the linear hat averaged over each point's initial box, modified at the
    /// grid boundary as the B-spline: 3 nodes per axis. Every body needs the same points a
    /// cell side.
    UniformGimp,
}

impl ShapeKind {
    /// Nodes per axis in a point's support.
    pub fn support(self) -> usize {
        match self {
            ShapeKind::Linear => Linear::SUPPORT,
            ShapeKind::QuadraticBSpline => QuadraticBSpline::SUPPORT,
            ShapeKind::UniformGimp => UniformGimp::SUPPORT,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::dim::{Dim2, Dim3, Vector};
    use glam::{DVec2, DVec3};

    /// Checks Σw = 1, Σ w x_i = x, Σ ∇w = 0 and Σ x_i ⊗ ∇w = I at `x`.
    pub fn check_consistency<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec) {
        let mut sum_w = 0.0;
        let mut moment = D::Vec::ZERO;
        let mut sum_grad = D::Vec::ZERO;
        let mut grad_moment = [[0.0; 3]; 3];
        for_each_node::<D, S>(grid, x, |node, w, grad| {
            let xi = grid.node_position(grid.node_ijk(node));
            sum_w += w;
            moment += xi * w;
            sum_grad += grad;
            for a in 0..D::N {
                for b in 0..D::N {
                    grad_moment[a][b] += xi.get(a) * grad.get(b);
                }
            }
        });
        assert!(
            (sum_w - 1.0).abs() < 1e-12,
            "partition of unity at {x:?}: {sum_w}"
        );
        for a in 0..D::N {
            assert!(
                (moment.get(a) - x.get(a)).abs() < 1e-12,
                "linear reproduction at {x:?}"
            );
            assert!(sum_grad.get(a).abs() < 1e-12, "gradients sum to zero at {x:?}");
            for b in 0..D::N {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((grad_moment[a][b] - expect).abs() < 1e-12, "∇x = I at {x:?}");
            }
        }
    }

    fn sample_points(n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..=n).map(|k| lo + (hi - lo) * k as f64 / n as f64).collect()
    }

    #[test]
    fn linear_shape_is_a_partition_of_unity_and_reproduces_linear_fields() {
        let g2 = Grid::<Dim2>::new(DVec2::new(-1.0, 2.0), 0.5, [6, 4, 0]);
        let g3 = Grid::<Dim3>::new(DVec3::new(0.0, -1.0, 3.0), 0.25, [4, 4, 4]);
        for &x in &sample_points(37, -1.0, 2.0) {
            for &y in &sample_points(13, 2.0, 4.0) {
                check_consistency::<Dim2, Linear>(&g2, DVec2::new(x, y));
            }
        }
        for &x in &sample_points(9, 0.0, 1.0) {
            for &z in &sample_points(11, 3.0, 4.0) {
                check_consistency::<Dim3, Linear>(&g3, DVec3::new(x, -0.3, z));
            }
        }
    }

    #[test]
    fn bspline_and_gimp_are_partitions_of_unity_and_reproduce_linear_fields_up_to_the_boundary() {
        let g2 = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [5, 4, 0]);
        let g3 = Grid::<Dim3>::new(DVec3::ZERO, 0.5, [3, 4, 3]);
        // Includes points on the faces, in the boundary cells and in the interior.
        for &x in &sample_points(50, 0.0, 5.0) {
            for &y in &sample_points(16, 0.0, 4.0) {
                check_consistency::<Dim2, QuadraticBSpline>(&g2, DVec2::new(x, y));
                check_consistency::<Dim2, UniformGimp>(&g2, DVec2::new(x, y));
            }
        }
        for &x in &sample_points(12, 0.0, 1.5) {
            for &z in &sample_points(12, 0.0, 1.5) {
                check_consistency::<Dim3, QuadraticBSpline>(&g3, DVec3::new(x, 0.1, z));
            }
        }
    }

    /// An arbitrary nodal field: node id → three components, none of them affine in the id.
    fn nodal_field(i: usize) -> [f64; 3] {
        let i = i as f64;
        [(i * 0.37).sin(), (i * 0.11).cos(), (i * 0.53).sin() - 0.2]
    }

    /// A point's share to scatter: mass (kg), momentum (kg·m/s), a stress with every
    /// component set (Pa) and −V (m³).
    fn sample_load() -> (f64, [f64; 3], Sym3, f64) {
        let s = Sym3 {
            xx: -3.1e5,
            yy: 1.7e5,
            zz: -0.4e5,
            xy: 2.2e5,
            yz: -0.9e5,
            zx: 1.3e5,
        };
        (2.5, [0.7, -1.9, 0.4], s, -0.125)
    }

    /// A shape's row-wise gather against the node-by-node sums at `x` for an arbitrary nodal
    /// field; `entries` lists a velocity gradient's entries.
    fn check_row_gather<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec, entries: impl Fn(D::Mat) -> Vec<f64>) {
        let v = |i: usize| D::vec_from(nodal_field(i));
        let (l, vel) = S::gather_with_gradient(grid, x, v);
        let (l_ref, vel_ref) = gather_node_by_node::<D, S>(grid, x, v);
        for (a, b) in entries(l).iter().zip(entries(l_ref)) {
            assert!((a - b).abs() < 1e-12, "{x:?}");
        }
        let (vel, vel_ref) = (D::vec_to3(vel), D::vec_to3(vel_ref));
        for a in 0..3 {
            assert!((vel[a] - vel_ref[a]).abs() < 1e-14, "{x:?}");
        }
    }

    /// The grids and points on which the row-wise forms are checked against the node-by-node
    /// sums: a 3D and a 2D grid, points on their faces, in the boundary cells and inside.
    fn row_form_cases() -> (Grid<Dim3>, Grid<Dim2>, Vec<(DVec3, DVec2)>) {
        let g3 = Grid::<Dim3>::new(DVec3::new(0.0, -1.0, 3.0), 0.25, [4, 5, 3]);
        let g2 = Grid::<Dim2>::new(DVec2::new(-1.0, 2.0), 0.5, [6, 4, 0]);
        let mut points = Vec::new();
        for &a in &sample_points(7, 0.0, 1.0) {
            for &b in &sample_points(5, 0.0, 1.0) {
                points.push((
                    DVec3::new(a, -1.0 + 1.25 * b, 3.0 + 0.75 * (1.0 - a * b)),
                    DVec2::new(-1.0 + 3.0 * a, 2.0 + 2.0 * b),
                ));
            }
        }
        (g3, g2, points)
    }

    fn check_row_gathers<S: Shape>() {
        let (g3, g2, points) = row_form_cases();
        for (x3, x2) in points {
            check_row_gather::<_, S>(&g3, x3, |m: glam::DMat3| m.to_cols_array().to_vec());
            check_row_gather::<_, S>(&g2, x2, |m: glam::DMat2| m.to_cols_array().to_vec());
        }
        // An affine field v = A x + c is reproduced exactly: L = A and v_p = A x_p + c, in
        // the boundary cells too.
        let a = glam::DMat3::from_cols_array(&[0.3, -1.2, 0.5, 2.0, 0.1, -0.7, -0.4, 0.9, 1.5]);
        let c = DVec3::new(0.2, -0.1, 0.05);
        let affine = |i: usize| a * g3.node_position(g3.node_ijk(i)) + c;
        for x in [DVec3::new(0.61, 0.13, 3.37), DVec3::new(0.02, -0.97, 3.74)] {
            let (l, vel) = S::gather_with_gradient(&g3, x, affine);
            assert!((l - a).to_cols_array().iter().all(|d| d.abs() < 1e-12), "{x:?}");
            assert!((vel - (a * x + c)).abs().max_element() < 1e-12, "{x:?}");
        }
    }

    #[test]
    fn shapes_gather_row_by_row_what_the_node_by_node_sums_give() {
        // The row-wise forms must agree with every node's outer product to round-off, in 2D
        // and 3D, on faces and inside.
        check_row_gathers::<Linear>();
        check_row_gathers::<QuadraticBSpline>();
    }

    /// A shape's row-wise scatter against the node-by-node products at `x`, and
    /// the sums any scatter must give: Σ w_i m = m, Σ w_i q = q, Σ f_i = 0 (the gradients
    /// sum to zero) and Σ f_i ⊗ x_i = −Vσ (from Σ ∇w_i ⊗ x_i = I).
    fn check_row_scatter<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec) {
        let (m, q, s, neg_vol) = sample_load();
        let q = D::vec_from(q);
        type Share = (f64, [f64; 3], [f64; 3]);
        let add = |into: &mut [Share], i: usize, dm: f64, dp: D::Vec, df: D::Vec| {
            let (dp, df) = (D::vec_to3(dp), D::vec_to3(df));
            into[i].0 += dm;
            for a in 0..3 {
                into[i].1[a] += dp[a];
                into[i].2[a] += df[a];
            }
        };
        let mut rows = vec![(0.0, [0.0; 3], [0.0; 3]); grid.node_count()];
        S::scatter_with_gradient(grid, x, m, q, &s, neg_vol, |i, dm, dp, df| {
            add(&mut rows, i, dm, dp, df)
        });
        let mut nodes = rows.clone();
        nodes.fill((0.0, [0.0; 3], [0.0; 3]));
        scatter_node_by_node::<D, S>(grid, x, m, q, &s, neg_vol, |i, dm, dp, df| {
            add(&mut nodes, i, dm, dp, df)
        });
        let force_scale = 3.1e5 * neg_vol.abs() / grid.cell_size;
        let (mut mass, mut momentum, mut force) = (0.0, [0.0; 3], [0.0; 3]);
        let mut moment = [[0.0; 3]; 3];
        for (i, (r, n)) in rows.iter().zip(&nodes).enumerate() {
            assert!((r.0 - n.0).abs() < 1e-14 * m, "mass at node {i}, {x:?}");
            let xi = D::vec_to3(grid.node_position(grid.node_ijk(i)));
            mass += r.0;
            for a in 0..3 {
                assert!((r.1[a] - n.1[a]).abs() < 1e-14, "momentum at node {i}, {x:?}");
                assert!((r.2[a] - n.2[a]).abs() < 1e-12 * force_scale, "force at node {i}");
                momentum[a] += r.1[a];
                force[a] += r.2[a];
                for b in 0..3 {
                    moment[a][b] += r.2[a] * xi[b];
                }
            }
        }
        let sigma = [[s.xx, s.xy, s.zx], [s.xy, s.yy, s.yz], [s.zx, s.yz, s.zz]];
        let q = D::vec_to3(q);
        assert!((mass - m).abs() < 1e-14 * m);
        for a in 0..D::N {
            assert!((momentum[a] - q[a]).abs() < 1e-14);
            assert!(force[a].abs() < 1e-10 * force_scale, "Σ f = {force:?} at {x:?}");
            for b in 0..D::N {
                let p = neg_vol * sigma[a][b];
                assert!(
                    (moment[a][b] - p).abs() < 1e-10 * p.abs().max(1.0),
                    "{a}{b} at {x:?}"
                );
            }
        }
    }

    #[test]
    fn shapes_scatter_row_by_row_what_the_node_by_node_products_give() {
        let (g3, g2, points) = row_form_cases();
        for (x3, x2) in points {
            check_row_scatter::<_, Linear>(&g3, x3);
            check_row_scatter::<_, Linear>(&g2, x2);
            check_row_scatter::<_, QuadraticBSpline>(&g3, x3);
            check_row_scatter::<_, QuadraticBSpline>(&g2, x2);
        }
    }

    /// `gather_node_by_node` and `scatter_node_by_node` against the same sums written one
    /// component at a time with `lanes::madd`, bit for bit, at `x` for an arbitrary nodal field.
    fn check_lanes_round_as_scalars<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec) {
        use crate::infra::lanes::madd;
        let v = |i: usize| D::vec_from(nodal_field(i));
        let (n, bits) = (D::N, |a: f64| a.to_bits());
        let (mut l, mut vel) = ([[0.0; 3]; 3], [0.0; 3]);
        for_each_node::<D, S>(grid, x, |i, w, grad| {
            let (vi, g) = (nodal_field(i), D::vec_to3(grad));
            for a in 0..n {
                for b in 0..n {
                    l[a][b] = madd(vi[a], g[b], l[a][b]);
                }
                vel[a] = madd(vi[a], w, vel[a]);
            }
        });
        let (l_lanes, vel_lanes) = gather_node_by_node::<D, S>(grid, x, v);
        for a in 0..n {
            assert_eq!(bits(D::vec_to3(vel_lanes)[a]), bits(vel[a]), "v_{a} at {x:?}");
            for b in 0..n {
                let entry = D::mat_entry(&l_lanes, a, b);
                assert_eq!(bits(entry), bits(l[a][b]), "L_{a}{b} at {x:?}");
            }
        }
        let (m, q, s, neg_vol) = sample_load();
        let sigma = [[s.xx, s.xy, s.zx], [s.xy, s.yy, s.yz], [s.zx, s.yz, s.zz]];
        let mut expect = Vec::new();
        for_each_node::<D, S>(grid, x, |i, w, grad| {
            let g = D::vec_to3(grad);
            let force = |a: usize| {
                let rest = if n == 3 {
                    madd(sigma[a][1], g[1], sigma[a][2] * g[2])
                } else {
                    sigma[a][1] * g[1]
                };
                madd(sigma[a][0], g[0], rest) * neg_vol
            };
            expect.push((i, w * m, q.map(|qa| qa * w), [force(0), force(1), force(2)]));
        });
        let mut k = 0;
        scatter_node_by_node::<D, S>(grid, x, m, D::vec_from(q), &s, neg_vol, |i, dm, dp, df| {
            let (node, mass, momentum, force) = expect[k];
            assert_eq!((i, bits(dm)), (node, bits(mass)), "node {k} at {x:?}");
            for a in 0..n {
                assert_eq!(bits(D::vec_to3(dp)[a]), bits(momentum[a]), "q_{a} at {x:?}");
                assert_eq!(bits(D::vec_to3(df)[a]), bits(force[a]), "f_{a} at {x:?}");
            }
            k += 1;
        });
        assert_eq!(k, expect.len());
    }

    #[test]
    fn node_by_node_transfers_in_lanes_give_the_bits_of_scalar_multiply_adds() {
        // The lanes (`GradientSum`, `StressColumns`) exist for speed alone: each lane must
        // round exactly as the one-component formula, on faces and inside, for both shapes.
        let (g3, g2, points) = row_form_cases();
        for (x3, x2) in points {
            check_lanes_round_as_scalars::<Dim3, Linear>(&g3, x3);
            check_lanes_round_as_scalars::<Dim3, QuadraticBSpline>(&g3, x3);
            check_lanes_round_as_scalars::<Dim2, Linear>(&g2, x2);
            check_lanes_round_as_scalars::<Dim2, QuadraticBSpline>(&g2, x2);
        }
    }

    #[test]
    fn shape_weights_are_never_negative() {
        let axis = Axis::new(5, 1.0);
        for k in 0..=400 {
            let xi = 5.0 * k as f64 / 400.0;
            for s in [
                Linear::eval_1d(xi, &axis),
                QuadraticBSpline::eval_1d(xi, &axis),
                UniformGimp::eval_1d(xi, &axis),
            ] {
                assert!(s.w.iter().all(|&w| w >= -1e-15), "{xi}: {s:?}");
            }
        }
    }
}
