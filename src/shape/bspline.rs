//! Quadratic B-splines with a boundary modification.

use super::{Shape, Stencil1};

/// Quadratic B-spline centred on each node (support 3h, C¹ continuous).
///
/// Near a grid face the standard stencil would need a ghost node outside the grid. The ghost
/// node's value is taken as the linear extrapolation of the two nodes inside
/// (v_ghost = 2v_0 − v_1), which folds its weight onto them: N_0 += 2N_ghost,
/// N_1 −= N_ghost. This keeps partition of unity and linear reproduction, keeps the weights
/// non-negative, and makes the basis linear within half a cell of the face (where it meets
/// the interior B-spline with matching value and slope).
#[derive(Clone, Copy, Debug, Default)]
pub struct QuadraticBSpline;

impl Shape for QuadraticBSpline {
    const NAME: &'static str = "QuadraticBSpline";
    const SUPPORT: usize = 3;

    #[inline(always)]
    fn eval_1d(xi: f64, cells: usize, inv_h: f64) -> Stencil1 {
        // Stencil nodes b, b+1, b+2 with b = floor(xi − 1/2); local coordinate of node b+1.
        // xi ≥ 0 inside the grid, so truncation is floor except on [−1/2, 0), which is −1;
        // this avoids a libm call (no SSE4.1 rounding on the baseline x86-64 target).
        let t = xi - 0.5;
        let b = if t < 0.0 { -1.0 } else { (t as i64) as f64 };
        let d = xi - (b + 1.0); // in [-1/2, 1/2)
        let w0 = 0.5 * (0.5 - d) * (0.5 - d);
        let w1 = 0.75 - d * d;
        let w2 = 0.5 * (0.5 + d) * (0.5 + d);
        let g0 = -(0.5 - d) * inv_h;
        let g1 = -2.0 * d * inv_h;
        let g2 = (0.5 + d) * inv_h;
        if b < 0.0 {
            // Ghost node at −1: nodes 0, 1, 2.
            Stencil1 {
                base: 0,
                w: [w1 + 2.0 * w0, w2 - w0, 0.0],
                dw: [g1 + 2.0 * g0, g2 - g0, 0.0],
            }
        } else if b as usize + 2 > cells {
            // Ghost node at cells + 1: nodes cells − 2, cells − 1, cells.
            let base = cells - 2;
            Stencil1 {
                base,
                w: [0.0, w0 - w2, w1 + 2.0 * w2],
                dw: [0.0, g0 - g2, g1 + 2.0 * g2],
            }
        } else {
            Stencil1 {
                base: b as usize,
                w: [w0, w1, w2],
                dw: [g0, g1, g2],
            }
        }
    }
}
