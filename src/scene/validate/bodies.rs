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
        if !(body.initial_pressure.is_finite() && body.initial_pressure >= 0.0) {
            return r.bad(
                &format!("bodies[{b}].initial_pressure"),
                format!(
                    "must be a finite pressure ≥ 0 Pa, found {}",
                    body.initial_pressure
                ),
            );
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
