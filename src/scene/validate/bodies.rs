//! The bodies: each region (box, polygon) inside the grid, its material and its points
//! per cell.

use super::rules::*;
use crate::error::SceneError;
use crate::scene::spec::Region;

/// The bodies: material, points per cell, region.
pub(super) fn check_bodies(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    if s.bodies.is_empty() {
        return r.bad(
            "bodies",
            "the scene has no body: there is nothing to simulate".into(),
        );
    }
    for (b, body) in s.bodies.iter().enumerate() {
        if !s.materials.contains_key(&body.material) {
            let known: Vec<_> = s.materials.keys().map(String::as_str).collect();
            return r.bad(
                &format!("bodies[{b}].material"),
                format!(
                    "unknown material \"{}\" (defined: {})",
                    body.material,
                    known.join(", ")
                ),
            );
        }
        r.len(
            &format!("bodies[{b}].points_per_cell"),
            body.points_per_cell.len(),
        )?;
        if let Some(start) = &body.initial_stress {
            let field = format!("bodies[{b}].initial_stress");
            if let Err(e) = start.check() {
                let e = e.under(&field);
                return r.bad(&e.field, e.rule);
            }
            if matches!(start, crate::scene::InitialStress::Geostatic { .. }) {
                geostatic_gravity(r, &field)?;
            }
        }
        if body.points_per_cell.contains(&0) {
            return r.bad(
                &format!("bodies[{b}].points_per_cell"),
                "every entry must be ≥ 1".into(),
            );
        }
        match &body.region {
            Region::Box { min, max } => {
                r.len(&format!("bodies[{b}].region.min"), min.len())?;
                r.len(&format!("bodies[{b}].region.max"), max.len())?;
                r.finite(&format!("bodies[{b}].region.min"), min, "m")?;
                r.finite(&format!("bodies[{b}].region.max"), max, "m")?;
                if min.iter().zip(max).any(|(a, b)| !positive(b - a)) {
                    return r.bad(
                        &format!("bodies[{b}].region"),
                        "box needs min < max on every axis".into(),
                    );
                }
            }
            Region::Polygon { vertices, z } => {
                if vertices.len() < 3 {
                    return r.bad(
                        &format!("bodies[{b}].region.vertices"),
                        "a polygon needs at least 3 vertices".into(),
                    );
                }
                if let Some(k) = vertices.iter().position(|v| v.len() != 2) {
                    return r.bad(
                        &format!("bodies[{b}].region.vertices"),
                        format!("vertex {k} needs 2 entries [x, y], found {}", vertices[k].len()),
                    );
                }
                for (k, v) in vertices.iter().enumerate() {
                    r.finite(&format!("bodies[{b}].region.vertices[{k}]"), v, "m")?;
                }
                if let Some(z) = z {
                    if n == 2 {
                        return r.bad(
                            &format!("bodies[{b}].region.z"),
                            "a 2D polygon has no extent along z: remove z (it is for 3D scenes)".into(),
                        );
                    }
                    r.finite(&format!("bodies[{b}].region.z"), z, "m")?;
                }
                if let Some(rule) = crate::polygon::fault(vertices) {
                    return r.bad(&format!("bodies[{b}].region.vertices"), rule);
                }
                if n == 3 && !z.as_ref().is_some_and(|z| z.len() == 2 && positive(z[1] - z[0])) {
                    return r.bad(
                        &format!("bodies[{b}].region"),
                        "in 3D a polygon needs z: [z_min, z_max] with z_min < z_max".into(),
                    );
                }
            }
        }
    }
    Ok(())
}

/// A geostatic start balances full gravity, down one axis, from the first step.
fn geostatic_gravity(r: &Rules, field: &str) -> Result<(), SceneError> {
    let Some(g) = &r.loaded.scene.gravity else {
        return r.bad(
            field,
            "a Geostatic start is the ground's own weight: the scene needs gravity".into(),
        );
    };
    if crate::water::down_axis(&g.acceleration).is_none() {
        return r.bad(
            "gravity.acceleration",
            format!(
                "{:?} under a Geostatic start: gravity points down one axis (a negative entry, \
                 the others 0), the vertical the ground's weight is summed along",
                g.acceleration
            ),
        );
    }
    if g.ramp_time != 0.0 {
        return r.bad(
            "gravity.ramp_time",
            format!(
                "{} s under a Geostatic start: the start balances full gravity, so gravity acts \
                 in full from the first step (ramp_time 0)",
                g.ramp_time
            ),
        );
    }
    Ok(())
}
