//! Tractions: a distributed load on a body's surface, carried by the outermost points.

use super::{pad3, LoadedScene};
use crate::components::*;
use crate::dim::Dim;
use crate::error::SceneError;
use crate::state::LoadSteps;
use hecs::{Entity, World};
use std::collections::BTreeMap;

/// Gives the outermost point of each column of points inside each traction's box (along
/// the surface's normal) a point load: the traction times the column's share of the
/// surface, (h/n) per axis across the normal for n points a cell. `body_ids` holds the
/// point ids of each body.
pub(super) fn place<D: Dim>(
    world: &mut World,
    loaded: &LoadedScene,
    body_ids: &[std::ops::Range<u32>],
) -> Result<Placed, SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    let mut placed = Placed::default();
    for (i, t) in s.tractions.iter().enumerate() {
        let (normal, upper) = t.surface.axis_side();
        // Column key: the point's sub-cell coordinates across the normal.
        // Key → (how far out, the point, its share); key order keeps set-up deterministic.
        let mut outermost: BTreeMap<Vec<i64>, (f64, Entity, f64)> = BTreeMap::new();
        for (e, x, id) in world.query::<(Entity, &Position<D::Vec>, &PointId)>().iter() {
            if world.get::<&Stress<D::Stress>>(e).is_err() {
                continue; // a load carrier
            }
            let x = D::vec_to3(x.0);
            if !(0..n).all(|a| x[a] >= t.min[a] && x[a] <= t.max[a]) {
                continue;
            }
            let body = body_ids
                .iter()
                .position(|r| r.contains(&id.0))
                .expect("every point has a body");
            let ppc = &s.bodies[body].points_per_cell;
            let sub = |a: usize| s.grid.cell_size / ppc[a] as f64;
            let key: Vec<i64> = (0..n)
                .filter(|&a| a != normal)
                .map(|a| (x[a] / sub(a)).floor() as i64)
                .collect();
            // The column's share of the surface; per radian in axisymmetry, times the
            // surface's radius: the point's own on a face across the axis, the edge of its
            // sub-cell on a face normal to r.
            let radius = match (D::AXISYMMETRIC, normal) {
                (false, _) => 1.0,
                (true, 0) if upper => x[0] + 0.5 * sub(0),
                (true, 0) => x[0] - 0.5 * sub(0),
                (true, _) => x[0],
            };
            let share: f64 = (0..n).filter(|&a| a != normal).map(sub).product::<f64>() * radius;
            let out = if upper { x[normal] } else { -x[normal] };
            let entry = outermost.entry(key).or_insert((out, e, share));
            if entry.0 < out {
                *entry = (out, e, share);
            }
        }
        if outermost.is_empty() {
            return Err(loaded.invalid(
                &format!("tractions[{i}].min"),
                format!("traction \"{}\": no point of a body lies in its box", t.name),
            ));
        }
        let (mut points, mut shares) = (Vec::new(), Vec::new());
        for (_, (_, e, share)) in outermost {
            let f = D::vec_from(pad3(&t.traction)) * share;
            let total = match world.get::<&PointLoad<D::Vec>>(e) {
                Ok(p) => p.0 + f,
                Err(_) => f,
            };
            world.insert_one(e, PointLoad(total)).expect("a live point");
            let id = world.get::<&PointId>(e).expect("a live point").0;
            points.push((id, D::vec_to3(f)));
            shares.push((id, share));
        }
        points.sort_by_key(|p| p.0);
        placed.shares.push((t.name.clone(), shares));
        if let Some(k) = t.increments {
            placed.steps.push(LoadSteps {
                name: t.name.clone(),
                points,
                increments: k,
                pressure: t.traction.iter().map(|c| c * c).sum::<f64>().sqrt(),
            });
        }
    }
    Ok(placed)
}

/// Where the tractions went.
#[derive(Default)]
pub(super) struct Placed {
    /// The tractions applied in increments.
    pub steps: Vec<LoadSteps>,
    /// Each traction's points (ids) and their shares of the surface (m²; m in 2D).
    pub shares: Vec<(String, Vec<(u32, f64)>)>,
}
