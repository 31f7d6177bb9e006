//! The materials: each entry's own rules, the mass its density gives, and smoothing only
//! where the flow rule allows it.

use super::rules::*;
use crate::error::Refusal;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::scene::loaded::LoadedScene;

/// Each body's mass (ρ times its bounding box's volume, an upper bound) and the scene's
/// weight are finite numbers: a density of 1e308 kg/m³ gives points whose mass sums to
/// infinity, and a gravity of 1e308 m/s² forces that do, and the first step turns them
/// into NaN.
pub(super) fn check_mass_finite(
    loaded: &LoadedScene,
    table: &[(String, MaterialModel)],
    n: usize,
) -> Result<(), SceneError> {
    let s = &loaded.scene;
    let mut total = 0.0f64;
    for body in &s.bodies {
        let Some((_, model)) = table.iter().find(|(name, _)| *name == body.material) else {
            continue;
        };
        let (lo, hi) = crate::scene::region::region_bounds(&body.region, n);
        let volume: f64 = (0..n).map(|a| (hi[a] - lo[a]).abs()).product();
        let mass = model.density() * volume;
        total += mass;
        if !mass.is_finite() || !total.is_finite() {
            return Err(loaded.invalid(
                &format!("materials.{}.density", body.material),
                format!(
                    "{:e} kg/m³ over the bodies' {volume:e} m{} gives a mass that is not a finite number",
                    model.density(),
                    if n == 2 { "² (per metre)" } else { "³" }
                ),
            ));
        }
    }
    if let Some(g) = &s.gravity {
        let size = g.acceleration.iter().fold(0.0f64, |s, a| s.hypot(*a));
        if !(total * size).is_finite() {
            return Err(loaded.invalid(
                "gravity.acceleration",
                format!("|g| = {size:e} m/s² on {total:e} kg gives a weight that is not a finite number"),
            ));
        }
    }
    Ok(())
}

/// The cell means give an undrained clay's points of a cell one mean total stress, and its
/// water already holds one pore pressure a cell, so the skeleton's mean effective stress
/// is averaged too. The undrained oedometer of `clay_oedometer.ron` settles within 0.7 % of
/// its answer without them, but the piezocone of `cptu_clay.ron` at D/4 finds no static
/// state with them: K_F stays at 0.004–0.07 over 37 s of simulated time, where each
/// increment comes to rest when its 5 s of travel end without them (docs/verification.md).
pub(super) fn check_cell_means(loaded: &LoadedScene) -> Result<(), SceneError> {
    for (name, m) in loaded.scene.every_material() {
        if m.holds_water() {
            return Err(loaded.invalid(
                "solver.anti_locking",
                format!(
                    "material \"{name}\" holds undrained water: with the cell means a cone \
                     pushed into it finds no static state (docs/verification.md); use \
                     anti_locking Off"
                ),
            ));
        }
    }
    Ok(())
}

/// Volumetric smoothing is for isochoric plastic flow (ψ = 0): it is refused on a material
/// that dilates, in the scene or in a stage. The smoothed strain rate is not work-conjugate
/// to the nodal forces, and on dilatant flow the mismatch feeds the kinetic energy: a
/// smooth strip footing on c = 10 kPa, φ = ψ = 30° soil stops at K_E > 10 (docs/verification.md).
/// Making the forces conjugate (the mean stress projected the same way) is stable there but
/// spreads a shear band's dilation into the soil around it, which loses confinement: the
/// limit pressure falls 12 % below Prandtl–Reissner and the footing then sinks without end.
pub(super) fn check_smoothing(loaded: &LoadedScene) -> Result<(), SceneError> {
    let s = &loaded.scene;
    for (name, m) in s.every_material() {
        let psi = m.dilatancy_angle();
        if psi > 0.0 {
            return Err(loaded.invalid(
                "solver.anti_locking",
                format!(
                    "material \"{name}\" dilates (ψ = {psi}°): volumetric smoothing is for plastic \
                     flow without volume change (ψ = 0) and makes a run with dilatant flow \
                     unstable (docs/verification.md); use CellMean, or ψ = 0"
                ),
            ));
        }
    }
    Ok(())
}

/// Every material, checked by its own scene entry; the models in name order.
pub(super) fn check_materials(r: &Rules) -> Result<Vec<(String, MaterialModel)>, SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    if s.materials.is_empty() {
        return r.bad("materials", "the scene defines no material".into());
    }
    let mut table = Vec::new();
    for (name, m) in &s.materials {
        let at = |f: &str| format!("materials.{name}.{f}");
        let model = m
            .model(&at)
            .map_err(|Refusal { field, rule }| loaded.invalid(&field, rule))?;
        table.push((name.clone(), model));
    }
    Ok(table)
}
