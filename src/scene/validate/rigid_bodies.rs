//! Rigid bodies: each checks itself ([`crate::rigid::RigidBodySpec::check`]); here, their
//! names beside the motions' (they share `curve.csv`), their place in the grid over the
//! whole travel along the axes they move on (a body under load control finds its own
//! travel: it is stopped if it leaves the grid), and that no two overlap.

use super::rules::*;
use crate::error::Refusal;
use crate::error::SceneError;

/// Every rigid body, then the rules between bodies and with the grid.
pub(super) fn check_rigid_bodies(r: &Rules) -> Result<(), SceneError> {
    let (loaded, s, n) = (r.loaded, &r.loaded.scene, r.n);
    if s.rigid_bodies.len() > 32 {
        return r.bad(
            "rigid_bodies",
            format!("at most 32 bodies, found {}", s.rigid_bodies.len()),
        );
    }
    let g = &s.grid;
    let lo: Vec<f64> = g.origin.clone();
    let hi: Vec<f64> = (0..n)
        .map(|a| g.origin[a] + g.cells[a] as f64 * g.cell_size)
        .collect();
    // Each body's box at the start and the box it sweeps.
    let mut boxes: Vec<(Boxed, Boxed)> = Vec::new();
    for (i, b) in s.rigid_bodies.iter().enumerate() {
        let field = |f: &str| format!("rigid_bodies[{i}].{f}");
        b.check(n, s.dimension == crate::scene::spec::Dimension::Axisymmetric)
            .map_err(|Refusal { field: f, rule }| loaded.invalid(&field(&f), rule))?;
        if let Some(j) = s.motions.iter().position(|m| m.name == b.name) {
            return r.bad(
                &field("name"),
                format!(
                    "\"{}\" is also the name of motions[{j}]: the curve tells them apart by name",
                    b.name
                ),
            );
        }
        if let Some(j) = s.rigid_bodies[..i].iter().position(|o| o.name == b.name) {
            return r.bad(
                &field("name"),
                format!(
                    "\"{}\" is also the name of rigid_bodies[{j}]: each needs its own name",
                    b.name
                ),
            );
        }
        if let (Some(_), Some(j)) = (&b.cpt, s.rigid_bodies[..i].iter().position(|o| o.cpt.is_some())) {
            return r.bad(
                &field("cpt"),
                format!(
                    "rigid_bodies[{j}] is already logged as the run's piezocone: cpt.csv holds \
                     one; run the second cone in a scene of its own"
                ),
            );
        }
        if let Some(stage) = b.stage() {
            if !s.stages.iter().any(|t| &t.name == stage) {
                let names: Vec<&str> = s.stages.iter().map(|t| t.name.as_str()).collect();
                let control = if b.load.is_some() { "load" } else { "motion" };
                return r.bad(
                    &field(&format!("{control}.stage")),
                    format!("\"{stage}\" is not a stage of the scene (its stages: {names:?})"),
                );
            }
        }
        // Its bounds at the start and at the end of its travel, on every axis it moves
        // along; across the others it may reach past the grid (half a T-bar on a
        // symmetry face: the part outside meets no soil).
        let (start_lo, start_hi) = b.bounds(n);
        if let Some(a) = (0..n).find(|&a| start_hi[a] <= lo[a] || start_lo[a] >= hi[a]) {
            return r.bad(
                &field("parts"),
                format!(
                    "the body spans {}..{} m on axis {a}, outside the grid's {}..{} m: it would \
                     never meet the soil",
                    start_lo[a], start_hi[a], lo[a], hi[a]
                ),
            );
        }
        let (v, step) = b
            .motion
            .as_ref()
            .map_or(([0.0; 3], 0.0), |m| (m.vector(), m.travel / m.speed()));
        for (when, shift) in [("at the start", 0.0), ("at the end of its travel", step)] {
            for a in (0..n).filter(|&a| v[a] != 0.0) {
                let (l, h) = (start_lo[a] + v[a] * shift, start_hi[a] + v[a] * shift);
                if l < lo[a] || h > hi[a] {
                    return r.bad(
                        &field("geometry"),
                        format!(
                            "the body {when} spans {l}..{h} m on axis {a}, outside the grid's \
                             {}..{} m: give the grid room for the whole travel",
                            lo[a], hi[a]
                        ),
                    );
                }
            }
        }
        let start = (start_lo, start_hi);
        let path = swept(b, n, start, &lo, &hi);
        apart_from_earlier(r, i, (start, path), &boxes)?;
        boxes.push((start, path));
    }
    Ok(())
}

/// A box by its lower and upper corners (m).
type Boxed = ([f64; 3], [f64; 3]);

/// The box body `b` sweeps from its box `start` over its travel, to the end of its motion
/// or, under a load, to the grid's edge (`lo`..`hi`) along each axis the load acts on (it
/// finds its own travel).
fn swept(b: &crate::rigid::RigidBodySpec, n: usize, start: Boxed, lo: &[f64], hi: &[f64]) -> Boxed {
    let (mut swept_lo, mut swept_hi) = start;
    for a in 0..n {
        if let Some(l) = &b.load {
            let f = l.vector()[a];
            if f < 0.0 {
                swept_lo[a] = swept_lo[a].min(lo[a]);
            } else if f > 0.0 {
                swept_hi[a] = swept_hi[a].max(hi[a]);
            }
        }
        if let Some(m) = &b.motion {
            let moved = m.vector()[a] * (m.travel / m.speed());
            swept_lo[a] = swept_lo[a].min(start.0[a] + moved);
            swept_hi[a] = swept_hi[a].max(start.1[a] + moved);
        }
    }
    (swept_lo, swept_hi)
}

/// Body `i`'s box at the start and the box it sweeps (`start`, `path`) meet none of the
/// earlier bodies' (`boxes`): bodies meet the soil, not each other.
fn apart_from_earlier(
    r: &Rules,
    i: usize,
    (start, path): (Boxed, Boxed),
    boxes: &[(Boxed, Boxed)],
) -> Result<(), SceneError> {
    let n = r.n;
    let meet = |(alo, ahi): Boxed, (blo, bhi): Boxed| !(0..n).any(|a| ahi[a] <= blo[a] || bhi[a] <= alo[a]);
    for (j, &(other_start, other_path)) in boxes.iter().enumerate() {
        if meet(start, other_start) {
            return r.bad(
                &format!("rigid_bodies[{i}].geometry"),
                format!("the body overlaps rigid_bodies[{j}] (their bounding boxes meet): give them room"),
            );
        }
        if meet(path, other_path) {
            return r.bad(
                &format!("rigid_bodies[{i}].motion"),
                format!(
                    "the body's path crosses rigid_bodies[{j}]'s (the boxes they sweep over \
                     their travels meet, a load's to the grid's edge): rigid bodies do not \
                     meet each other, only the soil; give them paths apart"
                ),
            );
        }
    }
    Ok(())
}
