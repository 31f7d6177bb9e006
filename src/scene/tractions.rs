//! Tractions: a distributed load on a body's surface, carried by the outermost points.

use super::loaded::{place_text, LoadedScene};
use super::region::BodyPoint;
use super::spec::{TractionSpec, TractionSurface};
use crate::components::*;
use crate::dim::Dim;
use crate::error::SceneError;
use crate::model::LoadSteps;
use crate::surface_pressure::{ArcPoint, SurfacePoint, SurfacePressures, NONE};
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
        .map(|i| match &s.tractions[i].surface {
            TractionSurface::Arc { centre, radius } => {
                on_arc::<D>(every(), loaded, i, centre, *radius).map(Loaded::Arc)
            }
            _ => outermost::<D>(every(), loaded, i)
                .and_then(|c| on_surface::<D>(every(), loaded, i, &c).map(|()| Loaded::Face(c))),
        })
        .collect::<Result<Vec<_>, _>>()?;
    let wanted: std::collections::BTreeSet<u32> = columns.iter().flat_map(Loaded::ids).collect();
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
    // The arc points' set-up places, to finish their `ArcPoint`s.
    let mut arc_places: BTreeMap<u32, [f64; 3]> = BTreeMap::new();
    for ((i, t), loaded_points) in s.tractions.iter().enumerate().zip(&columns) {
        let outermost = match loaded_points {
            Loaded::Face(c) => c,
            Loaded::Arc(arc) => {
                let mut shares = Vec::new();
                for q in arc {
                    let id = q.point.id;
                    if let Some(&(j, _)) = loaded_by.get(&id) {
                        return Err(shared_point(loaded, i, j, q.point.x[..n].to_vec()));
                    }
                    loaded_by.insert(id, (i, true));
                    let f = D::vec_from(t.load_at(&[t.pressure.expect("validated")], q.normal)) * q.share;
                    if let Some(&e) = held.get(&id) {
                        world.insert_one(e, PointLoad(f)).expect("a live point");
                    }
                    shares.push(Share {
                        id,
                        share: q.share,
                        normal: q.normal,
                    });
                    arc_places.insert(id, q.point.x);
                    followers.push((id, q.surface_point()));
                }
                placed.shares.push((t.name.clone(), shares));
                continue;
            }
        };
        let face = t.surface.face().expect("a face");
        let (normal, upper) = face.axis_side();
        let mut face_normal = [0.0; 3];
        face_normal[normal] = if upper { 1.0 } else { -1.0 };
        let pressed = t.pressure.is_some();
        let value = t.pressure.map_or_else(|| t.traction.clone(), |p| vec![p]);
        // The traction at set-up (Pa), x y z.
        let load = t.load_at(&value, face_normal);
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
            let f = D::vec_from(load) * share;
            if let Some(&e) = held.get(&id) {
                let earlier = world.get::<&PointLoad<D::Vec>>(e).map(|p| p.0).ok();
                world
                    .insert_one(e, PointLoad(earlier.map_or(f, |g| g + f)))
                    .expect("a live point");
            }
            points.push((id, D::vec_to3(f)));
            shares.push(Share {
                id,
                share,
                normal: face_normal,
            });
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
                pressure: load.iter().map(|c| c * c).sum::<f64>().sqrt(),
            });
        }
    }
    followers.sort_by_key(|f| f.0);
    placed.pressures = SurfacePressures {
        ids: followers.iter().map(|f| f.0).collect(),
        points: followers.into_iter().map(|f| f.1).collect(),
    };
    finish_arcs::<D>(&mut placed.pressures, &arc_places);
    Ok(placed)
}

/// A traction's loaded points: a face's columns or an arc's pieces.
enum Loaded {
    Face(Columns),
    Arc(Vec<OnArc>),
}

impl Loaded {
    /// The loaded points' ids.
    fn ids(&self) -> Vec<u32> {
        match self {
            Loaded::Face(c) => c.values().map(|v| v.1.id).collect(),
            Loaded::Arc(a) => a.iter().map(|q| q.point.id).collect(),
        }
    }
}

/// A point that loads a piece of an arc.
struct OnArc {
    /// The point (the nearest to the arc of those behind its piece).
    point: BodyPoint,
    /// Its piece's area (m, per radian in axisymmetry: ∫ r dl).
    share: f64,
    /// The bodies' outward normal at the point at set-up (unit, x y z).
    normal: [f64; 3],
    /// The point's distance from the arc (m).
    depth: f64,
    /// The ids of the points on the pieces before and after (`NONE` where none).
    links: [u32; 2],
    /// The arc's length a piece (m).
    spacing: f64,
    /// How many pieces a cell holds (the tangents' reach).
    reach: u32,
}

impl OnArc {
    /// Its place in the chain of a pressed surface; the orientation, chord and scale are
    /// set once the whole chain is known ([`finish_arcs`]).
    fn surface_point(&self) -> SurfacePoint {
        SurfacePoint {
            across: [0, 0],
            links: [self.links, [NONE; 2]],
            spacing: [self.spacing, 0.0],
            reach: [self.reach, self.reach],
            normal: self.normal,
            share: self.share,
            radius_offset: 0.0,
            arc: Some(ArcPoint {
                sign: 1.0,
                depth: self.depth,
                chord: 1.0,
                radius: self.point.x[0],
                scale: 1.0,
            }),
        }
    }
}

/// The pieces of the circle (`centre`, `radius`) inside traction `i`'s box and the point
/// of the bodies `every` nearest to each (on the bodies' side, within a cell): pieces of
/// about a sub-cell along the arc, each with its exact share of the arc.
fn on_arc<D: Dim>(
    every: impl Iterator<Item = BodyPoint>,
    loaded: &LoadedScene,
    i: usize,
    centre: &[f64],
    radius: f64,
) -> Result<Vec<OnArc>, SceneError> {
    use std::f64::consts::TAU;
    let s = &loaded.scene;
    let t = &s.tractions[i];
    let (cx, cy) = (centre[0], centre[1]);
    let (lo, hi, closed) = match arc_in_box(t, centre, radius) {
        Ok(span) => span,
        Err(0) => {
            return Err(loaded.invalid(
                &format!("tractions[{i}].min"),
                format!("traction \"{}\": its box holds no part of the circle", t.name),
            ))
        }
        Err(arcs) => {
            return Err(loaded.invalid(
                &format!("tractions[{i}].min"),
                format!(
                    "traction \"{}\": its box holds {arcs} separate arcs of the circle; give each \
                     its own traction",
                    t.name
                ),
            ))
        }
    };
    let (candidates, sub, hole) = around(every, loaded, t, centre, radius);
    if candidates.is_empty() {
        return Err(loaded.invalid(
            &format!("tractions[{i}].min"),
            format!("traction \"{}\": no point of a body lies in its box", t.name),
        ));
    }
    arc_on_face::<D>(loaded, i, &candidates, radius, hole, sub)?;
    let pieces = ((radius * (hi - lo) / sub).round() as usize).max(2);
    let width = (hi - lo) / pieces as f64;
    let mut nearest: Vec<Option<(f64, BodyPoint, f64)>> = vec![None; pieces];
    for (p, rho, phi) in candidates {
        if (hole && rho < radius) || (!hole && rho > radius) {
            continue;
        }
        let turned = lo + (phi - lo).rem_euclid(TAU);
        if turned >= hi {
            continue;
        }
        let k = (((turned - lo) / width) as usize).min(pieces - 1);
        let depth = (rho - radius).abs();
        if depth > s.grid.cell_size {
            continue;
        }
        if nearest[k].is_none_or(|n| depth < n.0 || (depth == n.0 && p.id < n.1.id)) {
            nearest[k] = Some((depth, p, rho));
        }
    }
    let ids: Vec<u32> = nearest.iter().map(|n| n.map_or(NONE, |n| n.1.id)).collect();
    let reach = (s.grid.cell_size / sub).round().max(1.0) as u32;
    let mut out = Vec::new();
    for (k, n) in nearest.iter().enumerate() {
        let Some((depth, point, rho)) = *n else { continue };
        let (a, b) = (lo + k as f64 * width, lo + (k + 1) as f64 * width);
        let share = if D::AXISYMMETRIC {
            radius * (cx * width + radius * (b.sin() - a.sin()))
        } else {
            radius * width
        };
        if share <= 0.0 {
            return Err(loaded.invalid(
                &format!("tractions[{i}].surface"),
                format!(
                    "traction \"{}\": its arc reaches r < 0 across the axis; an arc in an \
                     axisymmetric scene lies in r ≥ 0",
                    t.name
                ),
            ));
        }
        let side = if hole { -1.0 } else { 1.0 };
        let normal = [
            side * (point.x[0] - cx) / rho,
            side * (point.x[1] - cy) / rho,
            0.0,
        ];
        let link = |j: Option<usize>| j.map_or(NONE, |j| ids[j]);
        let before = if k > 0 {
            Some(k - 1)
        } else {
            closed.then_some(pieces - 1)
        };
        let after = if k + 1 < pieces {
            Some(k + 1)
        } else {
            closed.then_some(0)
        };
        out.push(OnArc {
            point,
            share,
            normal,
            depth,
            links: [link(before), link(after)],
            spacing: radius * width,
            reach,
        });
    }
    if out.len() < 2 {
        return Err(loaded.invalid(
            &format!("tractions[{i}].min"),
            format!(
                "traction \"{}\": fewer than two points lie within a cell of its arc, which \
                 needs a chain of them",
                t.name
            ),
        ));
    }
    Ok(out)
}

/// Refuses traction `i`'s circle of `radius` (m) where it is not the bodies' face: one of
/// the `candidates` (points in its box, with their radius and angle) lies on the far side
/// of it from the pressed points (inside a `hole`'s wall, outside a disc's rim) by more
/// than half a sub-cell `sub` (a polygon's chords sag inside their circle by less) and
/// within a cell: the arc runs through the soil.
fn arc_on_face<D: Dim>(
    loaded: &LoadedScene,
    i: usize,
    candidates: &[(BodyPoint, f64, f64)],
    radius: f64,
    hole: bool,
    sub: f64,
) -> Result<(), SceneError> {
    let cell = loaded.scene.grid.cell_size;
    let Some((p, rho, _)) = candidates.iter().find(|(_, rho, _)| {
        let beyond = if hole { radius - rho } else { rho - radius };
        beyond > 0.5 * sub && beyond <= cell
    }) else {
        return Ok(());
    };
    let side = if hole { "inside" } else { "outside" };
    Err(loaded.invalid(
        &format!("tractions[{i}].surface"),
        format!(
            "traction \"{}\" acts on a body's face, but its arc runs through the soil: the \
             point at {} lies {side} the circle, {:.4} m from it, where the points it presses \
             lie on the other side",
            loaded.scene.tractions[i].name,
            place_text(&p.x[..D::N]),
            (rho - radius).abs()
        ),
    ))
}

/// The points of the bodies `every` in traction `t`'s box with their radius and angle from
/// the circle's `centre`; the smallest sub-cell among them (m); whether the circle is a
/// hole's wall (the points lie outside it) rather than a disc's rim.
fn around(
    every: impl Iterator<Item = BodyPoint>,
    loaded: &LoadedScene,
    t: &TractionSpec,
    centre: &[f64],
    radius: f64,
) -> (Vec<(BodyPoint, f64, f64)>, f64, bool) {
    let s = &loaded.scene;
    let (cx, cy) = (centre[0], centre[1]);
    let mut candidates = Vec::new();
    let (mut outside, mut within) = (0usize, 0usize);
    let mut sub = f64::INFINITY;
    for p in every {
        let x = p.x;
        if !t.holds(&x) {
            continue;
        }
        let (dx, dy) = (x[0] - cx, x[1] - cy);
        let rho = dx.hypot(dy);
        if rho > radius {
            outside += 1;
        } else {
            within += 1;
        }
        let ppc = &s.bodies[p.body].points_per_cell;
        sub = sub.min(s.grid.cell_size / ppc[0].max(ppc[1]) as f64);
        candidates.push((p, rho, dy.atan2(dx)));
    }
    (candidates, sub, outside >= within)
}

/// The arc of the circle (`centre`, `radius`) inside traction `t`'s box, as its ends
/// [lo, hi] (rad, counter-clockwise from +x) and whether it is the whole circle: sampled
/// finely, its ends found by bisection. Err(n): the box holds n ≠ 1 separate arcs.
fn arc_in_box(t: &TractionSpec, centre: &[f64], radius: f64) -> Result<(f64, f64, bool), usize> {
    use std::f64::consts::{PI, TAU};
    const SAMPLES: usize = 1 << 14;
    let (cx, cy) = (centre[0], centre[1]);
    let inside = |phi: f64| t.holds(&[cx + radius * phi.cos(), cy + radius * phi.sin()]);
    let at = |j: usize| -PI + TAU * j as f64 / SAMPLES as f64;
    let flags: Vec<bool> = (0..SAMPLES).map(|j| inside(at(j))).collect();
    let starts: Vec<usize> = (0..SAMPLES)
        .filter(|&j| flags[j] && !flags[(j + SAMPLES - 1) % SAMPLES])
        .collect();
    let bisect = |mut out: f64, mut inn: f64| {
        for _ in 0..60 {
            let mid = 0.5 * (out + inn);
            if inside(mid) {
                inn = mid;
            } else {
                out = mid;
            }
        }
        inn
    };
    match starts.as_slice() {
        [] if flags[0] => Ok((-PI, PI, true)),
        [j] => {
            let end = (*j..*j + SAMPLES).find(|&k| !flags[k % SAMPLES]).expect("an end");
            let lo = bisect(at(*j) - TAU / SAMPLES as f64, at(*j));
            let hi = bisect(
                at(*j) + TAU * (end - j) as f64 / SAMPLES as f64,
                at(*j) + TAU * (end - j - 1) as f64 / SAMPLES as f64,
            );
            Ok((lo, hi, false))
        }
        _ => Err(starts.len()),
    }
}

/// Sets each arc point's orientation, chord and scale from the set-up places `places` of
/// the arcs' points ([`ArcPoint`]).
fn finish_arcs<D: Dim>(pressures: &mut SurfacePressures, places: &BTreeMap<u32, [f64; 3]>) {
    if places.is_empty() {
        return;
    }
    let place = |id: u32| places.get(&id).copied().unwrap_or([0.0; 3]);
    let arcs: Vec<usize> = (0..pressures.points.len())
        .filter(|&k| pressures.points[k].arc.is_some())
        .collect();
    for &k in &arcs {
        let raw = pressures.raw_area::<D>(k, place);
        let size = raw.iter().map(|c| c * c).sum::<f64>().sqrt();
        let p = &mut pressures.points[k];
        let towards = (0..3).map(|c| raw[c] * p.normal[c]).sum::<f64>();
        let a = p.arc.as_mut().expect("an arc point");
        a.sign = if towards >= 0.0 { 1.0 } else { -1.0 };
        a.chord = size;
    }
    // The places on the wall at set-up, and each point's exact share against its area
    // vector there.
    let mut on: Vec<[f64; 3]> = Vec::new();
    let xs: Vec<[f64; 3]> = pressures
        .ids
        .iter()
        .map(|&id| places.get(&id).copied().unwrap_or([0.0; 3]))
        .collect();
    pressures.surface_places::<D>(&xs, &mut on);
    let wall = |id: u32| on[pressures.index(id).expect("loaded")];
    let areas: Vec<f64> = arcs
        .iter()
        .map(|&k| {
            let size = pressures
                .area::<D>(k, wall)
                .iter()
                .map(|c| c * c)
                .sum::<f64>()
                .sqrt();
            pressures.points[k].share / size
        })
        .collect();
    for (&k, scale) in arcs.iter().zip(areas) {
        pressures.points[k].arc.as_mut().expect("an arc point").scale = scale;
    }
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
    let (normal, upper) = t.surface.face().expect("a face").axis_side();
    let mut outermost = Columns::new();
    for p in every {
        let x = p.x;
        if !t.holds(&x) {
            continue;
        }
        let ppc = &s.bodies[p.body].points_per_cell;
        let sub = |a: usize| s.grid.cell_size / ppc[a] as f64;
        let key = column_key(x, n, normal, sub);
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

/// Refuses traction `i` where a column's outermost point in its box ([`Columns`]) is not
/// on the body's surface: a point of the bodies `every` lies beyond it in the same column,
/// within a cell, outside the box (the box cut the body below its face, and the load would
/// act inside the soil).
fn on_surface<D: Dim>(
    every: impl Iterator<Item = BodyPoint>,
    loaded: &LoadedScene,
    i: usize,
    columns: &Columns,
) -> Result<(), SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    let t = &s.tractions[i];
    let (normal, upper) = t.surface.face().expect("a face").axis_side();
    for q in every {
        let x = q.x;
        let ppc = &s.bodies[q.body].points_per_cell;
        let key = column_key(x, n, normal, |a| s.grid.cell_size / ppc[a] as f64);
        let Some((top, p, ..)) = columns.get(&key) else {
            continue;
        };
        let beyond = if upper { x[normal] } else { -x[normal] } - top;
        if beyond > 0.0 && beyond <= s.grid.cell_size {
            // The box's bound on the face's side is the one that stops short of it.
            let bound = if upper { "max" } else { "min" };
            return Err(loaded.invalid(
                &format!("tractions[{i}].{bound}"),
                format!(
                    "traction \"{}\" acts on a body's surface, but its box ends inside the body: \
                     the point at {} has soil beyond it at {}; reach the box past the face",
                    t.name,
                    place_text(&p.x[..n]),
                    place_text(&x[..n])
                ),
            ));
        }
    }
    Ok(())
}

/// The column of a face's points that `x` (m) lies in: its sub-cell index along each of
/// the `n` axes but the face's `normal`, `sub(a)` the sub-cell's edge along axis a (m).
fn column_key(x: [f64; 3], n: usize, normal: usize, sub: impl Fn(usize) -> f64) -> Vec<i64> {
    (0..n)
        .filter(|&a| a != normal)
        .map(|a| (x[a] / sub(a)).floor() as i64)
        .collect()
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
            arc: None,
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

/// A point that a traction loads.
#[derive(Clone, Copy, Debug)]
pub(super) struct Share {
    /// The point's id.
    pub id: u32,
    /// Its share of the surface (m²; m in 2D; per radian in axisymmetry).
    pub share: f64,
    /// The surface's outward normal there at set-up (unit, x y z).
    pub normal: [f64; 3],
}

/// Where the tractions went.
#[derive(Default)]
pub(super) struct Placed {
    /// The tractions applied in increments.
    pub steps: Vec<LoadSteps>,
    /// Each traction's name and loaded points.
    pub shares: Vec<(String, Vec<Share>)>,
    /// The points under pressures and their places in their surfaces.
    pub pressures: SurfacePressures,
}
