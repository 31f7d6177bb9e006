//! Surface pressures: tractions that follow the surface as it deforms (follower loads).
//!
//! A traction given as a `pressure` p (Pa, compression positive) pushes on the surface
//! along its current inward normal, in proportion to its current size: F = −p A, with A the
//! outward area vector of the point's share of the surface (m²; m in plane strain; per
//! radian in axisymmetry). A fixed traction keeps its set-up direction and size, so on a
//! surface that heaves or tilts it gains a shear component: under a surcharge many times
//! the soil's strength (100 kPa on clay of c_u = 10 kPa beside a pushed cone), a tilt of
//! a few degrees shears the surface beyond c_u and it flows without end. A pressure,
//! normal wherever the surface turns, adds only a uniform mean stress to a surface it
//! covers, as a fluid or a surcharge does.
//!
//! The loaded points (the outermost point of each column, as for any traction) form a
//! lattice along the surface: a chain in 2D and axisymmetry, a sheet in 3D. A point's area
//! vector comes from its neighbours' current places: with the tangents t_a = (x_{+k} −
//! x_{−k})/2k along each axis across the normal, k points each way (a cell's worth, the
//! body's points per cell along that axis; fewer at the surface's edge), A = ⟂t in 2D
//! (times the current radius in axisymmetry) and A = t_a × t_b in 3D. On a flat surface at
//! set-up this is the point's share of the surface, along the face's normal: the pressure
//! starts as the traction −p n would. Reaching a cell each way, the normal is the surface's
//! at the grid's resolution: two neighbouring points that cross each other in a flow that
//! the grid cannot resolve (the surface beside a pile that drags it down) do not turn it.
//!
//! On a circular arc (the wall of a cavity, [`ArcPoint`]) the loaded points are the nearest
//! of each of the arc's pieces, up to a sub-cell from it, so the chain is not the surface: a
//! point stands for the piece of the arc at a depth d behind it along the inward normal. As
//! the chain stretches along itself by λ_t (and round the axis by λ_θ = r/r₀ in
//! axisymmetry) the layer between the points and the wall thins as a layer that keeps its
//! volume, d = d₀/(λ_t λ_θ), and the area vectors are taken along the chain of the points'
//! places on the wall, x + d n. Without it a cavity opened from a0 to 1.8 a0 carried its
//! pressure over the points' larger radius: +10 % at the start on a sub-cell of a0/10.

use crate::dim::Dim;

/// No neighbour on that side: the point is at the edge of its surface.
pub const NONE: u32 = u32::MAX;

/// The points loaded by pressures, what they need to find their area vector.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfacePressures {
    /// The loaded points' ids, ascending.
    pub ids: Vec<u32>,
    /// Each point's place in its surface, in the order of `ids`.
    pub points: Vec<SurfacePoint>,
}

/// A point that carries a pressure: its neighbours along the surface and its set-up share.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The axes across the surface's normal (the second unused in 2D).
    pub across: [usize; 2],
    /// The neighbours' ids before and after the point along each axis of `across`
    /// (`u32::MAX` at the surface's edge).
    pub links: [[u32; 2]; 2],
    /// The spacing of the lattice along each axis of `across` at set-up (m): the tangent of
    /// a point that has no neighbour along an axis.
    pub spacing: [f64; 2],
    /// How many neighbours each way a tangent reaches along each axis of `across` (≥ 1: the
    /// points a cell along it).
    pub reach: [u32; 2],
    /// The face's outward normal (unit, along a grid axis), x y z.
    pub normal: [f64; 3],
    /// The share of the surface at set-up (m², m in plane strain, per radian in
    /// axisymmetry): the size of the area vector there.
    pub share: f64,
    /// In axisymmetry, what is added to the point's radius to give its share's radius (m):
    /// half a sub-cell on a face normal to r, 0 across the axis.
    pub radius_offset: f64,
    /// On an arc, where the point stands from the arc; `None` on a face.
    pub arc: Option<ArcPoint>,
}

/// A point that carries a pressure on a circular arc: how it stands to the arc at set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArcPoint {
    /// The orientation of the chain's area vector against the outward normal (±1).
    pub sign: f64,
    /// The distance from the point to the arc along the outward normal at set-up (m, ≥ 0).
    pub depth: f64,
    /// The size of the chain's tangent at the point at set-up (m): its stretch is measured
    /// against it.
    pub chord: f64,
    /// The point's radius at set-up (m; axisymmetry: its stretch round the axis).
    pub radius: f64,
    /// The point's share of the arc (m, per radian in axisymmetry: r dl) over the size of
    /// its area vector on the wall at set-up: the chain of places on the wall zigzags
    /// round the circle by up to a sub-cell, and each point starts with its exact share.
    pub scale: f64,
}

impl SurfacePressures {
    /// Whether no traction is a pressure.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// The index of point `id` in [`Self::ids`], if it carries a pressure.
    #[inline]
    pub fn index(&self, id: u32) -> Option<usize> {
        self.ids.binary_search(&id).ok()
    }

    /// The force on point `k` (N; N/m in 2D; N/rad in axisymmetry) from the load `load` it
    /// carries at set-up (its point load: −p · share · normal, scaled by stages and load
    /// steps), with `place(id)` giving each loaded point's current place (x y z).
    pub fn force<D: Dim>(&self, k: usize, load: D::Vec, place: impl Fn(u32) -> [f64; 3]) -> D::Vec {
        let p = &self.points[k];
        let l = D::vec_to3(load);
        // −p: the load's component along the outward normal per unit of set-up share.
        let minus_p = (0..3).map(|a| l[a] * p.normal[a]).sum::<f64>() / p.share;
        let a = self.area::<D>(k, &place);
        D::vec_from(a.map(|c| c * minus_p))
    }

    /// The outward area vector of point `k`'s share of the surface now (m², m in 2D, per
    /// radian in axisymmetry), x y z, with `place(id)` the places on the surface.
    pub fn area<D: Dim>(&self, k: usize, place: impl Fn(u32) -> [f64; 3]) -> [f64; 3] {
        let p = &self.points[k];
        let x = place(self.ids[k]);
        let raw = self.raw_area::<D>(k, &place);
        let radius = if D::AXISYMMETRIC {
            x[0] + p.radius_offset
        } else {
            1.0
        };
        match &p.arc {
            Some(a) => raw.map(|c| c * a.sign * radius * a.scale),
            None => {
                // The lattice's own orientation against the outward normal at set-up (±1):
                // the axes across run in increasing order, so ⟂e_a or e_a × e_b is ± the
                // normal.
                let sign = orientation(D::N, p.across, p.normal);
                raw.map(|c| c * sign * radius)
            }
        }
    }

    /// The area vector of point `k`'s lattice cell as the chain or sheet of `place`s gives
    /// it, before orientation and radius: ⟂t in 2D, t_a × t_b in 3D, with the tangents
    /// reaching `reach` links each way.
    pub fn raw_area<D: Dim>(&self, k: usize, place: impl Fn(u32) -> [f64; 3]) -> [f64; 3] {
        let p = &self.points[k];
        // The point `reach` links away along axis j on `side` (or the last before the
        // edge) and how many links that is.
        let walk = |j: usize, side: usize| -> (u32, u32) {
            let (mut at, mut steps) = (self.ids[k], 0);
            while steps < p.reach[j] {
                let next = match self.index(at) {
                    Some(i) => self.points[i].links[j][side],
                    None => NONE,
                };
                if next == NONE {
                    break;
                }
                (at, steps) = (next, steps + 1);
            }
            (at, steps)
        };
        let tangent = |j: usize| -> [f64; 3] {
            let ((before, b), (after, a)) = (walk(j, 0), walk(j, 1));
            if a + b == 0 {
                let mut t = [0.0; 3];
                t[p.across[j]] = p.spacing[j];
                return t;
            }
            let (lo, hi) = (place(before), place(after));
            std::array::from_fn(|c| (hi[c] - lo[c]) / (a + b) as f64)
        };
        if D::N == 2 {
            let t = tangent(0);
            [-t[1], t[0], 0.0]
        } else {
            let (s, t) = (tangent(0), tangent(1));
            [
                s[1] * t[2] - s[2] * t[1],
                s[2] * t[0] - s[0] * t[2],
                s[0] * t[1] - s[1] * t[0],
            ]
        }
    }

    /// The places on the surface of the loaded points whose places are `places` (in the
    /// order of `ids`), into `out`: a point on a face is on its surface; a point on an arc
    /// stands its depth, thinned as the chain stretches, in front of itself ([`ArcPoint`]).
    pub fn surface_places<D: Dim>(&self, places: &[[f64; 3]], out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend_from_slice(places);
        let place = |id: u32| places[self.index(id).expect("a neighbour is loaded too")];
        for (k, p) in self.points.iter().enumerate() {
            let Some(a) = &p.arc else { continue };
            let raw = self.raw_area::<D>(k, place);
            let size = raw.iter().map(|c| c * c).sum::<f64>().sqrt();
            let x = places[k];
            let hoop = if D::AXISYMMETRIC && a.radius > 0.0 {
                x[0] / a.radius
            } else {
                1.0
            };
            let stretch = size / a.chord * hoop;
            if !(stretch > 0.0 && size > 0.0) {
                continue;
            }
            let d = a.depth / stretch;
            out[k] = std::array::from_fn(|c| x[c] + d * a.sign * raw[c] / size);
        }
    }
}

/// +1 when the area vector of an undeformed lattice along `across` (⟂e_a in 2D, e_a × e_b
/// in 3D) points along `normal`, −1 when against it.
fn orientation(n: usize, across: [usize; 2], normal: [f64; 3]) -> f64 {
    let mut raw = [0.0; 3];
    if n == 2 {
        // ⟂(x, y) = (−y, x).
        match across[0] {
            0 => raw[1] = 1.0,
            _ => raw[0] = -1.0,
        }
    } else {
        // e_a × e_b for a < b: +e_c for (0,1)→2 and (1,2)→0, −e_c for (0,2)→1.
        let c = 3 - across[0] - across[1];
        raw[c] = if (across[0], across[1]) == (0, 2) {
            -1.0
        } else {
            1.0
        };
    }
    if (0..3).map(|a| raw[a] * normal[a]).sum::<f64>() >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::{Dim2, Dim3, DimAxi};
    use glam::{DVec2, DVec3};

    /// A chain of three points along x at height 1, loaded on a top face (outward +y).
    fn top_chain(spacing: f64, radius_offset: f64, x0: f64) -> (SurfacePressures, Vec<[f64; 3]>) {
        chain(3, 1, spacing, radius_offset, x0)
    }

    /// A chain of `n` points along x at height 1 whose tangents reach `reach` points each
    /// way, loaded on a top face (outward +y).
    fn chain(
        n: u32,
        reach: u32,
        spacing: f64,
        radius_offset: f64,
        x0: f64,
    ) -> (SurfacePressures, Vec<[f64; 3]>) {
        let places = (0..n).map(|i| [x0 + i as f64 * spacing, 1.0, 0.0]).collect();
        let point = |i: u32| SurfacePoint {
            across: [0, 0],
            links: [
                [
                    if i == 0 { NONE } else { i - 1 },
                    if i == n - 1 { NONE } else { i + 1 },
                ],
                [NONE; 2],
            ],
            spacing: [spacing, 0.0],
            reach: [reach, reach],
            normal: [0.0, 1.0, 0.0],
            share: spacing,
            radius_offset,
            arc: None,
        };
        let sp = SurfacePressures {
            ids: (0..n).collect(),
            points: (0..n).map(point).collect(),
        };
        (sp, places)
    }

    #[test]
    fn two_points_that_cross_do_not_turn_a_pressure_that_reaches_a_cell() {
        // Five points, two a cell; the second moved past the fourth. Reaching one point
        // each way the middle point's surface would face down and the pressure pull it
        // out; reaching a cell (two points) it faces up as the chain does.
        for (reach, up) in [(1, false), (2, true)] {
            let (sp, mut x) = chain(5, reach, 0.25, 0.0, 0.125);
            x[1][0] = 0.125 + 3.5 * 0.25;
            let f = sp.force::<Dim2>(2, DVec2::new(0.0, -100.0e3 * 0.25), |id| x[id as usize]);
            assert_eq!(f.y < 0.0, up, "reach {reach}: {f}");
        }
    }

    #[test]
    fn a_flat_surface_carries_the_traction_of_its_pressure() {
        let (sp, x) = top_chain(0.25, 0.0, 0.125);
        let load = DVec2::new(0.0, -100.0e3 * 0.25);
        for k in 0..3 {
            let f = sp.force::<Dim2>(k, load, |id| x[id as usize]);
            assert_eq!(f, load, "point {k}");
        }
    }

    #[test]
    fn a_pressure_turns_with_its_surface_and_grows_with_its_length() {
        // The chain turned by 30° and stretched by half: the force turns with it, its size
        // grows by half, and it stays normal to the chain.
        let (sp, x) = top_chain(0.25, 0.0, 0.125);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let moved: Vec<[f64; 3]> = x
            .iter()
            .map(|p| {
                let (u, v) = (1.5 * p[0], 1.5 * (p[1] - 1.0));
                [c * u - s * v, s * u + c * v, 0.0]
            })
            .collect();
        let f = sp.force::<Dim2>(1, DVec2::new(0.0, -100.0e3 * 0.25), |id| moved[id as usize]);
        let expected = DVec2::new(s, -c) * (100.0e3 * 0.25 * 1.5);
        assert!(
            (f - expected).length() < 1e-9 * expected.length(),
            "{f} against {expected}"
        );
    }

    #[test]
    fn an_axisymmetric_share_grows_with_its_radius() {
        // A point on a top face at r = 2 m carries p · spacing · r per radian; moved out to
        // r = 3 m it carries half as much again.
        let (mut sp, x) = top_chain(0.25, 0.0, 1.75);
        for p in &mut sp.points {
            p.share = 0.25 * 2.0;
        }
        let load = DVec2::new(0.0, -100.0e3 * 0.25 * 2.0);
        assert_eq!(sp.force::<DimAxi>(1, load, |id| x[id as usize]), load);
        let out: Vec<[f64; 3]> = x.iter().map(|p| [p[0] + 1.0, p[1], 0.0]).collect();
        let f = sp.force::<DimAxi>(1, load, |id| out[id as usize]);
        assert_eq!(f, load * 1.5);
    }

    /// A point alone on a face with outward `normal`, its lattice along `across`.
    fn lone(across: [usize; 2], spacing: [f64; 2], normal: [f64; 3], share: f64) -> SurfacePressures {
        let point = SurfacePoint {
            across,
            links: [[NONE; 2]; 2],
            spacing,
            reach: [2, 2],
            normal,
            share,
            radius_offset: 0.0,
            arc: None,
        };
        SurfacePressures {
            ids: vec![7],
            points: vec![point],
        }
    }

    #[test]
    fn every_face_of_a_box_starts_with_its_outward_normal() {
        for axis in 0..3 {
            for outward in [-1.0, 1.0] {
                let mut normal = [0.0; 3];
                normal[axis] = outward;
                if axis < 2 {
                    let sp = lone([1 - axis; 2], [0.5, 0.0], normal, 0.5);
                    let load = DVec2::new(normal[0], normal[1]) * (-2.0e3 * 0.5);
                    let f = sp.force::<Dim2>(0, load, |_| [1.0, 1.0, 0.0]);
                    assert_eq!(f, load, "2D face {axis} {outward}");
                }
                let across: Vec<usize> = (0..3).filter(|&a| a != axis).collect();
                let sp = lone([across[0], across[1]], [0.5, 0.25], normal, 0.125);
                let load = DVec3::from_array(normal) * (-2.0e3 * 0.125);
                let f = sp.force::<Dim3>(0, load, |_| [1.0, 1.0, 1.0]);
                assert_eq!(f, load, "face {axis} {outward}");
            }
        }
    }

    /// A hole's wall of radius 1 m in plane strain, carried by a closed ring of 40 points
    /// at 1.05 m (depth 0.05 m), each its exact share of the wall, 2π/40 m, as set-up
    /// finishes them: the ring opened to 1.55 m keeps the layer's area, the wall at
    /// √(1.55² − (1.05² − 1²)) = 1.5167 m; the wall's places stand at 1.5161 m (a thin
    /// layer's d₀/λ_t), and each point carries p times its share grown by 1.516: outward,
    /// pushing the wall away from the centre.
    #[test]
    fn a_point_on_an_arc_loads_the_wall_in_front_of_it() {
        let n = 40u32;
        let (a, rho) = (1.0, 1.05);
        let dphi = std::f64::consts::TAU / n as f64;
        let ring = |r: f64| -> Vec<[f64; 3]> {
            (0..n)
                .map(|i| {
                    let phi = i as f64 * dphi;
                    [r * phi.cos(), r * phi.sin(), 0.0]
                })
                .collect()
        };
        let point = |i: u32| {
            let phi = i as f64 * dphi;
            SurfacePoint {
                across: [0, 0],
                links: [[(i + n - 1) % n, (i + 1) % n], [NONE; 2]],
                spacing: [a * dphi, 0.0],
                reach: [2, 2],
                normal: [-phi.cos(), -phi.sin(), 0.0],
                share: a * dphi,
                radius_offset: 0.0,
                arc: Some(ArcPoint {
                    sign: 1.0,
                    depth: rho - a,
                    chord: 1.0,
                    radius: rho,
                    scale: 1.0,
                }),
            }
        };
        let mut sp = SurfacePressures {
            ids: (0..n).collect(),
            points: (0..n).map(point).collect(),
        };
        // What set-up does: the chord at the points, then each share over its wall area.
        let at_rest = ring(rho);
        for k in 0..n as usize {
            let raw = sp.raw_area::<Dim2>(k, |id| at_rest[id as usize]);
            let arc = sp.points[k].arc.as_mut().unwrap();
            arc.chord = raw[0].hypot(raw[1]);
            arc.sign = if raw[0] * -at_rest[k][0] + raw[1] * -at_rest[k][1] >= 0.0 {
                1.0
            } else {
                -1.0
            };
        }
        let mut wall = Vec::new();
        sp.surface_places::<Dim2>(&at_rest, &mut wall);
        for k in 0..n as usize {
            let size = sp.area::<Dim2>(k, |id| wall[id as usize]);
            let scale = sp.points[k].share / size[0].hypot(size[1]);
            sp.points[k].arc.as_mut().unwrap().scale = scale;
        }
        assert!((wall[3][0].hypot(wall[3][1]) - a).abs() < 1e-12);
        let opened = ring(1.55);
        sp.surface_places::<Dim2>(&opened, &mut wall);
        let r = wall[5][0].hypot(wall[5][1]);
        let exact = (1.55f64 * 1.55 - (rho * rho - a * a)).sqrt();
        assert!((r - exact).abs() < 1e-3 * exact, "{r} against {exact}");
        let p = 100.0e3;
        let load = DVec2::new(point(5).normal[0], point(5).normal[1]) * (-p * a * dphi);
        let f = sp.force::<Dim2>(5, load, |id| wall[id as usize]);
        let phi = 5.0 * dphi;
        let expected = DVec2::new(phi.cos(), phi.sin()) * (p * a * dphi * r / a);
        assert!(
            (f - expected).length() < 1e-9 * expected.length(),
            "{f} against {expected}"
        );
    }
}
