//! Quadratic B-splines with a boundary modification.

use super::{fold_ghosts, for_each_row, from_lanes, in_lanes, GradientSum, Shape, Stencil1, StressColumns};
use crate::dim::Dim;
use crate::grid::{cell_index, index_to_f64, Axis, Grid};
use crate::infra::lanes::{F64x4, Lanes};
use crate::tensor::Sym3;

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
        // truncation is the cell index's, without a saturating cast's fix-ups.
        let t = xi - 0.5;
        let k = cell_index(t, axis);
        let d = offset_from_centre(xi, t, k); // in [-1/2, 1/2)
        let w0 = 0.5 * (0.5 - d) * (0.5 - d);
        let w1 = 0.75 - d * d;
        let w2 = 0.5 * (0.5 + d) * (0.5 + d);
        let g0 = -(0.5 - d) * inv_h;
        let g1 = -2.0 * d * inv_h;
        let g2 = (0.5 + d) * inv_h;
        fold_ghosts(t, k, cells, [w0, w1, w2], [g0, g1, g2])
    }

    /// Row by row along x: with v̄ = Σ_i w_i v_i and v' = Σ_i w_i' v_i over a row's three
    /// nodes, the row adds v' w_r to the x column of L, v̄ ∂w_r/∂y and v̄ ∂w_r/∂z to the
    /// others and v̄ w_r to the velocity. Node by node, each node formed its own gradient
    /// and outer product; this is a third of the multiply-adds in 3D (docs/performance.md),
    /// equal to them up to round-off.
    #[inline(always)]
    fn gather_with_gradient_visiting<D: Dim>(
        grid: &Grid<D>,
        x: D::Vec,
        v: impl Fn(usize) -> D::Vec,
        mut visit: impl FnMut(&Stencil1, usize, f64),
    ) -> (D::Mat, D::Vec) {
        let mut acc = GradientSum::default();
        let k = F64x4::splat;
        for_each_row::<D, Self>(grid, x, |sx, first, w, dw_dy, dw_dz| {
            visit(sx, first, w);
            let (v0, v1, v2) = (
                in_lanes::<D>(v(first)),
                in_lanes::<D>(v(first + 1)),
                in_lanes::<D>(v(first + 2)),
            );
            let mean = Lanes::madd(v2, k(sx.w[2]), Lanes::madd(v1, k(sx.w[1]), v0 * k(sx.w[0])));
            let slope = Lanes::madd(v2, k(sx.dw[2]), Lanes::madd(v1, k(sx.dw[1]), v0 * k(sx.dw[0])));
            acc.add_row::<D>((slope, w), mean, (w, dw_dy, dw_dz));
        });
        acc.finish::<D>()
    }

    /// Row by row along x, as the gather: with P = −Vσ, node i of a row gets w_i (w_r m),
    /// w_i (w_r q) and w_i' a + w_i b, where a = P_x w_r and b = P_y ∂w_r/∂y + P_z ∂w_r/∂z:
    /// no node forms its own gradient or σ·∇w (docs/performance.md).
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
        let p = StressColumns::of(s, neg_vol);
        let (px, q, k) = (p.column(0), in_lanes::<D>(q), F64x4::splat);
        for_each_row::<D, Self>(grid, x, |sx, first, w, dw_dy, dw_dz| {
            let (a, b) = (px * k(w), p.dot_yz::<D>(dw_dy, dw_dz));
            let (mr, qr) = (m * w, q * k(w));
            for i in 0..3 {
                let f = Lanes::madd(b, k(sx.w[i]), a * k(sx.dw[i]));
                add(
                    first + i,
                    mr * sx.w[i],
                    from_lanes::<D>(qr * k(sx.w[i])),
                    from_lanes::<D>(f),
                );
            }
        });
    }
}

/// xi − (b + 1): the local coordinate of a point at grid coordinate `xi` from the centre
/// node b + 1 of its stencil, given t = xi − 1/2 and k = `cell_index(t)` (b = k, or −1 for
/// t < 0).
///
/// With SSE4.1 the centre is floor(xi + 1/2), one rounding instruction, rather than k
/// converted back: the weights of every point wait on it, and k then only picks the nodes, off
/// that path. The two agree for 1/2 ≤ xi ≤ cells (there xi − 1/2 is exact and xi + 1/2
/// cannot round across an integer), so the bits are the same either way; below 1/2 the centre
/// is node 0 (xi + 1/2 rounds up to 1 for the largest double below 1/2).
#[inline(always)]
fn offset_from_centre(xi: f64, t: f64, k: usize) -> f64 {
    let centre = if t < 0.0 {
        0.0
    } else if cfg!(target_feature = "sse4.1") {
        (xi + 0.5).floor()
    } else {
        index_to_f64(k) + 1.0
    };
    xi - centre
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_offset_from_the_centre_node_is_xi_less_floor_of_xi_minus_a_half_plus_one() {
        // By definition d = xi − (floor(xi − 1/2) + 1), with the ghost node's centre 0 below
        // 1/2; checked bit for bit on whichever path this build takes, within 256 doubles of
        // every integer, half and quarter up to 180 and at 10⁶ pseudo-random coordinates.
        let axis = Axis::new(180, 1.0);
        let check = |xi: f64| {
            let t = xi - 0.5;
            let expect = if t < 0.0 { xi } else { xi - (t.floor() + 1.0) };
            let d = offset_from_centre(xi, t, cell_index(t, &axis));
            assert_eq!(d.to_bits(), expect.to_bits(), "xi = {xi:e}");
        };
        for n in 0..=180 {
            for fraction in [0.0, 0.25, 0.5, 0.75] {
                let base = (n as f64 + fraction).to_bits() as i64;
                for step in -256..=256 {
                    let xi = f64::from_bits((base + step) as u64);
                    if (0.0..=180.0).contains(&xi) {
                        check(xi);
                    }
                }
            }
        }
        let mut seed = 7;
        for _ in 0..1_000_000 {
            check(90.0 * (1.0 + crate::testing::uniform(&mut seed)));
        }
    }

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
