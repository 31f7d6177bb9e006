//! The solver settings, and the time step they and the materials give (Courant, mass
//! scaling, the scheme's limits).

use super::rules::*;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::scene::spec::TimeStep;
use crate::state::Scheme;

/// The largest Courant number accepted with the USL scheme. Measured on the self-weight
/// column (`studies/courant.ron`): USL with linear shapes diverges from Courant 0.8 and with
/// quadratic B-splines never settles at 1.0; on the 2D slope it loses a point at Courant 1.
pub const USL_COURANT_LIMIT: f64 = 0.7;

/// The largest Courant number (of the slowest material) accepted with mass scaling.
/// Measured on a soil layer on rock a million times stiffer (`tests/engine/extremes.rs`): it
/// settles at Courant 0.5 to 0.9 and diverges at step 59 at Courant 1.
pub const MASS_SCALING_COURANT_LIMIT: f64 = 0.9;

/// Largest step count a `max_time` without `max_steps` may imply: 10^12 steps of the
/// smallest scene would take days; a larger count is a time step too small to mean it.
pub(super) const MAX_IMPLIED_STEPS: f64 = 1e12;

/// The time step and what set it.
pub(super) struct StepChoice {
    /// Largest (smallest with mass scaling) P-wave speed of the materials bodies use (m/s).
    pub(super) p_wave_speed: f64,
    /// h / c_p (s).
    pub(super) critical: f64,
    /// The time step (s).
    pub(super) dt: f64,
    /// Materials no body uses, in name order.
    pub(super) unused_materials: Vec<String>,
}

/// The solver's and the output's settings that stand alone.
pub(super) fn check_solver(r: &Rules) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    if !positive(s.solver.tolerance) {
        return r.bad(
            "solver.tolerance",
            format!("must be > 0, found {}", s.solver.tolerance),
        );
    }
    if let crate::state::Damping::Viscous { beta } = s.solver.damping {
        if !non_negative(beta) {
            return r.bad(
                "solver.damping",
                format!("viscous β must be ≥ 0 (1/s), found {beta}"),
            );
        }
    }
    if let Some(snap) = s.output.snapshots {
        if snap.every_steps == Some(0) {
            return r.bad("output.snapshots.every_steps", "must be ≥ 1 step".to_string());
        }
        if let Some(t) = snap.every_time {
            if !positive(t) {
                return r.bad("output.snapshots.every_time", format!("must be > 0 s, found {t}"));
            }
        }
        if snap.every_steps.is_none() && snap.every_time.is_none() && !snap.at_resets {
            return r.bad(
                "output.snapshots",
                "takes no snapshot but the last: set every_steps, every_time or at_resets".to_string(),
            );
        }
    }
    if s.solver.peak_interpolation && s.solver.damping != crate::state::Damping::Kinetic {
        return r.bad(
            "solver.peak_interpolation",
            "places kinetic-damping resets: it needs `damping: Kinetic`".to_string(),
        );
    }
    if let crate::state::Damping::Local { alpha } = s.solver.damping {
        if !(non_negative(alpha) && alpha < 1.0) {
            return r.bad(
                "solver.damping",
                format!("local damping α must be in [0, 1), found {alpha}"),
            );
        }
    }
    if let Some(c) = s.solver.static_check {
        if !positive(c.window) {
            return r.bad(
                "solver.static_check.window",
                format!("must be > 0 s, found {}", c.window),
            );
        }
        if !positive(c.max_displacement) {
            return r.bad(
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
            return r.bad(
                field,
                format!("must be in [0, 1) (a fraction of a full node's mass), found {value}"),
            );
        }
    }
    let t = s.solver.contact_tolerance;
    if !(t > 0.0 && t <= 1e-3) {
        return r.bad(
            "solver.contact_tolerance",
            format!(
                "must be in (0, 1e-3] (a fraction of the contact solve's scale; looser leaves \
                 part of each step's entry into a body), found {t}"
            ),
        );
    }
    if !(0.0..=1.0).contains(&s.solver.flip) {
        return r.bad(
            "solver.flip",
            format!("must be in [0, 1] (1 = FLIP, 0 = PIC), found {}", s.solver.flip),
        );
    }
    if s.solver.max_steps.is_none() && s.solver.max_time.is_none() {
        return r.bad(
            "solver",
            "set max_steps or max_time, so that a run that never converges still ends".into(),
        );
    }
    if s.solver.max_steps == Some(0) {
        return r.bad("solver.max_steps", "must be ≥ 1".into());
    }
    if let Some(t) = s.solver.max_time {
        if !positive(t) {
            return r.bad("solver.max_time", format!("must be > 0 s, found {t}"));
        }
    }
    match s.solver.checkpoint_every {
        Some(crate::scene::spec::CheckpointEvery::Steps(0)) => {
            return r.bad("solver.checkpoint_every", "Steps(n) needs n ≥ 1".into());
        }
        Some(crate::scene::spec::CheckpointEvery::Seconds(t)) if !positive(t) => {
            return r.bad(
                "solver.checkpoint_every",
                format!("Seconds(t) needs a wall time t > 0 s, found {t}"),
            );
        }
        _ => {}
    }
    if s.output.history_every == 0 {
        return r.bad("output.history_every", "must be ≥ 1".into());
    }
    Ok(())
}

/// The time step: the critical one of the materials bodies use, and the scheme's limits.
pub(super) fn time_step(r: &Rules, table: &[(String, MaterialModel)]) -> Result<StepChoice, SceneError> {
    let s = &r.loaded.scene;
    // Only materials that bodies use set the time step: a stiff material kept in a scene
    // for later would otherwise make every run take more steps for nothing.
    let used = |name: &str| s.bodies.iter().any(|b| b.material == name);
    // With mass scaling the slowest material sets the step; the others are given inertia.
    let speeds = table
        .iter()
        .filter(|(name, _)| used(name))
        .map(|(_, m)| (m.p_wave_modulus() / m.density()).sqrt());
    let c_p = if s.solver.mass_scaling {
        speeds.fold(f64::INFINITY, f64::min)
    } else {
        speeds.fold(0.0f64, f64::max)
    };
    let unused_materials = table
        .iter()
        .filter(|(name, _)| !used(name))
        .map(|(name, _)| name.clone())
        .collect();
    let dt_crit = s.grid.cell_size / c_p;
    if !positive(dt_crit) {
        return r.bad(
            "grid.cell_size",
            format!(
                "the critical time step h/c_p = {} m / {c_p} m/s = {dt_crit} s is not a finite number > 0",
                s.grid.cell_size
            ),
        );
    }
    let dt = chosen_step(r, dt_crit, c_p)?;
    step_limits(r, dt, dt_crit)?;
    Ok(StepChoice {
        p_wave_speed: c_p,
        critical: dt_crit,
        dt,
        unused_materials,
    })
}

/// The time step the solver asks for (s): a fixed Δt no longer than the critical step
/// `dt_crit` (s; `c_p` m/s the P-wave speed that set it), or a Courant fraction of it.
fn chosen_step(r: &Rules, dt_crit: f64, c_p: f64) -> Result<f64, SceneError> {
    let s = &r.loaded.scene;
    Ok(match s.solver.time_step {
        TimeStep::Fixed(dt) => {
            if !positive(dt) {
                return r.bad(
                    "solver.time_step",
                    format!("Fixed(Δt) needs Δt > 0 s, found {dt}"),
                );
            }
            if dt > dt_crit {
                return r.bad(
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
                return r.bad(
                    "solver.time_step",
                    format!("Courant(α) needs 0 < α ≤ 1, found {a}"),
                );
            }
            a * dt_crit
        }
    })
}

/// The limits on a time step `dt` (s) beyond the critical one `dt_crit` (s): mass
/// scaling's and USL's Courant numbers, viscous damping's βΔt ≤ 1, a step that advances
/// the clock, and no more than [`MAX_IMPLIED_STEPS`] steps in `max_time`.
fn step_limits(r: &Rules, dt: f64, dt_crit: f64) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    if s.solver.mass_scaling && dt > MASS_SCALING_COURANT_LIMIT * dt_crit * (1.0 + 1e-12) {
        return r.bad(
            "solver.time_step",
            format!(
                "Δt = {dt:.6e} s is Courant {:.3} of the slowest material; with mass scaling the \
                 nodes where stiff and soft points meet diverge above Courant {MASS_SCALING_COURANT_LIMIT} \
                 (docs/verification.md): use Courant({MASS_SCALING_COURANT_LIMIT}) or less",
                dt / dt_crit
            ),
        );
    }
    if s.solver.scheme == Scheme::Usl && dt > USL_COURANT_LIMIT * dt_crit * (1.0 + 1e-12) {
        return r.bad(
            "solver.time_step",
            format!(
                "Δt = {dt:.6e} s is Courant {:.3}; USL is unstable above Courant {USL_COURANT_LIMIT} \
                 (it diverges or never settles there, see docs/verification.md): use \
                 Courant({USL_COURANT_LIMIT}) or less, or scheme Musl or Usf, which are stable up to 1",
                dt / dt_crit
            ),
        );
    }
    // Explicit viscous damping scales a node's velocity by (1 − 2βΔt) each step: above
    // βΔt = 1 that factor is below −1 and the velocities grow without bound.
    if let crate::state::Damping::Viscous { beta } = s.solver.damping {
        if beta * dt > 1.0 {
            return r.bad(
                "solver.damping",
                format!(
                    "viscous β = {beta:e} 1/s with Δt = {dt:.6e} s gives βΔt = {:.3e}: explicit viscous \
                     damping is unstable above βΔt = 1; use β ≤ {:.6e} 1/s",
                    beta * dt,
                    1.0 / dt
                ),
            );
        }
    }
    // A time step that rounds to zero or to a subnormal never advances the clock: the run
    // would write history rows for ever without getting anywhere.
    if !dt.is_normal() {
        return r.bad(
            "solver.time_step",
            format!("gives Δt = {dt:e} s, too small to advance the simulated time"),
        );
    }
    if let (Some(t), None) = (s.solver.max_time, s.solver.max_steps) {
        let steps = t / dt;
        if steps > MAX_IMPLIED_STEPS {
            return r.bad(
                "solver.max_time",
                format!(
                    "{t} s at Δt = {dt:e} s is {steps:.3e} steps (more than {MAX_IMPLIED_STEPS:e}): \
                     set max_steps as well, or a shorter max_time"
                ),
            );
        }
    }
    Ok(())
}
