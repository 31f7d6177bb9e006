//! Uniform GIMP (uGIMP): each point is a box of fixed half-width l (its initial share of a
//! cell) and its weights are the linear hat averaged over the box (Bardenhagen and Kober
//! 2004), modified at grid faces like the B-spline.

use super::{fold_ghosts, Shape, Stencil1};
use crate::grid::{cell_index, index_to_f64, Axis};

/// The generalised-interpolation weight of a node at distance `r` (cell units) from a point
/// of half-width `l` ≤ ½ (cell units), and its derivative in r:
///
/// |r| < l:             S = 1 − (r² + l²)/(2l),   S' = −r/l
/// l ≤ |r| < 1 − l:     S = 1 − |r|,              S' = −sign r
/// 1 − l ≤ |r| < 1 + l: S = (1 + l − |r|)²/(4l),  S' = −sign r (1 + l − |r|)/(2l)
/// otherwise 0.
#[inline(always)]
fn weight(r: f64, l: f64) -> (f64, f64) {
    let a = r.abs();
    let sign = if r < 0.0 { -1.0 } else { 1.0 };
    if a < l {
        (1.0 - (r * r + l * l) / (2.0 * l), -r / l)
    } else if a < 1.0 - l {
        (1.0 - a, -sign)
    } else if a < 1.0 + l {
        let e = 1.0 + l - a;
        (e * e / (4.0 * l), -sign * e / (2.0 * l))
    } else {
        (0.0, 0.0)
    }
}

/// Uniform GIMP: the point's half-width is its initial share of a cell along each axis,
/// l = h/(2 n) for n points a cell side ([`Axis::particle_half_width`]), kept as the point
/// deforms. C⁰ weights with continuous gradients: a point crossing a cell face no longer
/// jumps its internal force as the linear hat's does.
///
/// The support is the three nodes nearest the point, as the B-spline's, and a ghost node
/// beyond a grid face folds onto the two nodes inside in the same way (v_ghost = 2v_0 −
/// v_1), keeping partition of unity and linear reproduction.
#[derive(Clone, Copy, Debug, Default)]
pub struct UniformGimp;

impl Shape for UniformGimp {
    const NAME: &'static str = "UniformGimp";
    const SUPPORT: usize = 3;

    #[inline(always)]
    fn eval_1d(xi: f64, axis: &Axis) -> Stencil1 {
        let (cells, inv_h, l) = (axis.cells, axis.inv_h, axis.particle_half_width);
        // Nodes b, b+1, b+2 with b = floor(xi − 1/2): a box of half-width l ≤ 1/2 around xi
        // lies within [b, b + 2].
        let t = xi - 0.5;
        let k = cell_index(t, axis);
        let b = if t < 0.0 { -1.0 } else { index_to_f64(k) };
        let (w0, g0) = weight(xi - b, l);
        let (w1, g1) = weight(xi - b - 1.0, l);
        let (w2, g2) = weight(xi - b - 2.0, l);
        // With r = xi − node, dS/dx = S'(r)/h.
        let (g0, g1, g2) = (g0 * inv_h, g1 * inv_h, g2 * inv_h);
        fold_ghosts(t, k, cells, [w0, w1, w2], [g0, g1, g2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gimp_weights_are_the_hat_averaged_over_the_point() {
        // Against a numerical average of the hat over [xi − l, xi + l] (midpoint rule).
        let mut axis = Axis::new(10, 1.0);
        for l in [0.5, 0.25, 1.0 / 6.0] {
            axis.particle_half_width = l;
            for k in 0..=200 {
                let xi = 1.0 + 8.0 * k as f64 / 200.0;
                let s = UniformGimp::eval_1d(xi, &axis);
                for j in 0..3 {
                    let node = (s.base + j) as f64;
                    let n = 4000;
                    let avg: f64 = (0..n)
                        .map(|m| {
                            let x = xi - l + 2.0 * l * (m as f64 + 0.5) / n as f64;
                            (1.0 - (x - node).abs()).max(0.0)
                        })
                        .sum::<f64>()
                        / n as f64;
                    assert!(
                        (s.w[j] - avg).abs() < 1e-6,
                        "l {l} xi {xi} node {node}: {} vs {avg}",
                        s.w[j]
                    );
                    // The derivative is the difference of the hat at the box's ends over 2l.
                    let hat = |x: f64| (1.0 - (x - node).abs()).max(0.0);
                    let d = (hat(xi + l) - hat(xi - l)) / (2.0 * l);
                    assert!(
                        (s.dw[j] - d).abs() < 1e-12,
                        "l {l} xi {xi} node {node}: {} vs {d}",
                        s.dw[j]
                    );
                }
            }
        }
    }
}
