//! The bodies: each region (box, polygon) inside the grid, its material and its points
//! per cell.

use super::*;
use crate::error::SceneError;
use crate::scene::Region;

/// Why a polygon cannot be filled, if it cannot: zero area, or two edges that cross or
/// touch other than at their shared vertex (the even-odd fill of a self-intersecting
/// polygon is rarely the region meant).
pub(super) fn polygon_fault(vertices: &[Vec<f64>]) -> Option<String> {
    let m = vertices.len();
    let p = |i: usize| (vertices[i % m][0], vertices[i % m][1]);
    let twice_area: f64 = (0..m)
        .map(|i| {
            let ((x0, y0), (x1, y1)) = (p(i), p(i + 1));
            x0 * y1 - x1 * y0
        })
        .sum();
    if !positive(twice_area.abs()) {
        return Some("the polygon encloses no area".into());
    }
    let cross =
        |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let on = |a: (f64, f64), b: (f64, f64), q: (f64, f64)| {
        q.0 >= a.0.min(b.0) && q.0 <= a.0.max(b.0) && q.1 >= a.1.min(b.1) && q.1 <= a.1.max(b.1)
    };
    // Segments a-b and c-d meet (proper crossing, or one end on the other segment).
    let meet = |a, b, c, d| {
        let (d1, d2, d3, d4) = (cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d));
        (d1 * d2 < 0.0 && d3 * d4 < 0.0)
            || (d1 == 0.0 && on(c, d, a))
            || (d2 == 0.0 && on(c, d, b))
            || (d3 == 0.0 && on(a, b, c))
            || (d4 == 0.0 && on(a, b, d))
    };
    for i in 0..m {
        for j in i + 1..m {
            // Neighbouring edges share a vertex; they fault only by folding back on each other.
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            let (a, b, c, d) = (p(i), p(i + 1), p(j), p(j + 1));
            if adjacent {
                let (shared, u, v) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                let collinear_back = cross(shared, u, v) == 0.0
                    && (u.0 - shared.0) * (v.0 - shared.0) + (u.1 - shared.1) * (v.1 - shared.1) > 0.0;
                if collinear_back {
                    return Some(format!("edges {i} and {j} fold back on each other"));
                }
            } else if meet(a, b, c, d) {
                return Some(format!(
                    "edges {i} ({:?} to {:?}) and {j} ({:?} to {:?}) cross: give the vertices of a simple polygon, in order",
                    vertices[i], vertices[(i + 1) % m], vertices[j], vertices[(j + 1) % m]
                ));
            }
        }
    }
    None
}

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
                if let Some(rule) = polygon_fault(vertices) {
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
