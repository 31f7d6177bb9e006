//! The grid: origin, cell size and counts, the shape's needs, and the face conditions.

use super::rules::*;
use crate::error::Refusal;
use crate::error::SceneError;
pub use crate::model::FaceHold;
use crate::rigid::check_friction_angle;
use crate::scene::spec::{pad3, BoundarySpec, Condition};
use crate::shape::ShapeKind;

/// The grid as set-up builds it, checked.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckedGrid {
    /// The grid's lower corner (m), padded to three axes with zeros.
    pub origin: [f64; 3],
    /// Cell size h (m).
    pub cell_size: f64,
    /// Cells per axis (0 on the axis a 2D grid does not have).
    pub cells: [usize; 3],
    /// Half the width of a point's box per axis, in cells (uniform GIMP): 1/(2n) with n
    /// points a cell side in the first body (uniform GIMP requires the same in all); 1/4
    /// (two a side) where the scene has no body.
    pub half_width: [f64; 3],
    /// The scene's face conditions.
    pub faces: Vec<FaceHold>,
}

/// In an axisymmetric scene the lower x face is the axis, a symmetry face: a `Roller`
/// (u_r = 0 and free along it), and nothing else. `field`: where the faces are.
pub(super) fn check_axis(faces: &[FaceHold], field: &str) -> Result<(), Refusal> {
    let axis = faces.iter().find(|f| f.axis == 0 && !f.upper);
    match axis {
        Some(f) if f.mask == 1 && f.friction.is_none() => Ok(()),
        _ => Err(Refusal::new(
            field.to_string(),
            "the axis of an axisymmetric scene (the XMin face, r = 0) is a symmetry face: give it \
             `(face: XMin, condition: Roller)`, and no other condition"
                .into(),
        )),
    }
}

/// Checks a list of face conditions (`field`: where it is in the scene): faces of the
/// grid's dimension `n`, one condition a face. Returns them as the nodes hold them.
pub(super) fn check_faces(list: &[BoundarySpec], field: &str, n: usize) -> Result<Vec<FaceHold>, Refusal> {
    let mut holds = Vec::with_capacity(list.len());
    for (i, bc) in list.iter().enumerate() {
        if bc.face.axis_side().0 >= n {
            return Err(Refusal::new(
                format!("{field}[{i}].face"),
                format!("{:?} does not exist in {n}D", bc.face),
            ));
        }
        // One condition a face: two would leave the reader to guess which one holds.
        if let Some(j) = list[..i].iter().position(|o| o.face == bc.face) {
            return Err(Refusal::new(
                format!("{field}[{i}].face"),
                format!(
                    "{:?} already has a condition ({field}[{j}]): give each face one condition \
                     (Fixed holds every component, Roller and Friction the normal one)",
                    bc.face
                ),
            ));
        }
        let (axis, upper) = bc.face.axis_side();
        let (mask, friction) = match bc.condition {
            Condition::Fixed => ((1u8 << n) - 1, None),
            Condition::Roller => (1u8 << axis, None),
            Condition::Friction(angle) => {
                check_friction_angle(angle)
                    .map_err(|r| Refusal::new(format!("{field}[{i}].condition"), r))?;
                (1u8 << axis, Some(angle.to_radians().tan()))
            }
        };
        holds.push(FaceHold {
            axis,
            upper,
            mask,
            friction,
        });
    }
    Ok(holds)
}

/// The grid: origin, cells and cell size, and its face conditions.
pub(super) fn check_grid(r: &Rules) -> Result<CheckedGrid, SceneError> {
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
    let faces = check_faces(&s.boundaries, "boundaries", n)
        .map_err(|Refusal { field, rule }| r.loaded.invalid(&field, rule))?;
    if s.dimension == crate::scene::spec::Dimension::Axisymmetric {
        if s.grid.origin[0] != 0.0 {
            return r.bad(
                "grid.origin",
                format!(
                    "an axisymmetric grid starts on the axis, at x = r = 0 (found x = {}): the \
                     points lie at r ≥ 0",
                    s.grid.origin[0]
                ),
            );
        }
        check_axis(&faces, "boundaries").map_err(|Refusal { field, rule }| r.loaded.invalid(&field, rule))?;
    }
    let mut cells = [0usize; 3];
    cells[..n].copy_from_slice(&s.grid.cells);
    let mut half_width = [0.25; 3];
    if let Some(b) = s.bodies.first() {
        for (w, &per) in half_width.iter_mut().zip(&b.points_per_cell) {
            *w = 0.5 / per as f64;
        }
    }
    Ok(CheckedGrid {
        origin: pad3(&s.grid.origin),
        cell_size: s.grid.cell_size,
        cells,
        half_width,
        faces,
    })
}
