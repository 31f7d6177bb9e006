//! The grid: origin, cell size and counts, the shape's needs, and the face conditions.

use super::*;
use crate::error::SceneError;
use crate::scene::BoundarySpec;
use crate::shape::ShapeKind;

/// Checks a list of face conditions (`field`: where it is in the scene): faces of the
/// grid's dimension `n`, one condition a face.
pub(super) fn check_faces(list: &[BoundarySpec], field: &str, n: usize) -> Result<(), (String, String)> {
    for (i, bc) in list.iter().enumerate() {
        if bc.face.axis_side().0 >= n {
            return Err((
                format!("{field}[{i}].face"),
                format!("{:?} does not exist in {n}D", bc.face),
            ));
        }
        // One condition a face: two would leave the reader to guess which one holds.
        if let Some(j) = list[..i].iter().position(|o| o.face == bc.face) {
            return Err((
                format!("{field}[{i}].face"),
                format!(
                    "{:?} already has a condition ({field}[{j}]): give each face one condition \
                     (Fixed holds every component, Roller the normal one)",
                    bc.face
                ),
            ));
        }
    }
    Ok(())
}

/// The grid: origin, cells and cell size.
pub(super) fn check_grid(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    r.len("grid.origin", s.grid.origin.len())?;
    r.finite("grid.origin", &s.grid.origin, "m")?;
    r.len("grid.cells", s.grid.cells.len())?;
    if !positive(s.grid.cell_size) {
        return r.bad(
            "grid.cell_size",
            format!("must be > 0 m, found {}", s.grid.cell_size),
        );
    }
    if s.shape == ShapeKind::UniformGimp {
        if let Some(i) = s
            .bodies
            .iter()
            .position(|b| b.points_per_cell != s.bodies[0].points_per_cell)
        {
            return r.bad(
                &format!("bodies[{i}].points_per_cell"),
                "UniformGimp sizes every point's box from its points a cell side: every body needs the same as bodies[0]".to_string(),
            );
        }
    }
    let min_cells = if s.shape.support() == 3 { 2 } else { 1 };
    // The grid's far corner and a cell's volume h^D must be finite numbers > 0: a cell
    // size of 1e-200 m would give cells of zero volume and points of zero mass.
    let cell_volume = s.grid.cell_size.powi(n as i32);
    if !(cell_volume.is_normal() && cell_volume.is_finite()) {
        return r.bad(
            "grid.cell_size",
            format!(
                "h = {:e} m gives a cell volume h^{n} = {cell_volume:e}, which is not a finite number > 0",
                s.grid.cell_size
            ),
        );
    }
    if let Some(a) =
        (0..n).find(|&a| !(s.grid.origin[a] + s.grid.cell_size * s.grid.cells[a] as f64).is_finite())
    {
        return r.bad(
            "grid.cells",
            format!("the grid's far corner along axis {a} is not a finite coordinate"),
        );
    }
    if let Some(c) = s.grid.cells.iter().find(|&&c| c < min_cells) {
        return r.bad(
            "grid.cells",
            format!(
                "every axis needs at least {min_cells} cell(s) with {:?} shape functions, found {c}",
                s.shape
            ),
        );
    }
    Ok(())
}
