//! The water: its surfaces and saturated densities ([`crate::water::WaterSpec::checked`]),
//! and each stage's surfaces. That every material with points below a surface has a
//! saturated density is checked as the points are placed ([`check_saturated`]).

use super::grid::CheckedGrid;
use super::rules::*;
use crate::error::Refusal;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::scene::loaded::LoadedScene;
use crate::water::{Frame, Water};

/// The scene's water, checked, or `None` when the scene is dry; with each stage's (`None`
/// where a stage leaves the water as it is).
pub(super) fn check_water(
    r: &Rules,
    grid: &CheckedGrid,
    table: &[(String, MaterialModel)],
    checked_stages: &[super::stages::CheckedStage],
) -> Result<(Option<Water>, Vec<Option<Water>>), SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    let n = r.n;
    let hi: Vec<f64> = (0..n)
        .map(|a| grid.origin[a] + grid.cell_size * grid.cells[a] as f64)
        .collect();
    let materials: Vec<(&str, f64)> = table.iter().map(|(n, m)| (n.as_str(), m.density())).collect();
    let frame = Frame {
        gravity: s.gravity.as_ref().map(|g| g.acceleration.as_slice()),
        lo: &grid.origin[..n],
        hi: &hi,
        materials: &materials,
        axisymmetric: s.dimension == crate::scene::spec::Dimension::Axisymmetric,
    };
    // A refusal of the scene's gravity is the scene's own field, not the water's.
    let at = |prefix: &str, r: Refusal| {
        let r = if r.field.starts_with("gravity") {
            r
        } else {
            r.under(prefix)
        };
        loaded.invalid(&r.field, r.rule)
    };
    let Some(spec) = &s.water else {
        if let Some(k) = s.stages.iter().position(|st| st.water.is_some()) {
            return r.bad(
                &format!("stages[{k}].water"),
                "a stage moves the scene's water: give the scene a `water` (its unit weight, \
                 first table and saturated densities)"
                    .into(),
            );
        }
        return Ok((None, vec![None; s.stages.len()]));
    };
    let water = spec.checked(&frame).map_err(|e| at("water", e))?;
    // A stage's gravity keeps to the water's axis; its dry density stays at most the
    // saturated density, which stages keep.
    for (k, g) in s
        .stages
        .iter()
        .enumerate()
        .filter_map(|(k, st)| Some((k, st.gravity.as_ref()?)))
    {
        if let Some(rule) = water.gravity_fault(&g.acceleration) {
            return r.bad(&format!("stages[{k}].gravity.acceleration"), rule);
        }
    }
    for (k, st) in checked_stages.iter().enumerate() {
        for (id, m) in &st.materials {
            let name = &table[*id as usize].0;
            let sat = water.saturated_density(*id);
            let dry = m.density();
            if let Some(sat) = sat.filter(|&sat| dry > sat) {
                return r.bad(
                    &format!("stages[{k}].materials.{name}.density"),
                    format!(
                        "{dry} kg/m³ is above the saturated density the water gives \"{name}\" \
                         ({sat} kg/m³): a stage keeps the scene's saturated densities, and a \
                         dry density is at most that"
                    ),
                );
            }
        }
    }
    let mut stages = Vec::with_capacity(s.stages.len());
    for (k, st) in s.stages.iter().enumerate() {
        stages.push(match &st.water {
            Some(w) => Some(
                w.checked(&water, &frame)
                    .map_err(|e| at(&format!("stages[{k}].water"), e))?,
            ),
            None => None,
        });
    }
    Ok((Some(water), stages))
}

/// Every point of material `material` (`name`) that starts below a surface, wholly or in
/// part (the scene's or a stage's, judged at its place at set-up; `xs` the points' places
/// and volumes), has a saturated density to weigh.
pub(crate) fn check_saturated(
    loaded: &LoadedScene,
    waters: &[(String, &Water)],
    material: u16,
    name: &str,
    mut xs: impl Iterator<Item = ([f64; 3], f64)>,
) -> Result<(), SceneError> {
    let has = loaded
        .scene
        .water
        .as_ref()
        .is_some_and(|w| w.saturated_density.contains_key(name));
    if has {
        return Ok(());
    }
    let below = |(x, v): ([f64; 3], f64)| {
        let (field, _) = waters.iter().find(|(_, w)| w.wets(material, x, v))?;
        Some((x, field))
    };
    if let Some((x, field)) = xs.find_map(below) {
        return Err(loaded.invalid(
            "water.saturated_density",
            format!(
                "material \"{name}\" has points below the piezometric surface of `{field}` (one \
                 at {:?}): give it a saturated density",
                &x[..loaded.scene.dimension.axes()]
            ),
        ));
    }
    Ok(())
}
