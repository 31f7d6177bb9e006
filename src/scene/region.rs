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
        Region::Annulus { .. } => Sector::of(region).expect("an annulus").bounds(),
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
        Region::Annulus { .. } => Sector::of(region).expect("an annulus").contains(x),
    }
}

/// A checked `Region::Annulus`: a sector of the annulus about `c` between radii `r` (m),
/// from angle `a[0]` to `a[1]` (radians, anticlockwise from +x).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sector {
    c: [f64; 2],
    r: [f64; 2],
    a: [f64; 2],
}

impl Sector {
    /// The sector a region is, if it is an annulus (validated: see `validate::bodies`).
    pub(crate) fn of(region: &Region) -> Option<Sector> {
        let Region::Annulus {
            centre,
            radii,
            angles,
        } = region
        else {
            return None;
        };
        Some(Sector {
            c: [centre[0], centre[1]],
            r: [radii[0], radii[1]],
            a: [angles[0].to_radians(), angles[1].to_radians()],
        })
    }

    /// Whether the sector goes all the way round (no radial edges).
    fn closed(&self) -> bool {
        self.a[1] - self.a[0] >= std::f64::consts::TAU - 1e-12
    }

    /// The angle `phi` (radians) turned into `a[0] .. a[0] + 2π`.
    fn turned(&self, phi: f64) -> f64 {
        self.a[0] + (phi - self.a[0]).rem_euclid(std::f64::consts::TAU)
    }

    /// Whether the direction at angle `phi` (radians) lies within the sector's angles
    /// (`strict`: not on a radial edge).
    fn within(&self, phi: f64, strict: bool) -> bool {
        let t = self.turned(phi);
        self.closed()
            || if strict {
                t > self.a[0] && t < self.a[1]
            } else {
                t <= self.a[1] + 1e-12
            }
    }

    /// The point at radius `rho` and angle `phi` (m, x y z).
    fn at(&self, rho: f64, phi: f64) -> [f64; 3] {
        [self.c[0] + rho * phi.cos(), self.c[1] + rho * phi.sin(), 0.0]
    }

    /// Bounding box (m, x y z; z is 0..0): the four corners and the outer arc's extremes
    /// along the axes that lie within the angles.
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        use std::f64::consts::FRAC_PI_2;
        let (mut lo, mut hi) = (
            [f64::INFINITY, f64::INFINITY, 0.0],
            [f64::NEG_INFINITY, f64::NEG_INFINITY, 0.0],
        );
        let quarters = (0..4)
            .map(|k| k as f64 * FRAC_PI_2)
            .filter(|&q| self.within(q, false));
        let outer = quarters.map(|q| self.at(self.r[1], q));
        let corners = self.r.iter().flat_map(|&r| self.a.map(|a| self.at(r, a)));
        for x in corners.chain(outer) {
            for k in 0..2 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
        (lo, hi)
    }

    /// Whether `x` (m) lies strictly inside the sector.
    fn contains(&self, x: [f64; 3]) -> bool {
        let (dx, dy) = (x[0] - self.c[0], x[1] - self.c[1]);
        let rho = dx.hypot(dy);
        rho > self.r[0] && rho < self.r[1] && self.within(dy.atan2(dx), true)
    }

    /// The intervals (lo, hi) along axis `u` (0 or 1) that the sector holds on the line
    /// through `x` along that axis: where the line crosses the two arcs and the two radial
    /// edges, paired in order.
    pub(crate) fn segments(&self, u: usize, x: [f64; 3]) -> Vec<(f64, f64)> {
        let o = 1 - u;
        let d = x[o] - self.c[o];
        let mut at = Vec::new();
        for &r in &self.r {
            if r > d.abs() {
                let t = (r * r - d * d).sqrt();
                for s in [-t, t] {
                    let mut p = [0.0; 2];
                    (p[u], p[o]) = (s, d);
                    if self.within(p[1].atan2(p[0]), false) {
                        at.push(self.c[u] + s);
                    }
                }
            }
        }
        if !self.closed() {
            for a in self.a {
                let dir = [a.cos(), a.sin()];
                if dir[o].abs() > 1e-12 {
                    let s = d / dir[o];
                    if s >= self.r[0] && s <= self.r[1] {
                        at.push(self.c[u] + s * dir[u]);
                    }
                }
            }
        }
        at.sort_by(f64::total_cmp);
        at.chunks_exact(2).map(|c| (c[0], c[1])).collect()
    }

    /// The points filling the sector and each one's area (m²): rings `h / per[0]` apart
    /// across (as near as a whole number of rings fills the width), on each ring points
    /// about `h / per[1]` apart along it at equal angles, each point at the middle of its
    /// piece of ring with that piece's exact area.
    pub(crate) fn seeds(self, h: f64, per: [usize; 2]) -> impl Iterator<Item = ([f64; 3], f64)> + Clone {
        let width = self.r[1] - self.r[0];
        let sweep = self.a[1] - self.a[0];
        let rings = ((width * per[0] as f64 / h).round() as usize).max(1);
        let across = width / rings as f64;
        (0..rings).flat_map(move |j| {
            let rho = self.r[0] + (j as f64 + 0.5) * across;
            let along = ((rho * sweep * per[1] as f64 / h).round() as usize).max(1);
            let step = sweep / along as f64;
            // ∫ ρ dρ dφ over the piece: ρ_mid Δρ Δφ exactly.
            let area = rho * across * step;
            (0..along).map(move |k| (self.at(rho, self.a[0] + (k as f64 + 0.5) * step), area))
        })
    }
}

/// The cells `first..last` along one axis that the interval `lo..hi` (m) touches, clamped
/// to the grid's `cells` (origin in m, `inv_h` = 1/h in 1/m).
pub(crate) fn cell_span(lo: f64, hi: f64, origin: f64, inv_h: f64, cells: usize) -> (usize, usize) {
    let first = ((lo - origin) * inv_h).floor().max(0.0) as usize;
    let last = (((hi - origin) * inv_h).ceil().max(0.0) as usize).min(cells);
    (first, last)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn quarter() -> Region {
        Region::Annulus {
            centre: vec![0.0, 0.0],
            radii: vec![1.0, 6.0],
            angles: vec![0.0, 90.0],
        }
    }

    #[test]
    fn an_annulus_s_rings_fill_its_area_exactly_and_lie_inside_it() {
        let region = quarter();
        let sector = Sector::of(&region).unwrap();
        let seeds: Vec<_> = sector.seeds(0.1, [2, 2]).collect();
        let area: f64 = seeds.iter().map(|s| s.1).sum();
        let exact = PI / 4.0 * (36.0 - 1.0);
        assert!((area / exact - 1.0).abs() < 1e-12, "{area} against {exact}");
        assert!(seeds.iter().all(|s| region_contains(&region, s.0, 2)));
        // The first ring a quarter cell off the wall, every point on it at that radius.
        let first: Vec<_> = seeds.iter().filter(|s| s.0[0].hypot(s.0[1]) < 1.05).collect();
        assert!(first.iter().all(|s| (s.0[0].hypot(s.0[1]) - 1.025).abs() < 1e-12));
        // 1.025 m × 90° at 0.05 m a point: 32 of them.
        assert_eq!(first.len(), 32);
    }

    #[test]
    fn an_annulus_s_bounds_take_in_its_outer_arc_across_the_axes() {
        let (lo, hi) = region_bounds(&quarter(), 2);
        assert!(lo[0].abs() < 1e-12 && lo[1].abs() < 1e-12);
        assert!((hi[0] - 6.0).abs() < 1e-12 && (hi[1] - 6.0).abs() < 1e-12);
        // From 45° to 135°: the top of the outer circle, the inner corners below it.
        let arch = Region::Annulus {
            centre: vec![5.0, 0.0],
            radii: vec![1.0, 2.0],
            angles: vec![45.0, 135.0],
        };
        let (lo, hi) = region_bounds(&arch, 2);
        let s = 2f64.sqrt();
        assert!((lo[0] - (5.0 - s)).abs() < 1e-12 && (hi[0] - (5.0 + s)).abs() < 1e-12);
        assert!((lo[1] - 0.5 * s).abs() < 1e-12 && (hi[1] - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_vertical_through_an_annulus_crosses_its_arcs_and_edges() {
        let sector = Sector::of(&quarter()).unwrap();
        // x = 0.5: from the inner arc to the outer one.
        let at = sector.segments(1, [0.5, 3.0, 0.0]);
        assert_eq!(at.len(), 1);
        assert!((at[0].0 - 0.75f64.sqrt()).abs() < 1e-12 && (at[0].1 - 35.75f64.sqrt()).abs() < 1e-12);
        // x = 3: from the radial edge at y = 0 to the outer arc.
        let at = sector.segments(1, [3.0, 1.0, 0.0]);
        assert_eq!(at.len(), 1);
        assert!(at[0].0.abs() < 1e-12 && (at[0].1 - 27f64.sqrt()).abs() < 1e-12);
        // A whole ring: a vertical through its hole meets it twice.
        let ring = Sector::of(&Region::Annulus {
            centre: vec![0.0, 0.0],
            radii: vec![1.0, 2.0],
            angles: vec![0.0, 360.0],
        })
        .unwrap();
        let at = ring.segments(1, [0.0, 0.0, 0.0]);
        assert_eq!(at, vec![(-2.0, -1.0), (1.0, 2.0)]);
    }
}
