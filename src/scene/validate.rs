//! Rules a scene must satisfy before anything is built or written, and the figures derived
//! from it.

use super::{LoadedScene, MaterialSpec, Region, TimeStep};
use crate::error::SceneError;
use crate::materials::{LinearElastic, Material, MaterialModel, MohrCoulomb};
use crate::shape::ShapeKind;
use serde::Serialize;

/// Figures derived from a valid scene (printed by `kdmpm check`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Derived {
    /// Largest P-wave speed sqrt(M/ρ) over the materials the bodies use (m/s).
    pub p_wave_speed: f64,
    /// Critical time step h / c_p (s).
    pub critical_time_step: f64,
    /// Time step used (s).
    pub time_step: f64,
    /// Material points (load carriers included).
    pub points: usize,
    /// Nodes touched by the points at the start.
    pub active_nodes: usize,
    /// Grid nodes in all.
    pub grid_nodes: usize,
    /// Systems of one step, in order.
    pub systems: Vec<String>,
    /// Materials the scene defines but no body uses, in name order. They are validated
    /// like the others but do not set the time step.
    pub unused_materials: Vec<String>,
}

/// What [`check`] establishes.
#[derive(Clone, Debug)]
pub struct Checked {
    /// Every material the scene defines, in name order.
    pub materials: Vec<(String, MaterialModel)>,
    /// Largest P-wave speed sqrt(M/ρ) over the materials the bodies use (m/s).
    pub p_wave_speed: f64,
    /// Critical time step h / c_p (s).
    pub critical_time_step: f64,
    /// Time step to use (s).
    pub time_step: f64,
    /// Materials no body uses, in name order.
    pub unused_materials: Vec<String>,
}

/// True for a finite number > 0 (NaN fails).
fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

/// True for a finite number ≥ 0 (NaN fails).
fn non_negative(x: f64) -> bool {
    x >= 0.0 && x.is_finite()
}

/// Checks every rule that does not need the points.
pub fn check(loaded: &LoadedScene) -> Result<Checked, SceneError> {
    let s = &loaded.scene;
    let bad = |field: &str, rule: String| Err(loaded.invalid(field, rule));
    if s.dimension != 2 && s.dimension != 3 {
        return bad("dimension", format!("must be 2 or 3, found {}", s.dimension));
    }
    let n = s.dimension as usize;
    let len = |field: &str, v: usize| -> Result<(), SceneError> {
        if v != n {
            return Err(loaded.invalid(field, format!("needs {n} entries (dimension {n}), found {v}")));
        }
        Ok(())
    };
    len("grid.origin", s.grid.origin.len())?;
    len("grid.cells", s.grid.cells.len())?;
    if !positive(s.grid.cell_size) {
        return bad(
            "grid.cell_size",
            format!("must be > 0 m, found {}", s.grid.cell_size),
        );
    }
    let min_cells = if s.shape == ShapeKind::QuadraticBSpline {
        2
    } else {
        1
    };
    if let Some(c) = s.grid.cells.iter().find(|&&c| c < min_cells) {
        return bad(
            "grid.cells",
            format!(
                "every axis needs at least {min_cells} cell(s) with {:?} shape functions, found {c}",
                s.shape
            ),
        );
    }
    if s.materials.is_empty() {
        return bad("materials", "the scene defines no material".into());
    }
    let mut table = Vec::new();
    for (name, m) in &s.materials {
        let at = |f: &str| format!("materials.{name}.{f}");
        let (rho, e, nu) = match m {
            MaterialSpec::LinearElastic {
                density,
                youngs_modulus,
                poisson_ratio,
            }
            | MaterialSpec::MohrCoulomb {
                density,
                youngs_modulus,
                poisson_ratio,
                ..
            } => (*density, *youngs_modulus, *poisson_ratio),
        };
        if !positive(rho) {
            return bad(&at("density"), format!("must be > 0 kg/m³, found {rho}"));
        }
        if !positive(e) {
            return bad(&at("youngs_modulus"), format!("must be > 0 Pa, found {e}"));
        }
        if !(0.0..0.5).contains(&nu) {
            return bad(&at("poisson_ratio"), format!("must be in [0, 0.5), found {nu}"));
        }
        let model = match m {
            MaterialSpec::LinearElastic { .. } => {
                MaterialModel::LinearElastic(LinearElastic::new(rho, e, nu))
            }
            MaterialSpec::MohrCoulomb {
                cohesion,
                friction_angle,
                dilatancy_angle,
                tension_cutoff,
                ..
            } => {
                let (c, phi, psi) = (*cohesion, *friction_angle, *dilatancy_angle);
                if !non_negative(c) {
                    return bad(&at("cohesion"), format!("must be ≥ 0 Pa, found {c}"));
                }
                if !(0.0..90.0).contains(&phi) {
                    return bad(
                        &at("friction_angle"),
                        format!("must be in [0°, 90°), found {phi}°"),
                    );
                }
                if !(non_negative(psi) && psi <= phi) {
                    return bad(
                        &at("dilatancy_angle"),
                        format!("must be in [0°, φ = {phi}°], found {psi}°"),
                    );
                }
                if phi == 0.0 && c == 0.0 {
                    return bad(
                        &at("cohesion"),
                        "with φ = 0 the cohesion must be > 0 (no strength at all)".into(),
                    );
                }
                MaterialModel::MohrCoulomb(MohrCoulomb::new(rho, e, nu, c, phi, psi, *tension_cutoff))
            }
        };
        table.push((name.clone(), model));
    }
    if !positive(s.solver.tolerance) {
        return bad(
            "solver.tolerance",
            format!("must be > 0, found {}", s.solver.tolerance),
        );
    }
    if let crate::state::Damping::Viscous { beta } = s.solver.damping {
        if !non_negative(beta) {
            return bad(
                "solver.damping",
                format!("viscous β must be ≥ 0 (1/s), found {beta}"),
            );
        }
    }
    if let Some(c) = s.solver.static_check {
        if !positive(c.window) {
            return bad(
                "solver.static_check.window",
                format!("must be > 0 s, found {}", c.window),
            );
        }
        if !positive(c.max_displacement) {
            return bad(
                "solver.static_check.max_displacement",
                format!("must be > 0 m, found {}", c.max_displacement),
            );
        }
    }
    for (field, value) in [
        ("solver.node_mass_cutoff", s.solver.node_mass_cutoff),
        ("solver.virtual_mass_floor", s.solver.virtual_mass_floor),
    ] {
        if !(0.0..1.0).contains(&value) {
            return bad(
                field,
                format!("must be in [0, 1) (a fraction of a full node's mass), found {value}"),
            );
        }
    }
    if !(0.0..=1.0).contains(&s.solver.flip) {
        return bad(
            "solver.flip",
            format!("must be in [0, 1] (1 = FLIP, 0 = PIC), found {}", s.solver.flip),
        );
    }
    if s.solver.max_steps.is_none() && s.solver.max_time.is_none() {
        return bad(
            "solver",
            "set max_steps or max_time, so that a run that never converges still ends".into(),
        );
    }
    if s.solver.max_steps == Some(0) {
        return bad("solver.max_steps", "must be ≥ 1".into());
    }
    if let Some(t) = s.solver.max_time {
        if !positive(t) {
            return bad("solver.max_time", format!("must be > 0 s, found {t}"));
        }
    }
    if s.output.history_every == 0 {
        return bad("output.history_every", "must be ≥ 1".into());
    }
    if s.bodies.is_empty() {
        return bad(
            "bodies",
            "the scene has no body: there is nothing to simulate".into(),
        );
    }
    for (b, body) in s.bodies.iter().enumerate() {
        if !s.materials.contains_key(&body.material) {
            let known: Vec<_> = s.materials.keys().map(String::as_str).collect();
            return bad(
                &format!("bodies[{b}].material"),
                format!(
                    "unknown material \"{}\" (defined: {})",
                    body.material,
                    known.join(", ")
                ),
            );
        }
        len(
            &format!("bodies[{b}].points_per_cell"),
            body.points_per_cell.len(),
        )?;
        if body.points_per_cell.contains(&0) {
            return bad(
                &format!("bodies[{b}].points_per_cell"),
                "every entry must be ≥ 1".into(),
            );
        }
        match &body.region {
            Region::Box { min, max } => {
                len(&format!("bodies[{b}].region.min"), min.len())?;
                len(&format!("bodies[{b}].region.max"), max.len())?;
                if min.iter().zip(max).any(|(a, b)| !positive(b - a)) {
                    return bad(
                        &format!("bodies[{b}].region"),
                        "box needs min < max on every axis".into(),
                    );
                }
            }
            Region::Polygon { vertices, z } => {
                if vertices.len() < 3 {
                    return bad(
                        &format!("bodies[{b}].region.vertices"),
                        "a polygon needs at least 3 vertices".into(),
                    );
                }
                if let Some(k) = vertices.iter().position(|v| v.len() != 2) {
                    return bad(
                        &format!("bodies[{b}].region.vertices"),
                        format!("vertex {k} needs 2 entries [x, y], found {}", vertices[k].len()),
                    );
                }
                if n == 3 && !z.as_ref().is_some_and(|z| z.len() == 2 && positive(z[1] - z[0])) {
                    return bad(
                        &format!("bodies[{b}].region"),
                        "in 3D a polygon needs z: [z_min, z_max] with z_min < z_max".into(),
                    );
                }
            }
        }
    }
    for (i, bc) in s.boundaries.iter().enumerate() {
        if bc.face.axis_side().0 >= n {
            return bad(
                &format!("boundaries[{i}].face"),
                format!("{:?} does not exist in {n}D", bc.face),
            );
        }
    }
    if let Some(g) = &s.gravity {
        len("gravity.acceleration", g.acceleration.len())?;
        if !non_negative(g.ramp_time) {
            return bad(
                "gravity.ramp_time",
                format!("must be ≥ 0 s, found {}", g.ramp_time),
            );
        }
    }
    for (i, l) in s.point_loads.iter().enumerate() {
        len(&format!("point_loads[{i}].position"), l.position.len())?;
        len(&format!("point_loads[{i}].force"), l.force.len())?;
    }
    for (i, t) in s.traced.iter().enumerate() {
        len(&format!("traced[{i}].position"), t.position.len())?;
    }
    // Only materials that bodies use set the time step: a stiff material kept in a scene
    // for later would otherwise make every run take more steps for nothing.
    let used = |name: &str| s.bodies.iter().any(|b| b.material == name);
    let c_p = table
        .iter()
        .filter(|(name, _)| used(name))
        .map(|(_, m)| (m.p_wave_modulus() / m.density()).sqrt())
        .fold(0.0f64, f64::max);
    let unused_materials = table
        .iter()
        .filter(|(name, _)| !used(name))
        .map(|(name, _)| name.clone())
        .collect();
    let dt_crit = s.grid.cell_size / c_p;
    let dt = match s.solver.time_step {
        TimeStep::Fixed(dt) => {
            if !positive(dt) {
                return bad(
                    "solver.time_step",
                    format!("Fixed(Δt) needs Δt > 0 s, found {dt}"),
                );
            }
            if dt > dt_crit {
                return bad(
                    "solver.time_step",
                    format!(
                        "Δt = {dt} s is above the critical step h/c_p = {dt_crit:.6} s (c_p = {c_p:.4} m/s) \
                         by {:.1} %: the explicit scheme would be unstable",
                        100.0 * (dt / dt_crit - 1.0)
                    ),
                );
            }
            dt
        }
        TimeStep::Courant(a) => {
            if !(positive(a) && a <= 1.0) {
                return bad(
                    "solver.time_step",
                    format!("Courant(α) needs 0 < α ≤ 1, found {a}"),
                );
            }
            a * dt_crit
        }
    };
    Ok(Checked {
        materials: table,
        p_wave_speed: c_p,
        critical_time_step: dt_crit,
        time_step: dt,
        unused_materials,
    })
}
