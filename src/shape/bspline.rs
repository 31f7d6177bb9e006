//! Quadratic B-splines with a boundary modification.

use super::{Shape, Stencil1};
use crate::grid::{cell_index, index_to_f64, Axis};

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
    fn eval_1d(xi: f64, axis: &Axis) -> Stencil1 {
        let (cells, inv_h) = (axis.cells, axis.inv_h);
        // Stencil nodes b, b+1, b+2 with b = floor(xi − 1/2); local coordinate of node b+1.
        // xi ≥ 0 inside the grid, so truncation is floor except on [−1/2, 0), which is −1;
        // this avoids a libm call (no SSE4.1 rounding on the baseline x86-64 target). The
        // truncation is the cell index's, without a saturating cast's fix-ups: it sets the
        // weights of every point in every transfer, so it is on the critical path.
        let t = xi - 0.5;
        let k = cell_index(t, axis);
        let b = if t < 0.0 { -1.0 } else { index_to_f64(k) };
        let d = xi - (b + 1.0); // in [-1/2, 1/2)
        let w0 = 0.5 * (0.5 - d) * (0.5 - d);
        let w1 = 0.75 - d * d;
        let w2 = 0.5 * (0.5 + d) * (0.5 + d);
        let g0 = -(0.5 - d) * inv_h;
        let g1 = -2.0 * d * inv_h;
        let g2 = (0.5 + d) * inv_h;
        if t < 0.0 {
            // Ghost node at −1: nodes 0, 1, 2.
            Stencil1 {
                base: 0,
                w: [w1 + 2.0 * w0, w2 - w0, 0.0],
                dw: [g1 + 2.0 * g0, g2 - g0, 0.0],
            }
        } else if k + 2 > cells {
            // Ghost node at cells + 1: nodes cells − 2, cells − 1, cells.
            let base = cells - 2;
            Stencil1 {
                base,
                w: [0.0, w0 - w2, w1 + 2.0 * w2],
                dw: [0.0, g0 - g2, g1 + 2.0 * g2],
            }
        } else {
            Stencil1 {
                base: k,
                w: [w0, w1, w2],
                dw: [g0, g1, g2],
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stencil_starts_at_the_node_below_xi_minus_a_half_moved_inside_at_the_faces() {
        // b = floor(xi − 1/2) by definition; the ghost node −1 or cells + 1 is folded into the
        // grid, so the stencil starts at 0 or at cells − 2 there.
        for cells in [2usize, 3, 7] {
            let c = cells as f64;
            let mut xs = vec![0.0, 0.25, 0.5 - f64::EPSILON / 4.0, 0.5, 0.5 + f64::EPSILON];
            xs.extend([c - 0.5 - 1e-12, c - 0.5, c - 1e-12, c]);
            xs.extend((0..=100).map(|k| c * k as f64 / 100.0));
            for xi in xs {
                let b = (xi - 0.5).floor() as i64;
                let expect = b.clamp(0, cells as i64 - 2) as usize;
                let s = QuadraticBSpline::eval_1d(xi, &Axis::new(cells, 1.0));
                assert_eq!(s.base, expect, "xi = {xi}, {cells} cells");
                let d = xi - (b as f64 + 1.0);
                let interior = [
                    0.5 * (0.5 - d) * (0.5 - d),
                    0.75 - d * d,
                    0.5 * (0.5 + d) * (0.5 + d),
                ];
                if b >= 0 && b as usize + 2 <= cells {
                    assert_eq!(s.w, interior, "xi = {xi}, {cells} cells");
                }
            }
        }
    }
}
