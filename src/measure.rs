//! Measurements of a state: free-surface angle, displacements, mass.

use crate::components::{Displacement, Mass, PointId, Position};
use crate::dim::{Dim, Vector};
use crate::infra::columns::{col, points_with};
use crate::simulation::Simulation;
use serde::Serialize;

/// How steep the free surface stands, from the top-most point of each grid column.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceAngle {
    /// Angle of the fitted line to the horizontal (degrees, 0–90).
    pub degrees: f64,
    /// Columns used in the fit.
    pub columns: usize,
    /// Height of the highest point (m above the grid origin).
    pub max_height: f64,
}

/// Free-surface angle by least squares.
///
/// For every grid column (cells along x; in 3D all z together) the top-most point is taken
/// (its x and its height y above the grid origin). Columns whose top lies between 10 % and
/// 90 % of the highest top are kept — the crest plateau and the toe run-out are left out —
/// and a line y = a + b·x is fitted through their tops by least squares. The angle is
/// atan|b|. `None` when fewer than two columns qualify.
pub fn surface_angle<D: Dim>(sim: &Simulation<D>) -> Option<SurfaceAngle> {
    let grid = &sim.ctx.grid;
    let mut top: Vec<Option<(f64, f64)>> = vec![None; grid.axes[0].cells.max(1)];
    let y0 = grid.origin.get(1);
    for arch in points_with::<Mass>(&sim.ctx.world) {
        for x in col::<Position<D::Vec>>(arch).iter() {
            let Some(cell) = grid.cell_of(x.0) else { continue };
            let (px, py) = (x.0.get(0), x.0.get(1) - y0);
            let t = &mut top[cell[0]];
            if t.is_none_or(|(_, y)| py > y) {
                *t = Some((px, py));
            }
        }
    }
    // Over MPI each rank found the tops of its own points: the highest of the ranks' tops
    // (the lowest rank's on a tie) is the column's. A collective.
    let comm = &sim.ctx.comm;
    if comm.size() > 1 {
        let mine: Vec<f64> = top
            .iter()
            .flat_map(|t| t.map_or([f64::NAN; 2], |(x, y)| [x, y]))
            .collect();
        let all = comm.gather_all(&mine);
        let n = mine.len();
        for (c, t) in top.iter_mut().enumerate() {
            *t = None;
            for r in 0..comm.size() {
                let (x, y) = (all[r * n + 2 * c], all[r * n + 2 * c + 1]);
                if !y.is_nan() && t.is_none_or(|(_, ty)| y > ty) {
                    *t = Some((x, y));
                }
            }
        }
    }
    let max_height = top
        .iter()
        .flatten()
        .map(|t| t.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let used: Vec<(f64, f64)> = top
        .into_iter()
        .flatten()
        .filter(|t| t.1 >= 0.1 * max_height && t.1 <= 0.9 * max_height)
        .collect();
    if used.len() < 2 {
        return None;
    }
    let n = used.len() as f64;
    let (mx, my) = (
        used.iter().map(|t| t.0).sum::<f64>() / n,
        used.iter().map(|t| t.1).sum::<f64>() / n,
    );
    let sxy: f64 = used.iter().map(|t| (t.0 - mx) * (t.1 - my)).sum();
    let sxx: f64 = used.iter().map(|t| (t.0 - mx) * (t.0 - mx)).sum();
    let slope = sxy / sxx;
    Some(SurfaceAngle {
        degrees: slope.abs().atan().to_degrees(),
        columns: used.len(),
        max_height,
    })
}

/// Largest displacement magnitude and largest |horizontal (x) displacement| over the
/// points (m), or `None` when the scene keeps no displacements (`output.displacements`).
pub fn max_displacements<D: Dim>(sim: &Simulation<D>) -> Option<(f64, f64)> {
    let (mut total, mut horizontal) = (0.0f64, 0.0f64);
    let mut kept = false;
    for arch in points_with::<Displacement<D::Vec>>(&sim.ctx.world) {
        kept = true;
        for u in col::<Displacement<D::Vec>>(arch).iter() {
            total = total.max(u.0.dot(u.0).sqrt());
            horizontal = horizontal.max(u.0.get(0).abs());
        }
    }
    kept.then_some((total, horizontal))
}

/// True when every point position is finite.
pub fn all_positions_finite<D: Dim>(sim: &Simulation<D>) -> bool {
    points_with::<Position<D::Vec>>(&sim.ctx.world)
        .all(|a| col::<Position<D::Vec>>(a).iter().all(|x| x.0.is_finite()))
}

/// Positions of every point (load carriers included), padded to x y z (m), indexed by
/// [`PointId`]: lists taken at two times compare point by point even if a spatial sort
/// moved the points between rows in between.
pub fn positions<D: Dim>(world: &hecs::World, out: &mut Vec<[f64; 3]>) {
    out.clear();
    for arch in points_with::<Position<D::Vec>>(world) {
        let (x, id) = (col::<Position<D::Vec>>(arch), col::<PointId>(arch));
        for (x, id) in x.iter().zip(id.iter()) {
            id.place(out, D::vec_to3(x.0), [f64::NAN; 3]);
        }
    }
}

/// Largest distance between matching entries of two position lists (m).
pub fn max_movement(before: &[[f64; 3]], after: &[[f64; 3]]) -> f64 {
    before
        .iter()
        .zip(after)
        .map(|(a, b)| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt())
        .fold(0.0, f64::max)
}
