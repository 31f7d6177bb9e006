//! Linear hat functions (bilinear/trilinear by tensor product).

use super::{Shape, Stencil1};
use crate::dim::{Dim, Vector};
use crate::grid::Grid;
use crate::grid::{cell_index, index_to_f64, Axis};

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
        let f = xi - index_to_f64(base);
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
    /// nodes' outer products (kinematics 458 → 358 instructions a point in 3D).
    #[inline(always)]
    fn gather_with_gradient<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
    ) -> (D::Mat, D::Vec) {
        let sx = Self::eval_1d(grid.grid_coordinate(x, 0), &grid.axes[0]);
        let sy = Self::eval_1d(grid.grid_coordinate(x, 1), &grid.axes[1]);
        let (f, inv_h) = (sx.w[1], sx.dw[1]);
        let [_, stride_y, stride_z] = grid.strides;
        let mut cols = [D::Vec::ZERO; 3];
        let mut vel = D::Vec::ZERO;
        let mut row = |first: usize, w: f64, dw_dy: f64, dw_dz: f64| {
            let v0 = v(first);
            let dv = v(first + 1) - v0;
            let mean = v0 + dv * f;
            cols[0] += dv * (inv_h * w);
            cols[1] += mean * dw_dy;
            if D::N == 3 {
                cols[2] += mean * dw_dz;
            }
            vel += mean * w;
        };
        if D::N == 2 {
            for j in 0..2 {
                row((sy.base + j) * stride_y + sx.base, sy.w[j], sy.dw[j], 0.0);
            }
        } else {
            let sz = Self::eval_1d(grid.grid_coordinate(x, 2), &grid.axes[2]);
            for k in 0..2 {
                for j in 0..2 {
                    row(
                        (sz.base + k) * stride_z + (sy.base + j) * stride_y + sx.base,
                        sy.w[j] * sz.w[k],
                        sy.dw[j] * sz.w[k],
                        sy.w[j] * sz.dw[k],
                    );
                }
            }
        }
        (D::mat_from_cols(cols), vel)
    }
}
