//! The loads: gravity, point loads, tractions (and their increments), traced points, and
//! the rule that a scene loads something.

use super::materials::{check_cell_means, check_mass_finite, check_smoothing};
use super::rules::*;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::scene::spec::TractionSurface;

/// Gravity, point loads, and what the materials make of them.
pub(super) fn check_loads(r: &Rules, table: &[(String, MaterialModel)]) -> Result<(), SceneError> {
    let (loaded, s, n) = (r.loaded, &r.loaded.scene, r.n);
    if let Some(g) = &s.gravity {
        check_gravity(r, "gravity", g)?;
    }
    check_mass_finite(loaded, table, n)?;
    match s.solver.anti_locking {
        crate::state::AntiLocking::StrainSmoothing => check_smoothing(loaded)?,
        crate::state::AntiLocking::CellMean => check_cell_means(loaded)?,
        crate::state::AntiLocking::Off => {}
    }
    for (i, l) in s.point_loads.iter().enumerate() {
        r.len(&format!("point_loads[{i}].position"), l.position.len())?;
        r.len(&format!("point_loads[{i}].force"), l.force.len())?;
        r.finite(&format!("point_loads[{i}].position"), &l.position, "m")?;
        r.finite(&format!("point_loads[{i}].force"), &l.force, "N")?;
    }
    Ok(())
}

/// A gravity, the scene's or a stage's (`field` its path): one finite entry per axis, a
/// ramp of at least 0 s, and along the axis in an axisymmetric scene (a radial gravity
/// would pull every ring outwards alike). Under water the water checks it too
/// ([`crate::water::Water::gravity_fault`]).
pub(super) fn check_gravity(
    r: &Rules,
    field: &str,
    g: &crate::scene::spec::GravitySpec,
) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    let at = format!("{field}.acceleration");
    r.len(&at, g.acceleration.len())?;
    r.finite(&at, &g.acceleration, "m/s²")?;
    if !non_negative(g.ramp_time) {
        return r.bad(
            &format!("{field}.ramp_time"),
            format!("must be ≥ 0 s, found {}", g.ramp_time),
        );
    }
    if s.dimension == crate::scene::spec::Dimension::Axisymmetric && g.acceleration[0] != 0.0 {
        return r.bad(
            &at,
            "in an axisymmetric scene gravity acts along the axis (y): its x entry must be 0".into(),
        );
    }
    Ok(())
}

/// Tractions and traced points.
pub(super) fn check_tractions_and_traced(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    for (i, t) in s.tractions.iter().enumerate() {
        r.len(&format!("tractions[{i}].min"), t.min.len())?;
        r.len(&format!("tractions[{i}].max"), t.max.len())?;
        match (t.pressure, t.traction.is_empty()) {
            (Some(_), false) => {
                return r.bad(
                    &format!("tractions[{i}].pressure"),
                    "give a traction or a pressure, not both".into(),
                )
            }
            (None, true) => {
                return r.bad(
                    &format!("tractions[{i}].traction"),
                    "give the traction (Pa, one entry per axis) or a pressure (Pa)".into(),
                )
            }
            (Some(p), true) => r.finite(&format!("tractions[{i}].pressure"), &[p], "Pa")?,
            (None, false) => {
                r.len(&format!("tractions[{i}].traction"), t.traction.len())?;
                r.finite(&format!("tractions[{i}].traction"), &t.traction, "Pa")?;
            }
        }
        r.finite(&format!("tractions[{i}].min"), &t.min, "m")?;
        r.finite(&format!("tractions[{i}].max"), &t.max, "m")?;
        if t.min.iter().zip(&t.max).any(|(lo, hi)| lo > hi) {
            return r.bad(
                &format!("tractions[{i}].max"),
                "every entry must be at least min's".into(),
            );
        }
        if t.increments == Some(0) {
            return r.bad(&format!("tractions[{i}].increments"), "must be at least 1".into());
        }
        if t.increments.is_some() && !s.output.displacements {
            return r.bad(
                &format!("tractions[{i}].increments"),
                "the curve follows the loaded points' displacement: keep them (output.displacements: true)"
                    .into(),
            );
        }
        match (&t.surface, t.surface.face()) {
            (_, Some(face)) if face.axis_side().0 >= n => {
                return r.bad(
                    &format!("tractions[{i}].surface"),
                    format!("{face:?} is not a face of a {n}D grid"),
                );
            }
            (TractionSurface::Arc { centre, radius }, _) => {
                let field = format!("tractions[{i}].surface");
                if n != 2 {
                    return r.bad(
                        &field,
                        "an Arc is a circle in the x-y plane: a 2D or axisymmetric scene's \
                         (a cylinder's wall in plane strain, a sphere's in axisymmetry)"
                            .into(),
                    );
                }
                r.len(&format!("{field}.centre"), centre.len())?;
                r.finite(&format!("{field}.centre"), centre, "m")?;
                if !(radius.is_finite() && *radius > 0.0) {
                    return r.bad(&format!("{field}.radius"), "must be a length > 0 (m)".into());
                }
                if t.pressure.is_none() {
                    return r.bad(
                        &format!("tractions[{i}].traction"),
                        "an Arc is loaded by a pressure (Pa), normal to it wherever it turns".into(),
                    );
                }
                if t.increments.is_some() {
                    return r.bad(
                        &format!("tractions[{i}].increments"),
                        "an Arc's pressure is raised in stages (`stages[k].tractions`): the \
                         curve of load increments follows a face's settlement, which an arc \
                         has not"
                            .into(),
                    );
                }
            }
            _ => {}
        }
    }
    for (i, t) in s.traced.iter().enumerate() {
        r.len(&format!("traced[{i}].position"), t.position.len())?;
        r.finite(&format!("traced[{i}].position"), &t.position, "m")?;
    }
    Ok(())
}

/// A scene without load is static as it stands.
pub(super) fn check_has_load(r: &Rules) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    // A scene without load is static as it stands: K_F and K_E are 0/0 at every step and
    // there is nothing to solve. Say so rather than run it.
    let gravity = s
        .gravity
        .as_ref()
        .is_some_and(|g| g.acceleration.iter().any(|&a| a != 0.0));
    let loads = s.point_loads.iter().any(|l| l.force.iter().any(|&f| f != 0.0))
        || s.tractions.iter().any(|t| t.loads());
    // A rigid body loads the soil only when something drives it: one that holds its place
    // (a base, a wall at rest) only answers to what else acts.
    let driven = s
        .rigid_bodies
        .iter()
        .any(|b| b.motion.is_some() || b.load.is_some());
    if !gravity && !loads && s.motions.is_empty() && !driven {
        return r.bad(
            if s.gravity.is_some() {
                "gravity.acceleration"
            } else {
                "gravity"
            },
            "the scene applies no load (no gravity, no non-zero point load, no motion, no rigid \
             body with a motion or a load): its static state is the state it starts in; add \
             gravity, point_loads, motions or a driven rigid body"
                .into(),
        );
    }
    Ok(())
}
