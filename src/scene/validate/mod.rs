//! Rules a scene must satisfy before anything is built or written, and the figures derived
//! from it. Each part of a scene has its file here and checks itself through [`Rules`],
//! which names the field and the rule it breaks; [`check`] runs them in order and returns
//! what set-up needs from them ([`Checked`]: the grid and its faces, the built materials,
//! each stage's materials and faces, the time step, the memory bound), so nothing is checked or built twice. A new part of a
//! scene (a rigid body, a water table) is a new file with its check, one line in [`check`].

mod bodies;
mod grid;
mod loads;
mod materials;
mod memory;
mod motions;
mod rigid_bodies;
mod rules;
mod solver;
mod stages;
mod water;

pub use grid::{CheckedGrid, FaceHold};
pub(crate) use memory::carried_state;
pub use memory::Estimate;
pub(crate) use motions::check_motion_boxes;
pub use stages::CheckedStage;

use bodies::check_bodies;
use grid::check_grid;
use loads::{check_has_load, check_loads, check_tractions_and_traced};
use materials::check_materials;
use memory::check_memory;
use motions::check_motions_and_analyses;
use rigid_bodies::check_rigid_bodies;
use rules::Rules;
use solver::{check_solver, time_step};
use stages::check_stages;
pub(crate) use water::check_saturated;
use water::check_water;

use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::scene::loaded::LoadedScene;
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
    /// The memory bound checked before anything was allocated.
    pub estimate: Estimate,
    /// Each rigid body as `kdmpm check` describes it: its name, parts, control and travel.
    pub bodies: Vec<String>,
    /// The water as `kdmpm check` describes it: γ_w, gravity's axis and the stages that
    /// move it.
    pub water: Option<String>,
}

impl std::fmt::Display for Derived {
    /// The figures as `kdmpm check` prints them, one a line.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "  points                {}", self.points)?;
        writeln!(
            f,
            "  active nodes          {} of {}",
            self.active_nodes, self.grid_nodes
        )?;
        writeln!(f, "  P-wave speed          {:.6} m/s", self.p_wave_speed)?;
        writeln!(f, "  critical time step    {:.6e} s", self.critical_time_step)?;
        writeln!(
            f,
            "  time step             {:.6e} s (Courant {:.3})",
            self.time_step,
            self.time_step / self.critical_time_step
        )?;
        writeln!(
            f,
            "  memory (bound)        {:.1} MB ({} points, {} nodes at most)",
            self.estimate.bytes as f64 / 1e6,
            self.estimate.points,
            self.estimate.nodes
        )?;
        for b in &self.bodies {
            writeln!(f, "  rigid body            {b}")?;
        }
        if let Some(w) = &self.water {
            writeln!(f, "  water                 {w}")?;
        }
        writeln!(f, "  systems               {}", self.systems.join(" → "))?;
        if !self.unused_materials.is_empty() {
            writeln!(
                f,
                "  unused materials      {} (no body uses them; they do not set the time step)",
                self.unused_materials.join(", ")
            )?;
        }
        Ok(())
    }
}

/// What [`check`] establishes.
#[derive(Clone, Debug)]
pub struct Checked {
    /// The grid and its face conditions.
    pub grid: CheckedGrid,
    /// Every material the scene defines, in name order.
    pub materials: Vec<(String, MaterialModel)>,
    /// Each stage's materials (by index in `materials`) and face conditions, in stage order.
    pub stages: Vec<CheckedStage>,
    /// Largest P-wave speed sqrt(M/ρ) over the materials the bodies use (m/s).
    pub p_wave_speed: f64,
    /// Critical time step h / c_p (s).
    pub critical_time_step: f64,
    /// Time step to use (s).
    pub time_step: f64,
    /// Materials no body uses, in name order.
    pub unused_materials: Vec<String>,
    /// What the run will hold in memory, at most.
    pub estimate: Estimate,
    /// Each rigid body's contact samples (in its starting frame, with its part), in scene
    /// order: cut once here, for the memory bound, and handed to set-up.
    pub body_samples: Vec<crate::rigid::Samples>,
    /// The water, if any.
    pub water: Option<crate::water::Water>,
}

/// A displacement control's first step of an increment moves at its full velocity: an
/// increment (or a whole travel) shorter than one step's travel v Δt would be overshot, a
/// silently wrong curve. Refused, motions and rigid bodies alike.
fn check_increments_span_a_step(r: &Rules, dt: f64) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    let controls = s
        .motions
        .iter()
        .enumerate()
        .map(|(i, m)| (format!("motions[{i}]"), m.speed(), m.travel, m.increment))
        .chain(s.rigid_bodies.iter().enumerate().filter_map(|(i, b)| {
            let m = b.motion.as_ref()?;
            Some((
                format!("rigid_bodies[{i}].motion"),
                m.speed(),
                m.travel,
                m.increment,
            ))
        }));
    for (field, speed, travel, increment) in controls {
        let (name, length) = match increment {
            Some(inc) if inc < travel => ("increment", inc),
            _ => ("travel", travel),
        };
        let step = speed * dt;
        if length < step * (1.0 - 1e-9) {
            return r.bad(
                &format!("{field}.{name}"),
                format!(
                    "{length} m is shorter than one step's travel, v Δt = {step:.4e} m (Δt = \
                     {dt:.4e} s): its first step would overshoot it; lower the velocity or \
                     lengthen the {name}"
                ),
            );
        }
    }
    Ok(())
}

/// Checks every rule that does not need the points, part by part.
pub fn check(loaded: &LoadedScene) -> Result<Checked, SceneError> {
    let s = &loaded.scene;
    let r = Rules {
        loaded,
        n: s.dimension.axes(),
    };
    let grid = check_grid(&r)?;
    let table = check_materials(&r)?;
    check_solver(&r)?;
    check_bodies(&r)?;
    check_loads(&r, &table)?;
    check_motions_and_analyses(&r)?;
    check_rigid_bodies(&r)?;
    check_tractions_and_traced(&r)?;
    check_has_load(&r)?;
    let step = time_step(&r, &table)?;
    check_increments_span_a_step(&r, step.dt)?;
    let stages = check_stages(&r, &table, step.p_wave_speed)?;
    let (estimate, body_samples) = check_memory(&r, &table)?;
    let (water, stage_waters) = check_water(&r, &grid, &table, &stages)?;
    let mut stages = stages;
    for (st, w) in stages.iter_mut().zip(stage_waters) {
        st.water = w;
    }
    Ok(Checked {
        grid,
        materials: table,
        stages,
        p_wave_speed: step.p_wave_speed,
        critical_time_step: step.critical,
        time_step: step.dt,
        unused_materials: step.unused_materials,
        estimate,
        body_samples,
        water,
    })
}
