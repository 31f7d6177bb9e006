//! Loading stages: each stage's changes, checked against the scene, and its materials
//! built once.

use super::grid::{check_axis, check_faces, FaceHold};
use super::memory::carried_state;
use super::rules::*;
use crate::error::Refusal;
use crate::error::SceneError;
use crate::materials::MaterialModel;

/// A stage as set-up builds it: what the check built from its spec.
#[derive(Clone, Debug)]
pub struct CheckedStage {
    /// The materials the stage sets: the index in the scene's table and the model.
    pub materials: Vec<(u16, MaterialModel)>,
    /// The face conditions the stage sets, replacing the scene's.
    pub faces: Option<Vec<FaceHold>>,
    /// The water from this stage on (the scene's with the stage's surfaces), if it moves it.
    pub water: Option<crate::water::Water>,
}

/// The stages: each material, load, face condition and gravity they set.
pub(super) fn check_stages(
    r: &Rules,
    table: &[(String, MaterialModel)],
    c_p: f64,
) -> Result<Vec<CheckedStage>, SceneError> {
    let s = &r.loaded.scene;
    let mut built = Vec::with_capacity(s.stages.len());
    for (k, st) in s.stages.iter().enumerate() {
        let models = stage_materials(r, table, c_p, k)?;
        stage_loads(r, k)?;
        let faces = stage_faces(r, k)?;
        if let Some(g) = &st.gravity {
            if s.gravity.is_none() {
                return r.bad(
                    &format!("stages[{k}].gravity"),
                    "the scene has no gravity: give it one (even [0, 0]) for a stage to change".into(),
                );
            }
            super::loads::check_gravity(r, &format!("stages[{k}].gravity"), g)?;
        }
        if st.reset_displacements && !s.output.displacements {
            return r.bad(
                &format!("stages[{k}].reset_displacements"),
                "needs the displacements kept (output.displacements: true)".into(),
            );
        }
        built.push(CheckedStage {
            materials: models,
            faces,
            water: None, // set by the water's check
        });
    }
    Ok(built)
}

/// The materials stage `k` sets, each built once: a material of the scene, with the state
/// the scene's carries (or none) and a P-wave speed no faster than `c_p` (m/s), which set
/// the time step. As (index in `table`, model).
fn stage_materials(
    r: &Rules,
    table: &[(String, MaterialModel)],
    c_p: f64,
    k: usize,
) -> Result<Vec<(u16, MaterialModel)>, SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    let st = &s.stages[k];
    let mut models = Vec::with_capacity(st.materials.len());
    for (name, spec) in &st.materials {
        if !s.materials.contains_key(name) {
            return r.bad(
                &format!("stages[{k}].materials"),
                format!("\"{name}\" is not a material of the scene: a stage replaces one"),
            );
        }
        let at = |f: &str| format!("stages[{k}].materials.{name}.{f}");
        let model = spec
            .model(&at)
            .map_err(|Refusal { field, rule }| loaded.invalid(&field, rule))?;
        // A point carries one model's state for the whole run.
        if let Some(carried) = carried_state(loaded, table, name) {
            if let (Some(a), Some(b)) = (carried.state_name(), model.state_name()) {
                if a != b {
                    return r.bad(
                        &format!("stages[{k}].materials.{name}"),
                        format!(
                            "{} has another internal state than {}, which \"{name}\" takes \
                             in the scene or an earlier stage: a stage may change a material \
                             to a model with the same state, or with none",
                            model.name(),
                            carried.name()
                        ),
                    );
                }
            }
        }
        let speed = (model.p_wave_modulus() / model.density()).sqrt();
        if speed > c_p * (1.0 + 1e-12) {
            return r.bad(
                &at(spec.stiffness_field()),
                format!(
                    "a P-wave speed of {speed:.6} m/s, above the {c_p:.6} m/s that set the time \
                     step: the explicit scheme would be unstable in this stage; give the \
                     stiffest stage's material to the scene"
                ),
            );
        }
        let id = table.iter().position(|(n, _)| n == name).expect("checked above");
        models.push((id as u16, model));
    }
    Ok(models)
}

/// The point loads and tractions stage `k` sets: each the scene's, finite, of its length
/// (a pressure as `[p]`; not one applied in increments).
fn stage_loads(r: &Rules, k: usize) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    let st = &s.stages[k];
    for (name, force) in &st.point_loads {
        if !s.point_loads.iter().any(|l| l.name == *name) {
            return r.bad(
                &format!("stages[{k}].point_loads"),
                format!("\"{name}\" is not a point load of the scene"),
            );
        }
        r.len(&format!("stages[{k}].point_loads.{name}"), force.len())?;
        r.finite(&format!("stages[{k}].point_loads.{name}"), force, "N")?;
    }
    for (name, traction) in &st.tractions {
        let field = format!("stages[{k}].tractions.{name}");
        match s.tractions.iter().find(|t| t.name == *name) {
            None => return r.bad(&field, format!("\"{name}\" is not a traction of the scene")),
            Some(t) if t.increments.is_some() => {
                return r.bad(
                    &field,
                    "this traction is applied in increments: a stage cannot set it too".into(),
                )
            }
            Some(t) if t.pressure.is_some() && traction.len() != 1 => {
                return r.bad(
                    &field,
                    format!(
                        "\"{name}\" is a pressure: give its new value as one entry [p] (Pa), \
                         found {}",
                        traction.len()
                    ),
                )
            }
            Some(t) if t.pressure.is_none() => r.len(&field, traction.len())?,
            Some(_) => {}
        }
        r.finite(&field, traction, "Pa")?;
    }
    Ok(())
}

/// The face conditions stage `k` sets, checked as the scene's (the axis a roller in
/// axisymmetry; no friction face yet).
fn stage_faces(r: &Rules, k: usize) -> Result<Option<Vec<FaceHold>>, SceneError> {
    let (loaded, s, n) = (r.loaded, &r.loaded.scene, r.n);
    let st = &s.stages[k];
    let faces = match &st.boundaries {
        Some(b) => Some(
            check_faces(b, &format!("stages[{k}].boundaries"), n)
                .map_err(|Refusal { field, rule }| loaded.invalid(&field, rule))?,
        ),
        None => None,
    };
    if let (Some(f), crate::scene::spec::Dimension::Axisymmetric) = (&faces, s.dimension) {
        check_axis(f, &format!("stages[{k}].boundaries"))
            .map_err(|Refusal { field, rule }| loaded.invalid(&field, rule))?;
    }
    if let Some(i) = faces.iter().flatten().position(|f| f.friction.is_some()) {
        return r.bad(
            &format!("stages[{k}].boundaries[{i}].condition"),
            "a stage does not set Friction faces yet: give the friction face to the scene's \
             own `boundaries`, which the stages keep unless they replace them"
                .into(),
        );
    }
    Ok(faces)
}
