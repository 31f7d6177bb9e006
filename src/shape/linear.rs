//! Linear hat functions (bilinear/trilinear by tensor product).

use super::{for_each_row, from_lanes, in_lanes, GradientSum, Shape, Stencil1, StressColumns};
use crate::dim::Dim;
use crate::grid::{cell_floor, cell_index, Axis, Grid};
use crate::infra::lanes::{F64x4, Lanes};
use crate::tensor::Sym3;

/// Linear hat function: w = 1 − |x − x_i|/h on the two nodes of the cell holding the point.
#[derive(Clone, Copy, Debug, Default)]
pub struct Linear;

impl Shape for Linear {
    const NAME: &'static str = "Linear";
    const SUPPORT: usize = 2;

    #[inline(always)]
    fn eval_1d(xi: f64, axis: &Axis) -> Stencil1 {
        // A point on the upper face belongs to the last cell, so it never reaches a node
        // beyond the grid.
        let base = cell_index(xi, axis);
        let f = xi - cell_floor(xi, axis);
        Stencil1 {
            base,
            w: [1.0 - f, f, 0.0],
            dw: [-axis.inv_h, axis.inv_h, 0.0],
        }
    }

    /// Row by row along x. The two nodes of a row share the y-z weight w_r and its
    /// derivatives, and their x-weights are 1 − f and f with slopes ∓1/h, so with
    /// v̄ = v0 + f (v1 − v0) the row adds (v1 − v0) w_r/h to the x column of L, v̄ ∂w_r/∂y and
    /// v̄ ∂w_r/∂z to the others and v̄ w_r to the velocity: about half the arithmetic of two
    /// nodes' outer products (docs/performance.md).
    #[inline(always)]
    fn gather_with_gradient_visiting<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
        mut visit: impl FnMut(&Stencil1, usize, f64),
    ) -> (D::Mat, D::Vec) {
        let mut acc = GradientSum::default();
        for_each_row::<D, Self>(grid, x, |sx, first, w, dw_dy, dw_dz| {
            visit(sx, first, w);
            let v0 = in_lanes::<D>(v(first));
            let dv = in_lanes::<D>(v(first + 1)) - v0;
            let mean = Lanes::madd(dv, F64x4::splat(sx.w[1]), v0);
            acc.add_row::<D>((dv, sx.dw[1] * w), mean, (w, dw_dy, dw_dz));
        });
        acc.finish::<D>()
    }

    /// Row by row along x, as the gather. A row's nodes share w_r, so with P = −Vσ the far
    /// node gets f w_r m, f w_r q and a + f b, where a = P_x w_r/h and b = P_y ∂w_r/∂y +
    /// P_z ∂w_r/∂z, and the near node the row's totals w_r m, w_r q and b less those (the
    /// x-slopes of a row cancel). About 45 flops a row against 66 for two nodes.
    #[inline(always)]
    fn scatter_with_gradient<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        m: f64,
        q: D::Vec,
        s: &Sym3,
        neg_vol: f64,
        mut add: impl FnMut(usize, f64, D::Vec, D::Vec),
    ) {
        // Columns of −Vσ and the momentum in lanes (see `in_lanes`; only the first N
        // entries count in 2D).
        let p = StressColumns::of(s, neg_vol);
        let (px, q, k) = (p.column(0), in_lanes::<D>(q), F64x4::splat);
        for_each_row::<D, Self>(grid, x, |sx, first, w, dw_dy, dw_dz| {
            let f = sx.w[1];
            let (a, b) = (px * k(sx.dw[1] * w), p.dot_yz::<D>(dw_dy, dw_dz));
            let (mr, qr) = (m * w, q * k(w));
            let (m1, q1, f1) = (mr * f, qr * k(f), Lanes::madd(b, k(f), a));
            add(first, mr - m1, from_lanes::<D>(qr - q1), from_lanes::<D>(b - f1));
            add(first + 1, m1, from_lanes::<D>(q1), from_lanes::<D>(f1));
        });
    }
}
