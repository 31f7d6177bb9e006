//! The water table: itself ([`crate::water::WaterSpec::checked`]), and the saturated
//! densities of the materials that lie below it. That the ground stands above the table
//! everywhere is checked once the points are placed ([`check_ground`]).

use super::*;
use crate::components::Position;
use crate::dim::{Dim, Vector};
use crate::error::SceneError;
use crate::grid::Grid;
use crate::infra::columns::{col, points_with};
use crate::materials::MaterialModel;
use crate::water::Water;

/// The scene's water, checked, or `None` when the scene is dry.
pub(super) fn check_water(r: &Rules, table: &[(String, MaterialModel)]) -> Result<Option<Water>, SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    let Some(spec) = &s.water else {
        return Ok(None);
    };
    let gravity = s.gravity.as_ref().map(|g| g.acceleration.as_slice());
    let water = spec
        .checked(gravity)
        .map_err(|(f, rule)| loaded.invalid(&f, rule))?;
    for (name, &rho) in &spec.saturated_density {
        let field = format!("water.saturated_density.{name}");
        let Some((_, m)) = table.iter().find(|(n, _)| n == name) else {
            return r.bad(&field, format!("the scene has no material \"{name}\""));
        };
        if !(rho.is_finite() && rho >= m.density()) {
            return r.bad(
                &field,
                format!(
                    "must be at least the material's dry density ({} kg/m³), found {rho}",
                    m.density()
                ),
            );
        }
    }
    for (b, body) in s.bodies.iter().enumerate() {
        let (lo, _) = crate::scene::region_bounds(&body.region, r.n);
        if lo[water.axis] < water.table && !spec.saturated_density.contains_key(&body.material) {
            return r.bad(
                "water.saturated_density",
                format!(
                    "bodies[{b}] reaches below the table: give its material \"{}\" a saturated \
                     density",
                    body.material
                ),
            );
        }
    }
    Ok(Some(water))
}

/// The ground stands above the table in every column of cells: open water above the ground
/// would press on its surface, which this engine does not model yet, and leaving it out
/// would make a slope with a table above its toe fail far too early.
pub(crate) fn check_ground<D: Dim>(
    loaded: &LoadedScene,
    grid: &Grid<D>,
    water: &Water,
    world: &hecs::World,
) -> Result<(), SceneError> {
    // The highest point of each column of cells across gravity's axis.
    let across: Vec<usize> = (0..D::N).filter(|&a| a != water.axis).collect();
    let cells: Vec<usize> = across.iter().map(|&a| grid.axes[a].cells).collect();
    let mut top = vec![f64::NEG_INFINITY; cells.iter().product()];
    for arch in points_with::<Position<D::Vec>>(world) {
        for x in col::<Position<D::Vec>>(arch).iter() {
            let x = D::vec_to3(x.0);
            let mut k = 0;
            for (j, &a) in across.iter().enumerate() {
                let c = ((x[a] - grid.origin.get(a)) * grid.inv_h)
                    .floor()
                    .clamp(0.0, (cells[j] - 1) as f64);
                k = k * cells[j] + c as usize;
            }
            top[k] = top[k].max(x[water.axis]);
        }
    }
    let half = 0.5 * grid.cell_size;
    if let Some(k) = top
        .iter()
        .position(|&t| t > f64::NEG_INFINITY && t + half < water.table)
    {
        return Err(loaded.invalid(
            "water.table",
            format!(
                "the table ({} m) stands above the ground in column {k} of cells (its highest \
                 point at {:.3} m): open water on the surface is not modelled yet; lower the \
                 table below the ground",
                water.table, top[k]
            ),
        ));
    }
    Ok(())
}
