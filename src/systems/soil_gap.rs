//! How far the soil's surface stands off a rigid body's surface at each contact, so that
//! soil that has moved off a body may come back to it (a body with `soil_surface:
//! Points`).
//!
//! A contact holds grid velocities: a surface sample the mean velocity of the nodes round
//! it, a node inside the body its own. Both hold soil whose points lie up to the shape
//! functions' reach away, whether or not that soil touches the body. Where the soil has
//! moved off the body and would come back (the soil under a footing pushed fast runs on
//! when the footing stops, and springs back once the relaxation has taken its speed), a
//! constraint that only knows velocities keeps it off, and the static state it relaxes
//! to keeps the soil where its inertia took it. An elastic footing pushed 1 mm at 0.1 m/s
//! stood 29 % stiffer than pushed at 0.001 m/s, the soil under it 0.15 mm further down
//! than the footing (docs/verification.md, "The rigid footing under load control").
//!
//! Each step the points near each body give the gap between their own surface and the
//! body's,
//!
//! d_p = φ(x_p) − r_p,
//!
//! φ the distance of the point from the body's surface (negative inside) and r_p half the
//! point's size, V_p^(1/n)/2 (V_p per radian over the point's radius when axisymmetric):
//! the surface of a soil whose points lie against the body is at d_p = 0. A constraint
//! standing at x_c with outward normal n takes as its gap g the least d_p of the points in
//! front of it: within half a cell of the line x_c + t n, at −h < t ≤ [`DEPTH`] h, the
//! points its nodes' velocities move. The soil there may approach the body at up to
//! g/Δt, which closes the gap in a step; once it touches (g ≤ 0) it is held as before. A
//! constraint with no point in front of it has no gap, and holds as before.
//!
//! It is a body's choice, not the default: on the penetrometers the points' sizes stand
//! for the soil's surface poorly where the flow has spread them, and the gaps found there
//! are not all real (at the cone's apex at D/4, 3.5 cm, a seventh of a cell, beside soil
//! that the cone pushes), so their static states scatter more (docs/verification.md,
//! "The rigid footing under load control"). A body with `Nodes` is not looked at, and
//! its contacts keep their bits.
//!
//! The least d_p of a set of points does not depend on the order they are visited in:
//! the same on any thread count, and over several ranks each rank takes the least of its
//! own points and one reduction the least of all.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::infra::columns::{col, points_with};
use crate::rigid::SoilSurface;

/// How far in front of a constraint its soil's points are looked for (cells): the nodes a
/// sample holds lie within 1.5 cells of it (quadratic B-splines), and a point moves with
/// the nodes within 1.5 cells of it.
pub const DEPTH: f64 = 1.5;

/// How far beside the line x_c + t n a point counts as in front of the constraint (cells).
pub const BESIDE: f64 = 0.5;

/// Per body, the points near it and their gaps d_p, by cell of a box round the body.
#[derive(Debug, Default)]
pub struct SoilGap {
    fronts: Vec<Front>,
}

/// The points near one body, sorted by the cell of a box round it they lie in.
#[derive(Debug, Default)]
struct Front {
    /// Axes of the scene's space (2 or 3).
    n: usize,
    /// Lower corner of the box (m).
    lo: [f64; 3],
    /// Cells of the box along each axis (1 along an axis the dimension lacks).
    cells: [usize; 3],
    /// 1 / cell size (1/m).
    inv_h: f64,
    /// Per cell, where its points start in `points` (one entry more than cells).
    start: Vec<u32>,
    /// Place (m) and gap d_p (m) of each point, cell by cell.
    points: Vec<([f64; 3], f64)>,
    /// Scratch kept between steps: the points found (cell, place, gap), in the order
    /// found.
    found: Vec<(usize, [f64; 3], f64)>,
    /// Scratch kept between steps: each cell's next free place in `points` while the
    /// found points are sorted into it.
    next: Vec<u32>,
}

impl Front {
    /// The cell of the box `x` lies in, `None` outside it.
    fn cell(&self, x: [f64; 3]) -> Option<[usize; 3]> {
        let mut c = [0; 3];
        for a in 0..self.n {
            let t = ((x[a] - self.lo[a]) * self.inv_h).floor();
            if t < 0.0 || t >= self.cells[a] as f64 {
                return None;
            }
            c[a] = t as usize;
        }
        Some(c)
    }

    fn index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.cells[1] + c[1]) * self.cells[0] + c[0]
    }
}

impl SoilGap {
    /// Whether some body of the scene takes the soil's surface from its points.
    pub fn wanted<D: Dim>(ctx: &Context<D>) -> bool {
        (ctx.model.bodies.iter()).any(|b| b.spec.soil_surface == SoilSurface::Points)
    }

    /// Finds, for every body with `soil_surface: Points` at its current place, the points
    /// within the reach of its constraints and their gaps d_p (this rank's points); none
    /// for the others.
    pub fn gather<D: Dim>(&mut self, ctx: &Context<D>) {
        let bodies = &ctx.model.bodies;
        self.fronts.resize_with(bodies.len(), Front::default);
        let h = ctx.grid.cell_size;
        // A constraint inside the body lies within DEPTH cells of the soil it holds, and
        // looks DEPTH cells in front of it: the box reaches DEPTH + 1 cells past the body.
        let margin = (DEPTH + 1.0) * h;
        for (b, body) in bodies.iter().enumerate() {
            let f = &mut self.fronts[b];
            f.points.clear();
            if body.spec.soil_surface != SoilSurface::Points {
                f.start.clear();
                continue;
            }
            let offset = ctx.state.control.bodies[b].offset;
            let (lo, hi) = body.spec.bounds(D::N);
            (f.n, f.inv_h) = (D::N, 1.0 / h);
            for a in 0..3 {
                if a < D::N {
                    f.lo[a] = lo[a] + offset[a] - margin;
                    f.cells[a] = ((hi[a] - lo[a] + 2.0 * margin) / h).ceil() as usize + 1;
                } else {
                    (f.lo[a], f.cells[a]) = (0.0, 1);
                }
            }
            f.found.clear();
            for arch in points_with::<Volume>(&ctx.world) {
                let (xs, vs) = (col::<Position<D::Vec>>(arch), col::<Volume>(arch));
                for (x, v) in xs.iter().zip(vs.iter()) {
                    let x3 = D::vec_to3(x.0);
                    let Some(c) = f.cell(x3) else { continue };
                    let at: [f64; 3] = std::array::from_fn(|a| x3[a] - offset[a]);
                    let phi = body.spec.distance(at, D::N).0;
                    if phi > margin {
                        continue;
                    }
                    // The point's size: its volume, per radian over its radius when
                    // axisymmetric (as volumes are), to the 1/n.
                    let size = if D::AXISYMMETRIC { v.0 / x3[0] } else { v.0 };
                    let r = 0.5 * size.powf(1.0 / D::N as f64);
                    let k = f.index(c);
                    f.found.push((k, x3, phi - r));
                }
            }
            // By cell, in the order found within each (a counting sort).
            let count = f.cells.iter().product::<usize>();
            f.start.clear();
            f.start.resize(count + 1, 0);
            for &(c, _, _) in &f.found {
                f.start[c + 1] += 1;
            }
            for c in 0..count {
                f.start[c + 1] += f.start[c];
            }
            f.next.clone_from(&f.start);
            f.points.resize(f.found.len(), ([0.0; 3], 0.0));
            for &(c, x, d) in &f.found {
                f.points[f.next[c] as usize] = (x, d);
                f.next[c] += 1;
            }
        }
    }

    /// The least gap d_p (m) of this rank's points in front of a constraint of body `body`
    /// standing at `at` (m) with outward unit normal `normal`, for cells of size `h` (m);
    /// +∞ when none is.
    pub fn least(&self, body: usize, at: [f64; 3], normal: [f64; 3], h: f64) -> f64 {
        let Some(f) = self.fronts.get(body).filter(|f| !f.start.is_empty()) else {
            return f64::INFINITY;
        };
        let (depth, beside) = (DEPTH * h, BESIDE * h);
        // A point in front of the constraint lies within √(DEPTH² + BESIDE²) cells of it
        // (one behind it within √(1 + BESIDE²)): the cells that many away hold them all.
        let reach = DEPTH.hypot(BESIDE).ceil() as usize;
        let mut range = [(0, 0); 3];
        for a in 0..f.n {
            let t = ((at[a] - f.lo[a]) * f.inv_h).floor() as i64;
            let first = (t - reach as i64).max(0);
            let last = (t + reach as i64).min(f.cells[a] as i64 - 1);
            if first > last {
                return f64::INFINITY;
            }
            range[a] = (first as usize, last as usize);
        }
        let mut least = f64::INFINITY;
        for k in range[2].0..=range[2].1 {
            for j in range[1].0..=range[1].1 {
                let row = f.index([range[0].0, j, k]);
                let (from, to) = (f.start[row], f.start[row + range[0].1 - range[0].0 + 1]);
                for &(x, d) in &f.points[from as usize..to as usize] {
                    if d >= least {
                        continue;
                    }
                    let rel: [f64; 3] = std::array::from_fn(|a| x[a] - at[a]);
                    let t = rel[0] * normal[0] + rel[1] * normal[1] + rel[2] * normal[2];
                    if t <= -h || t > depth {
                        continue;
                    }
                    let off: f64 = (0..3).map(|a| (rel[a] - t * normal[a]).powi(2)).sum();
                    if off <= beside * beside {
                        least = d;
                    }
                }
            }
        }
        least
    }
}
