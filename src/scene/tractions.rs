//! Tractions: a distributed load on a body's surface, carried by the outermost points.

use super::loaded::LoadedScene;
use super::region::BodyPoint;
use crate::components::*;
use crate::dim::Dim;
use crate::error::SceneError;
use crate::model::LoadSteps;
use crate::surface_pressure::{SurfacePoint, SurfacePressures, NONE};
use hecs::{Entity, World};
use std::collections::BTreeMap;

/// Gives the outermost point of each column of points inside each traction's box (along
/// the surface's normal) a point load: the traction times the column's share of the
/// surface, (h/n) per axis across the normal for n points a cell. A `pressure` gives them
/// the traction −p n and their neighbours along the surface (the next columns' points), from
/// which `point_loads` turns the load with the surface ([`crate::surface_pressure`]).
/// `every` gives every body's points at set-up, whichever rank holds them: the columns and
/// their outermost points are the whole scene's, and the loads go to those `world` holds.
pub(super) fn place<D: Dim, I: Iterator<Item = BodyPoint>>(
    world: &mut World,
    loaded: &LoadedScene,
    every: impl Fn() -> I,
) -> Result<Placed, SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    let mut placed = Placed::default();
    // Each traction's columns, then the entities of the loaded points this rank holds.
    let columns = (0..s.tractions.len())
        .map(|i| outermost::<D>(every(), loaded, i))
        .collect::<Result<Vec<_>, _>>()?;
    let wanted: std::collections::BTreeSet<u32> =
        columns.iter().flat_map(|c| c.values().map(|v| v.1.id)).collect();
    let held: BTreeMap<u32, Entity> = world
        .query::<(Entity, &PointId)>()
        .iter()
        .filter(|(_, id)| wanted.contains(&id.0))
        .map(|(e, id)| (id.0, e))
        .collect();
    // Every loaded point, by id: the traction that loaded it and whether it is a pressure.
    let mut loaded_by: BTreeMap<u32, (usize, bool)> = BTreeMap::new();
    // The points under a pressure and their places in its surface.
    let mut followers: Vec<(u32, SurfacePoint)> = Vec::new();
    for ((i, t), outermost) in s.tractions.iter().enumerate().zip(&columns) {
        let (normal, upper) = t.surface.axis_side();
        let pressed = t.pressure.is_some();
        let across: Vec<usize> = (0..n).filter(|&a| a != normal).collect();
        let ids: BTreeMap<&Vec<i64>, u32> = outermost.iter().map(|(k, v)| (k, v.1.id)).collect();
        let (mut points, mut shares) = (Vec::new(), Vec::new());
        for (key, &(_, p, share, subs)) in outermost {
            let id = p.id;
            if let Some(&(j, earlier_pressed)) = loaded_by.get(&id) {
                if pressed || earlier_pressed {
                    return Err(shared_point(loaded, i, j, p.x[..n].to_vec()));
                }
            }
            loaded_by.entry(id).or_insert((i, pressed));
            let f = D::vec_from(t.vector()) * share;
            if let Some(&e) = held.get(&id) {
                let earlier = world.get::<&PointLoad<D::Vec>>(e).map(|p| p.0).ok();
                world
                    .insert_one(e, PointLoad(earlier.map_or(f, |g| g + f)))
                    .expect("a live point");
            }
            points.push((id, D::vec_to3(f)));
            shares.push((id, share));
            if pressed {
                let column = Column {
                    key,
                    across: &across,
                    subs,
                    share,
                    axisymmetric: D::AXISYMMETRIC,
                };
                followers.push((id, column.surface_point(&ids, normal, upper, s.grid.cell_size)));
            }
        }
        points.sort_by_key(|p| p.0);
        placed.shares.push((t.name.clone(), shares));
        if let Some(k) = t.increments {
            placed.steps.push(LoadSteps {
                name: t.name.clone(),
                points,
                increments: k,
                pressure: t.vector().iter().map(|c| c * c).sum::<f64>().sqrt(),
            });
        }
    }
    followers.sort_by_key(|f| f.0);
    placed.pressures = SurfacePressures {
        ids: followers.iter().map(|f| f.0).collect(),
        points: followers.into_iter().map(|f| f.1).collect(),
    };
    Ok(placed)
}

/// Traction `i`'s points in each column across its surface's normal: key (the point's
/// sub-cell coordinates across the normal; key order keeps set-up deterministic) → (how
/// far out along the normal, the point, the column's share of the surface, the sub-cell's
/// edges in m). Refused when the box holds no point or its face lies on the axis.
type Columns = BTreeMap<Vec<i64>, (f64, BodyPoint, f64, [f64; 3])>;

/// The outermost of the body points `every` in each column of traction `i` ([`Columns`]).
fn outermost<D: Dim>(
    every: impl Iterator<Item = BodyPoint>,
    loaded: &LoadedScene,
    i: usize,
) -> Result<Columns, SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    let t = &s.tractions[i];
    let (normal, upper) = t.surface.axis_side();
    let mut outermost = Columns::new();
    for p in every {
        let x = p.x;
        if !(0..n).all(|a| x[a] >= t.min[a] && x[a] <= t.max[a]) {
            continue;
        }
        let ppc = &s.bodies[p.body].points_per_cell;
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
        if radius <= 1e-9 * s.grid.cell_size {
            return Err(loaded.invalid(
                &format!("tractions[{i}].surface"),
                format!(
                    "traction \"{}\" loads points whose face lies on the axis (r = 0), which \
                     has no area: it would carry nothing; an XMin surface is a hollow body's \
                     inner face, off the axis",
                    t.name
                ),
            ));
        }
        let share: f64 = (0..n).filter(|&a| a != normal).map(sub).product::<f64>() * radius;
        let out = if upper { x[normal] } else { -x[normal] };
        let subs = std::array::from_fn(|a| if a < n { sub(a) } else { 0.0 });
        let entry = outermost.entry(key).or_insert((out, p, share, subs));
        if entry.0 < out {
            *entry = (out, p, share, subs);
        }
    }
    if outermost.is_empty() {
        return Err(loaded.invalid(
            &format!("tractions[{i}].min"),
            format!("traction \"{}\": no point of a body lies in its box", t.name),
        ));
    }
    Ok(outermost)
}

/// A pressed column of a traction, as [`Column::surface_point`] reads it.
struct Column<'a> {
    /// The column's key ([`Columns`]).
    key: &'a [i64],
    /// The axes across the surface's normal.
    across: &'a [usize],
    /// The column's sub-cell edges (m, per axis).
    subs: [f64; 3],
    /// Its share of the surface (m^(D−1), times r in axisymmetry).
    share: f64,
    /// Whether the scene is axisymmetric (x the radius).
    axisymmetric: bool,
}

impl Column<'_> {
    /// The column's point as a point of a pressed surface: its neighbours along the
    /// surface (the columns one sub-cell before and after along each axis across the
    /// normal, of points `ids`), their spacing and reach in sub-cells of a cell of
    /// `cell_size` (m), and the outward normal of the face (`normal` axis, `upper` side).
    fn surface_point(
        &self,
        ids: &BTreeMap<&Vec<i64>, u32>,
        normal: usize,
        upper: bool,
        cell_size: f64,
    ) -> SurfacePoint {
        let (across, subs) = (self.across, self.subs);
        let mut links = [[NONE; 2]; 2];
        let (mut spacing, mut reach) = ([0.0; 2], [1; 2]);
        for (j, &a) in across.iter().enumerate() {
            for (side, step) in [-1i64, 1].into_iter().enumerate() {
                let mut k = self.key.to_vec();
                k[j] += step;
                if let Some(&neighbour) = ids.get(&k) {
                    links[j][side] = neighbour;
                }
            }
            spacing[j] = subs[a];
            reach[j] = (cell_size / subs[a]).round().max(1.0) as u32;
        }
        let mut outward = [0.0; 3];
        outward[normal] = if upper { 1.0 } else { -1.0 };
        // In axisymmetry a face normal to r lies half a sub-cell out from the point.
        let radius_offset = if self.axisymmetric && normal == 0 {
            outward[0] * 0.5 * subs[0]
        } else {
            0.0
        };
        SurfacePoint {
            across: [across[0], *across.get(1).unwrap_or(&across[0])],
            links,
            spacing,
            reach,
            normal: outward,
            share: self.share,
            radius_offset,
        }
    }
}

/// Traction `i` loads a point that traction `j` loads too, and one of them is a pressure.
fn shared_point(loaded: &LoadedScene, i: usize, j: usize, x: Vec<f64>) -> SceneError {
    loaded.invalid(
        &format!("tractions[{i}].min"),
        format!(
            "its surface shares the point at {x:?} with tractions[{j}] (\"{}\"): a point under a \
             pressure carries no other traction; make the two boxes meet without a common point",
            loaded.scene.tractions[j].name
        ),
    )
}

/// Where the tractions went.
#[derive(Default)]
pub(super) struct Placed {
    /// The tractions applied in increments.
    pub steps: Vec<LoadSteps>,
    /// Each traction's points (ids) and their shares of the surface (m²; m in 2D).
    pub shares: Vec<(String, Vec<(u32, f64)>)>,
    /// The points under pressures and their places in their surfaces.
    pub pressures: SurfacePressures,
}
