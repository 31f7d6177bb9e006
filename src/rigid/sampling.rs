//! A body's surface samples within its reach: the samples of [`Geometry::samples`] that can
//! come inside the grid, found without walking the rest.
//!
//! A shape's samples lie on a fixed lattice of its surface (equal pieces of at most the
//! spacing along each edge, ring or face), so a sample keeps its place whatever the reach.
//! Here each lattice is cut to the index ranges whose places fall in the reach box, so a
//! circle of radius 1e9 m or a polygon far wider than the grid costs what its part in the
//! grid costs (a whole circle of 1e9 m at 0.1 m is 6e10 samples). The samples inside the
//! box come in the same order as the whole shape's, so a body that lies in the grid has the
//! same samples, in the same order, as before any cut.

use super::geometry::{Geometry, Sample};
use super::reach::Reach;
use std::f64::consts::PI;

/// The number of equal pieces of at most `spacing` that cut `length` (at least one).
pub(crate) fn pieces(length: f64, spacing: f64) -> usize {
    (length / spacing).ceil().max(1.0) as usize
}

/// The indices j of k pieces of 0..1 whose middles (j + 0.5)/k lie in t0..t1.
fn middles(k: usize, t0: f64, t1: f64) -> std::ops::Range<usize> {
    let kf = k as f64;
    let first = (t0 * kf - 0.5).ceil().max(0.0);
    let last = (t1 * kf - 0.5).floor().min(kf - 1.0);
    if first.is_nan() || last.is_nan() || first > last {
        return 0..0;
    }
    first as usize..last as usize + 1
}

/// The indices of a circle's k pieces (centre `c`, radius `r` in the plane of axes `u`,
/// `w`; middles at angles 2π(j + 0.5)/k from `u`) whose middles may lie in the reach box
/// across those axes, in increasing order.
fn arc(c: [f64; 2], r: f64, k: usize, lo: [f64; 2], hi: [f64; 2]) -> Vec<usize> {
    // Angles (as fractions of the turn) where the circle crosses the box's sides.
    let mut cuts = vec![0.0, 1.0];
    for axis in 0..2 {
        for side in [lo[axis], hi[axis]] {
            let s = (side - c[axis]) / r;
            if s.is_finite() && s.abs() <= 1.0 {
                let t = if axis == 0 { s.acos() } else { s.asin() };
                let both = if axis == 0 { [t, -t] } else { [t, PI - t] };
                cuts.extend(both.map(|t| (t / (2.0 * PI)).rem_euclid(1.0)));
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    let mut out = Vec::new();
    let inside = |t: f64| {
        let (x, y) = (c[0] + r * (2.0 * PI * t).cos(), c[1] + r * (2.0 * PI * t).sin());
        x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1]
    };
    for w in cuts.windows(2) {
        // A piece of the circle between two crossings is wholly in or out; its ends are
        // taken with it (a middle exactly on a side is checked again by the caller).
        if w[1] > w[0] && inside(0.5 * (w[0] + w[1])) {
            let pad = 1.0 / k as f64;
            for j in middles(k, w[0] - pad, w[1] + pad) {
                if out.last().is_none_or(|&l| j > l) {
                    out.push(j);
                }
            }
        }
    }
    out
}

impl Geometry {
    /// Points of the surface at most `spacing` (m) apart, at the middles of equal pieces (a
    /// polygon's corners stand between the samples of its two edges), those within `reach`.
    pub fn samples(&self, spacing: f64, reach: &Reach) -> Vec<Sample> {
        let mut out = match self {
            Geometry::Circle { centre, radius } => circle(centre, *radius, spacing, reach),
            Geometry::Polygon { vertices } => polygon(vertices, spacing, reach),
            Geometry::Sphere { centre, radius } => sphere(centre, *radius, spacing, reach),
            Geometry::Box { min, max } => cuboid(min, max, spacing, reach),
            Geometry::Cylinder {
                base,
                axis,
                length,
                radius,
            } => cylinder(base, *axis, *length, *radius, spacing, reach),
            Geometry::Mesh { .. } => self
                .mesh()
                .samples(spacing, reach)
                .into_iter()
                .map(|(x, normal, measure)| Sample { x, normal, measure })
                .collect(),
        };
        out.retain(|s| reach.holds(s.x));
        out
    }
}

fn point(v: &[f64]) -> [f64; 3] {
    std::array::from_fn(|a| v.get(a).copied().unwrap_or(0.0))
}

fn circle(centre: &[f64], radius: f64, spacing: f64, reach: &Reach) -> Vec<Sample> {
    let c = point(centre);
    let k = pieces(2.0 * PI * radius, spacing);
    arc(
        [c[0], c[1]],
        radius,
        k,
        [reach.lo[0], reach.lo[1]],
        [reach.hi[0], reach.hi[1]],
    )
    .into_iter()
    .map(|i| {
        let t = 2.0 * PI * (i as f64 + 0.5) / k as f64;
        let n = [t.cos(), t.sin(), 0.0];
        Sample {
            x: [c[0] + radius * n[0], c[1] + radius * n[1], 0.0],
            normal: n,
            measure: 2.0 * PI * radius / k as f64,
        }
    })
    .collect()
}

fn polygon(vertices: &[Vec<f64>], spacing: f64, reach: &Reach) -> Vec<Sample> {
    let ccw = crate::polygon::signed_area(vertices) > 0.0;
    let mut out = Vec::new();
    for i in 0..vertices.len() {
        let (a, b) = (&vertices[i], &vertices[(i + 1) % vertices.len()]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let l = (e[0] * e[0] + e[1] * e[1]).sqrt();
        let out_n = if ccw {
            [e[1] / l, -e[0] / l, 0.0]
        } else {
            [-e[1] / l, e[0] / l, 0.0]
        };
        let k = pieces(l, spacing);
        // The part of the edge in the reach box (Liang & Barsky), widened by a piece.
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for axis in 0..2 {
            if e[axis] == 0.0 {
                if a[axis] < reach.lo[axis] || a[axis] > reach.hi[axis] {
                    t1 = -1.0;
                }
                continue;
            }
            let (s0, s1) = (
                (reach.lo[axis] - a[axis]) / e[axis],
                (reach.hi[axis] - a[axis]) / e[axis],
            );
            t0 = t0.max(s0.min(s1));
            t1 = t1.min(s0.max(s1));
        }
        let pad = 1.0 / k as f64;
        for j in middles(k, t0 - pad, t1 + pad) {
            let t = (j as f64 + 0.5) / k as f64;
            out.push(Sample {
                x: [a[0] + t * e[0], a[1] + t * e[1], 0.0],
                normal: out_n,
                measure: l / k as f64,
            });
        }
    }
    out
}

/// Rings of equal latitude steps about z, each cut in pieces of about `spacing`.
fn sphere(centre: &[f64], radius: f64, spacing: f64, reach: &Reach) -> Vec<Sample> {
    let c = point(centre);
    let rings = pieces(PI * radius, spacing);
    // The polar angles whose height lies in the reach, as fractions of π, widened a ring.
    let cos = |z: f64| ((z - c[2]) / radius).clamp(-1.0, 1.0);
    let (t0, t1) = (cos(reach.hi[2]).acos() / PI, cos(reach.lo[2]).acos() / PI);
    let pad = 1.0 / rings as f64;
    let mut out = Vec::new();
    for i in middles(rings, t0 - pad, t1 + pad) {
        let (a0, a1) = (PI * i as f64 / rings as f64, PI * (i + 1) as f64 / rings as f64);
        let t = 0.5 * (a0 + a1);
        let band = 2.0 * PI * radius * radius * (a0.cos() - a1.cos());
        let rho = radius * t.sin();
        let k = pieces(2.0 * PI * rho, spacing);
        for j in arc(
            [c[0], c[1]],
            rho,
            k,
            [reach.lo[0], reach.lo[1]],
            [reach.hi[0], reach.hi[1]],
        ) {
            let f = 2.0 * PI * (j as f64 + 0.5) / k as f64;
            let n = [t.sin() * f.cos(), t.sin() * f.sin(), t.cos()];
            out.push(Sample {
                x: std::array::from_fn(|a| c[a] + radius * n[a]),
                normal: n,
                measure: band / k as f64,
            });
        }
    }
    out
}

/// A box's samples: each face cut into pieces of at most `spacing` a side.
fn cuboid(min: &[f64], max: &[f64], spacing: f64, reach: &Reach) -> Vec<Sample> {
    let (lo, hi) = (point(min), point(max));
    let n = min.len();
    let mut out = Vec::new();
    for axis in 0..n {
        for (side, at) in [(-1.0, lo[axis]), (1.0, hi[axis])] {
            if at < reach.lo[axis] || at > reach.hi[axis] {
                continue;
            }
            let others: Vec<usize> = (0..n).filter(|&a| a != axis).collect();
            let counts: Vec<usize> = others.iter().map(|&a| pieces(hi[a] - lo[a], spacing)).collect();
            let total: f64 = counts.iter().map(|&k| k as f64).product();
            let measure: f64 = others.iter().map(|&a| hi[a] - lo[a]).product::<f64>() / total;
            // Each other axis's pieces in the reach; the first varies fastest.
            let ranges: Vec<std::ops::Range<usize>> = others
                .iter()
                .zip(&counts)
                .map(|(&a, &k)| {
                    let span = hi[a] - lo[a];
                    let pad = 1.0 / k as f64;
                    middles(
                        k,
                        (reach.lo[a] - lo[a]) / span - pad,
                        (reach.hi[a] - lo[a]) / span + pad,
                    )
                })
                .collect();
            let outer = ranges.get(1).cloned().unwrap_or(0..1);
            for q in outer {
                for p in ranges[0].clone() {
                    let mut x = [0.0; 3];
                    x[axis] = at;
                    for (&a, (&j, &k)) in others.iter().zip([p, q].iter().zip(&counts)) {
                        x[a] = lo[a] + (hi[a] - lo[a]) * (j as f64 + 0.5) / k as f64;
                    }
                    let mut normal = [0.0; 3];
                    normal[axis] = side;
                    out.push(Sample { x, normal, measure });
                }
            }
        }
    }
    out
}

/// A cylinder's samples: its side in pieces of at most `spacing`, its end caps in rings.
fn cylinder(base: &[f64], axis: usize, length: f64, radius: f64, spacing: f64, reach: &Reach) -> Vec<Sample> {
    let b = point(base);
    let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
    let (across_lo, across_hi) = ([reach.lo[u], reach.lo[w]], [reach.hi[u], reach.hi[w]]);
    let axis_at = [b[u], b[w]];
    let mut out = Vec::new();
    let (around, along) = (pieces(2.0 * PI * radius, spacing), pieces(length, spacing));
    let pad = 1.0 / along as f64;
    let rows = middles(
        along,
        (reach.lo[axis] - b[axis]) / length - pad,
        (reach.hi[axis] - b[axis]) / length + pad,
    );
    for i in arc(axis_at, radius, around, across_lo, across_hi) {
        let f = 2.0 * PI * (i as f64 + 0.5) / around as f64;
        for j in rows.clone() {
            let mut x = b;
            x[axis] += length * (j as f64 + 0.5) / along as f64;
            x[u] += radius * f.cos();
            x[w] += radius * f.sin();
            let mut normal = [0.0; 3];
            normal[u] = f.cos();
            normal[w] = f.sin();
            out.push(Sample {
                x,
                normal,
                measure: 2.0 * PI * radius * length / (around * along) as f64,
            });
        }
    }
    // The end caps: rings of equal radial steps, those whose circle meets the reach.
    let rings = pieces(radius, spacing);
    // The distances from the axis to the nearest and farthest points of the reach across.
    let (nearest, farthest) = (0..2).fold((0.0f64, 0.0f64), |(near, far), k| {
        let (below, above) = (axis_at[k] - across_lo[k], across_hi[k] - axis_at[k]);
        let gap = (-below).max(-above).max(0.0);
        (near + gap * gap, far + below.abs().max(above.abs()).powi(2))
    });
    let (nearest, farthest) = (nearest.sqrt(), farthest.sqrt());
    let pad = 1.0 / rings as f64;
    let ring_range = middles(rings, nearest / radius - pad, farthest / radius + pad);
    for (side, at) in [(-1.0, b[axis]), (1.0, b[axis] + length)] {
        if at < reach.lo[axis] || at > reach.hi[axis] {
            continue;
        }
        for i in ring_range.clone() {
            let (r0, r1) = (
                radius * i as f64 / rings as f64,
                radius * (i + 1) as f64 / rings as f64,
            );
            let r = 0.5 * (r0 + r1);
            let k = pieces(2.0 * PI * r, spacing);
            for j in arc(axis_at, r, k, across_lo, across_hi) {
                let f = 2.0 * PI * (j as f64 + 0.5) / k as f64;
                let mut x = b;
                x[axis] = at;
                x[u] += r * f.cos();
                x[w] += r * f.sin();
                let mut normal = [0.0; 3];
                normal[axis] = side;
                out.push(Sample {
                    x,
                    normal,
                    measure: PI * (r1 * r1 - r0 * r0) / k as f64,
                });
            }
        }
    }
    out
}
