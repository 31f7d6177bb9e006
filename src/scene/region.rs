//! A body's region as the scene gives it: its bounding box, what lies inside, and the grid
//! cells it touches. Shared by the checks (memory bound, masses) and set-up (filling the
//! region with points), which both sit above it.

use super::spec::{pad3, Region};

/// A point filling a body's region at set-up, whichever rank holds it.
#[derive(Clone, Copy, Debug)]
pub(super) struct BodyPoint {
    /// Its body (index into `bodies`).
    pub body: usize,
    /// Its id.
    pub id: u32,
    /// Its place at set-up (m, x y z).
    pub x: [f64; 3],
}

/// Bounding box of a region (m, x y z; z is 0..0 in 2D).
pub(crate) fn region_bounds(region: &Region, n: usize) -> ([f64; 3], [f64; 3]) {
    match region {
        Region::Box { min, max } => (pad3(min), pad3(max)),
        Region::Polygon { vertices, z } => {
            let (mut lo, mut hi) = crate::polygon::bounds(vertices);
            if n == 3 {
                let z = z.as_ref().expect("validated");
                (lo[2], hi[2]) = (z[0], z[1]);
            }
            (lo, hi)
        }
    }
}

/// Whether `x` (m) lies strictly inside the region (`n` axes).
pub(crate) fn region_contains(region: &Region, x: [f64; 3], n: usize) -> bool {
    match region {
        Region::Box { min, max } => (0..n).all(|a| x[a] > min[a] && x[a] < max[a]),
        Region::Polygon { vertices, z } => {
            crate::polygon::contains(vertices, x[0], x[1])
                && (n == 2 || z.as_ref().is_some_and(|z| x[2] > z[0] && x[2] < z[1]))
        }
    }
}

/// The cells `first..last` along one axis that the interval `lo..hi` (m) touches, clamped
/// to the grid's `cells` (origin in m, `inv_h` = 1/h in 1/m).
pub(crate) fn cell_span(lo: f64, hi: f64, origin: f64, inv_h: f64, cells: usize) -> (usize, usize) {
    let first = ((lo - origin) * inv_h).floor().max(0.0) as usize;
    let last = (((hi - origin) * inv_h).ceil().max(0.0) as usize).min(cells);
    (first, last)
}
