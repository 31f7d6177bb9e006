//! The stages of one explicit MPM step, one file each, and the registry that makes the
//! schedules.
//!
//! [`registry`] holds one [`Entry`] per system: its name, its [`Stage`], when a scene needs
//! it, the systems it must follow and its constructor. The list of names, each scheme's
//! default schedule ([`default_names`]: the scheme's [`scheme_stages`] in order, and in each the
//! systems it needs), the checks on a scene's own `solver.schedule` ([`check_names`]) and
//! the table in docs/writing-a-system.md ([`systems_table`]) all come from it.
//!
//! MUSL with kinetic damping (the default) runs `grid_reset`, `spatial_sort`, `p2g`,
//! `gravity`, `boundary`, `integrate`, `g2p`, `peak_watch`, `remap`, `kinematics`,
//! `stress_update`, `volume_update`, `convergence`. USL drops `remap` (points move with the
//! updated grid velocity); USF maps momentum first (`p2g_momentum`, `nodal_velocity`),
//! updates stress (`velocity_gradient`, `stress_update`, `volume_update`), then maps forces
//! (`p2g_force`) and moves the points at the end (`move_points`).

pub mod boundary;
pub mod cell_mean;
pub mod convergence;
pub mod exchange;
pub mod g2p;
pub mod gravity;
pub mod grid_reset;
mod increments;
pub mod integrate;
pub mod kinematics;
pub mod load_steps;
pub mod mass_scaling;
pub mod migrate;
pub mod nodal_velocity;
mod node_pairs;
pub mod p2g;
pub mod peak_watch;
pub mod point_forces;
pub mod point_loads;
pub mod pore_pressure_field;
pub mod prescribed_motion;
pub mod remap;
pub mod remap_contact;
pub mod rigid_contact;
pub mod rigid_control;
pub mod shared;
pub mod soil_gap;
pub mod soil_side;
pub mod soil_strength;
pub mod spatial_sort;
pub mod stages;
pub mod stress_update;
pub mod volume_update;
pub mod volumetric_smoothing;

pub use boundary::Boundary;
pub use cell_mean::{CellMean, CellMeanPart};
pub use convergence::Convergence;
pub use g2p::G2p;
pub use gravity::Gravity;
pub use grid_reset::GridReset;
pub use integrate::Integrate;
pub use kinematics::Kinematics;
pub use load_steps::LoadControl;
pub use mass_scaling::MassScaling;
pub use nodal_velocity::NodalVelocity;
pub use p2g::{P2g, P2gPart};
pub use peak_watch::PeakWatch;
pub use point_loads::PointLoads;
pub use pore_pressure_field::{PorePressureField, UndrainedStrain};
pub use prescribed_motion::PrescribedMotion;
pub use remap::Remap;
pub use remap_contact::RemapContact;
pub use rigid_contact::RigidContact;
pub use rigid_control::RigidControl;
pub use spatial_sort::SpatialSort;
pub use stages::Stages;
pub use stress_update::StressUpdate;
pub use volume_update::VolumeUpdate;
pub use volumetric_smoothing::VolumetricSmoothing;

use crate::dim::{Dim, Dim2};
use crate::model::Model;
use crate::schedule::{Schedule, System};
use crate::shape::{Linear, QuadraticBSpline, Shape, ShapeKind, UniformGimp};
use crate::state::{AntiLocking, Damping, Numerics, Scheme};

/// What a scene contains that decides which optional systems it needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// The scene has point loads.
    pub point_loads: bool,
    /// A material of the scene or of a stage holds undrained pore water.
    pub undrained: bool,
}

/// The place of a system in a step. A scheme runs its stages in the order
/// [`scheme_stages`] gives; systems of one stage run in registry order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Empty the grid.
    Reset,
    /// Put the points in cell order.
    Sort,
    /// Map mass and momentum (and, but for USF, the internal force).
    Map,
    /// USF: nodal velocity from the mapped momentum.
    NodalVelocity,
    /// Velocity gradient (and, but for USF, the point motion).
    Strain,
    /// Smooth the volumetric strain rate.
    Smooth,
    /// The material law.
    Stress,
    /// Project the updated stress (the cell means of the mean stress).
    Project,
    /// Point volumes.
    Volume,
    /// USF: map the internal force of the updated stress.
    MapForce,
    /// External nodal forces.
    Forces,
    /// Boundary conditions on nodal momentum and force.
    Constrain,
    /// Nodal accelerations and velocities.
    Integrate,
    /// Changes to the integrated nodal accelerations.
    Scale,
    /// Nodal accelerations and velocities to the points.
    Interpolate,
    /// Kinetic damping.
    Damp,
    /// MUSL: point velocities back to the grid.
    Remap,
    /// USF: move the points.
    Move,
    /// Energies, force ratios and the stopping rule.
    Monitor,
    /// Acts on the step's outcome: load and displacement control.
    Control,
}

/// The stages of one step of `scheme`, in order.
pub fn scheme_stages(scheme: Scheme) -> &'static [Stage] {
    use Stage::*;
    match scheme {
        Scheme::Musl | Scheme::Usl => &[
            Reset,
            Sort,
            Map,
            Forces,
            Constrain,
            Integrate,
            Scale,
            Interpolate,
            Damp,
            Remap,
            Strain,
            Smooth,
            Stress,
            Project,
            Volume,
            Monitor,
            Control,
        ],
        Scheme::Usf => &[
            Reset,
            Sort,
            Map,
            NodalVelocity,
            Strain,
            Smooth,
            Stress,
            Project,
            Volume,
            MapForce,
            Forces,
            Constrain,
            Integrate,
            Scale,
            Interpolate,
            Damp,
            Move,
            Monitor,
            Control,
        ],
    }
}

/// When the default schedule holds a system.
#[derive(Clone, Copy)]
pub enum When {
    /// In every scheme's default schedule, and required in any schedule.
    Always,
    /// In the default schedule of these schemes.
    Schemes(&'static [Scheme]),
    /// Exactly when the scene needs it: required then, refused otherwise. The text says
    /// when ("the scene has gravity").
    Needed(fn(&Numerics, &Model, Needs) -> bool, &'static str),
    /// In the default schedule when the scene needs it, and required then; a schedule may
    /// hold it otherwise too (`volume_update`, which the stress update does when left out).
    RequiredWhen(fn(&Numerics, &Model, Needs) -> bool, &'static str),
}

/// Builds a system for a run's numerics and model. What it does may also depend on the
/// systems around it, which the schedule tells it ([`System::schedule_changed`]).
pub type Build<D> = fn(&Numerics, &Model) -> Box<dyn System<D>>;

/// One system: everything the schedule, its checks and the docs know about it.
pub struct Entry<D: Dim> {
    /// The name scenes use in `solver.schedule`, profiles and errors.
    pub name: &'static str,
    /// Its place in a step.
    pub stage: Stage,
    /// When a schedule holds it.
    pub when: When,
    /// Systems it must run after when both are scheduled, and why.
    pub after: &'static [(&'static str, &'static str)],
    /// What it does, one line (the docs' list and `kdmpm check`).
    pub does: &'static str,
    /// Builds it for a run's numerics and model.
    pub build: Build<D>,
}

const MUSL_USL: &[Scheme] = &[Scheme::Musl, Scheme::Usl];
const USF: &[Scheme] = &[Scheme::Usf];
const SORTED: (&str, &str) = (
    "spatial_sort",
    "the points are put in cell order before the step maps them",
);
const STRAINED: &str = "the stress update needs the velocity gradient";
const SMOOTHED: &str = "smoothing works on the velocity gradient";
const COMPLETE: &str = "boundary conditions act on the complete nodal force";
const NOT_IN_RESET: &str = "points must not move in a reset step";
const INTEGRATED: &str = "points move with the integrated velocity";

/// Every system, in the order they run within a stage. The names, the default schedules,
/// the order rules and the list in docs/writing-a-system.md all come from here: a new
/// system is one entry. `S` is the scene's shape function.
pub fn registry<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    let mut all = mapping::<D, S>();
    all.extend(straining::<D, S>());
    all.extend(projecting::<D, S>());
    all.extend(loading::<D, S>());
    all.extend(relaxing::<D, S>());
    all
}

/// One registry entry.
fn e<D: Dim>(
    name: &'static str,
    stage: Stage,
    when: When,
    after: &'static [(&'static str, &'static str)],
    does: &'static str,
    build: Build<D>,
) -> Entry<D> {
    Entry {
        name,
        stage,
        when,
        after,
        does,
        build,
    }
}

/// From the points to the grid: reset, sort, map, nodal velocity.
fn mapping<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    use Stage as St;
    use When::*;
    vec![
        e(
            "grid_reset",
            St::Reset,
            Always,
            &[],
            "empty, undeformed grid",
            |_, _| Box::new(GridReset::default()),
        ),
        e(
            "spatial_sort",
            St::Sort,
            Needed(|n, _, _| n.sort_every > 0, "solver.sort_every is above 0"),
            &[],
            "points back in cell order (every N steps)",
            |n, _| Box::new(SpatialSort::new(n.sort_every)),
        ),
        e(
            "p2g",
            St::Map,
            Schemes(MUSL_USL),
            &[SORTED],
            "mass, momentum, internal force (and each point's other forces, `point_forces.rs`) to the nodes",
            |_, _| Box::new(P2g::<D, S>::new(P2gPart::All)),
        ),
        e(
            "p2g_momentum",
            St::Map,
            Schemes(USF),
            &[SORTED],
            "USF: mass and momentum to the nodes",
            |_, _| Box::new(P2g::<D, S>::new(P2gPart::MassMomentum)),
        ),
        e(
            "nodal_velocity",
            St::NodalVelocity,
            Schemes(USF),
            &[("p2g_momentum", "the nodal velocity needs the mapped momentum")],
            "USF: nodal velocity from momentum",
            |_, _| Box::new(NodalVelocity),
        ),
    ]
}

/// The points' strain and stress.
fn straining<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    use Stage as St;
    use When::*;
    vec![
        e(
            "kinematics",
            St::Strain,
            Schemes(MUSL_USL),
            &[
                ("integrate", INTEGRATED),
                ("peak_watch", NOT_IN_RESET),
                (
                    "remap",
                    "MUSL strains and moves the points with the remapped velocity",
                ),
                (
                    "remap_contact",
                    "the points move with the remapped velocity the contacts hold",
                ),
            ],
            "velocity gradient, position update",
            |_, _| Box::new(Kinematics::<D, S>::both()),
        ),
        e(
            "velocity_gradient",
            St::Strain,
            Schemes(USF),
            &[("nodal_velocity", "the velocity gradient needs the nodal velocity")],
            "USF: velocity gradient",
            |_, _| Box::new(Kinematics::<D, S>::gradient_only()),
        ),
        e(
            "volumetric_smoothing",
            St::Smooth,
            Needed(
                |n, _, _| n.anti_locking == AntiLocking::StrainSmoothing,
                "solver.anti_locking is StrainSmoothing",
            ),
            &[("kinematics", SMOOTHED), ("velocity_gradient", SMOOTHED)],
            "volumetric strain rate smoothed through the nodes",
            |_, _| Box::new(VolumetricSmoothing::<D, S>::default()),
        ),
        e(
            "cell_mean_strain",
            St::Smooth,
            Needed(
                |n, _, _| n.anti_locking == AntiLocking::CellMean,
                "solver.anti_locking is CellMean",
            ),
            &[("kinematics", SMOOTHED), ("velocity_gradient", SMOOTHED)],
            "cell mean of the volumetric strain rate",
            |_, _| Box::new(CellMean::<D, S>::new(CellMeanPart::Strain)),
        ),
        e(
            "undrained_strain",
            St::Smooth,
            Needed(|_, _, n| n.undrained, "a material holds undrained water"),
            &[("kinematics", SMOOTHED), ("velocity_gradient", SMOOTHED)],
            "cell mean of the undrained points' volumetric strain rate",
            |_, _| Box::new(UndrainedStrain::<D, S>::default()),
        ),
        e(
            "stress_update",
            St::Stress,
            Always,
            &[
                ("kinematics", STRAINED),
                ("velocity_gradient", STRAINED),
                ("volumetric_smoothing", "the stress must see the smoothed strain"),
                ("cell_mean_strain", "the stress must see the cell's strain"),
                ("undrained_strain", "the stress must see the cell's strain"),
            ],
            "Jaumann rotation + material law (and V ← V det(I + LΔt) without `volume_update`)",
            |_, _| Box::new(StressUpdate::default()),
        ),
    ]
}

/// The stress's projections onto the cells, the volume update where it runs on its own,
/// and USF's internal force.
fn projecting<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    use Stage as St;
    use When::*;
    vec![
        e(
            "cell_mean_stress",
            St::Project,
            Needed(
                |n, _, _| n.anti_locking == AntiLocking::CellMean,
                "solver.anti_locking is CellMean",
            ),
            &[("stress_update", "it projects the updated stress")],
            "cell mean of the mean stress",
            |_, _| Box::new(CellMean::<D, S>::new(CellMeanPart::Stress)),
        ),
        e(
            "pore_pressure_field",
            St::Project,
            Needed(|_, _, n| n.undrained, "a material holds undrained water"),
            &[
                ("stress_update", "it projects the updated pore pressures"),
                ("cell_mean_stress", "it projects the projected stress's water"),
            ],
            "cell mean of the undrained points' excess pore pressure",
            |_, _| Box::new(PorePressureField::<D, S>::default()),
        ),
        e(
            "volume_update",
            St::Volume,
            RequiredWhen(
                volume_read_after_stress,
                "the cell mean of stress or the undrained water reads the volumes after the stress update",
            ),
            &[("stress_update", "the volume update follows the stress update")],
            "V ← V det(I + LΔt)",
            |_, _| Box::new(VolumeUpdate),
        ),
        e(
            "p2g_force",
            St::MapForce,
            Schemes(USF),
            &[
                ("stress_update", "p2g_force maps the updated stress"),
                ("cell_mean_stress", "p2g_force maps the projected stress"),
                ("pore_pressure_field", "p2g_force maps the water's cell pressure"),
            ],
            "USF: internal force of the updated stress (and each point's other forces)",
            |_, _| Box::new(P2g::<D, S>::new(P2gPart::InternalForce)),
        ),
    ]
}

/// External forces, the held components, integration and back to the points.
fn loading<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    use Stage as St;
    use When::*;
    vec![
        e(
            "gravity",
            St::Forces,
            Needed(|_, m, _| m.gravity.is_some(), "the scene has gravity"),
            &[
                ("p2g", "gravity acts on the nodal mass that p2g maps"),
                (
                    "p2g_momentum",
                    "gravity acts on the nodal mass that p2g_momentum maps",
                ),
            ],
            "body force m_i g",
            |_, _| Box::new(Gravity),
        ),
        e(
            "point_loads",
            St::Forces,
            Needed(|_, _, n| n.point_loads, "the scene has point loads"),
            &[
                ("p2g", "point loads go to nodes that carry mapped mass"),
                ("p2g_momentum", "point loads go to nodes that carry mapped mass"),
            ],
            "concentrated loads",
            |_, _| Box::new(PointLoads::<D, S>::default()),
        ),
        e(
            "rigid_contact",
            St::Constrain,
            Needed(|_, m, _| !m.bodies.is_empty(), "the scene has rigid bodies"),
            &[
                ("p2g", "contact acts on mapped momentum and force"),
                ("p2g_force", COMPLETE),
                ("gravity", COMPLETE),
                ("point_loads", COMPLETE),
            ],
            "soil–body contact: no entry, friction; the bodies' forces",
            |_, _| Box::new(RigidContact::<D, S>::default()),
        ),
        e(
            "boundary",
            St::Constrain,
            Always,
            &[
                ("p2g", "boundary conditions act on mapped momentum and force"),
                ("p2g_force", COMPLETE),
                ("gravity", COMPLETE),
                ("point_loads", COMPLETE),
                (
                    "rigid_contact",
                    "friction faces and motions feel the contact's force",
                ),
            ],
            "held components: fixed at zero, or at a motion's velocity",
            |_, _| Box::new(Boundary::default()),
        ),
        e(
            "integrate",
            St::Integrate,
            Always,
            &[("boundary", "integration needs constrained momentum and force")],
            "nodal acceleration and velocity (+ viscous or local damping)",
            |_, _| Box::new(Integrate),
        ),
        e(
            "mass_scaling",
            St::Scale,
            Needed(|_, m, _| m.mass_scaling(), "solver.mass_scaling is true"),
            &[("integrate", "mass scaling rescales the integrated accelerations")],
            "fictitious inertia",
            |_, _| Box::new(MassScaling::<D, S>::default()),
        ),
        e(
            "g2p",
            St::Interpolate,
            Always,
            &[
                ("integrate", "g2p interpolates the nodal accelerations"),
                ("mass_scaling", "g2p interpolates the rescaled accelerations"),
            ],
            "point velocities, kinetic energy (and what USL's kinematics or USF's move_points moves the points by)",
            |_, _| Box::new(G2p::<D, S>::default()),
        ),
    ]
}

/// Kinetic damping, the MUSL remap, USF's motion, the stopping rule and control.
fn relaxing<D: Dim, S: Shape>() -> Vec<Entry<D>> {
    use Stage as St;
    use When::*;
    vec![
        e(
            "peak_watch",
            St::Damp,
            Needed(
                |n, _, _| n.damping == Damping::Kinetic,
                "solver.damping is Kinetic",
            ),
            &[("g2p", "the peak watch reads the kinetic energy g2p computes")],
            "kinetic damping reset",
            |_, _| Box::new(PeakWatch),
        ),
        e(
            "remap",
            St::Remap,
            Schemes(&[Scheme::Musl]),
            &[
                ("g2p", "the remap maps the updated point velocities"),
                (
                    "peak_watch",
                    "a reset must happen before the velocities are remapped",
                ),
            ],
            "MUSL: point velocities back to the grid",
            |_, _| Box::new(Remap::<D, S>::default()),
        ),
        e(
            "remap_contact",
            St::Remap,
            Needed(
                |n, m, _| n.scheme == Scheme::Musl && !m.bodies.is_empty(),
                "the scheme is Musl and the scene has rigid bodies",
            ),
            &[("remap", "it holds the contacts on the remapped velocities")],
            "MUSL: the rigid bodies' contacts held again on the remapped velocities",
            |_, _| Box::new(RemapContact),
        ),
        e(
            "move_points",
            St::Move,
            Schemes(USF),
            &[("integrate", INTEGRATED), ("peak_watch", NOT_IN_RESET)],
            "USF: position update",
            |_, _| Box::new(Kinematics::<D, S>::motion_only()),
        ),
        e(
            "convergence",
            St::Monitor,
            Always,
            &[],
            "K_F, W_ext, K_E, stopping rule",
            |_, _| Box::new(Convergence),
        ),
        e(
            "prescribed_motion",
            St::Control,
            Needed(|_, m, _| !m.motions.is_empty(), "the scene has motions"),
            &[("convergence", "it acts on the step's static state")],
            "displacement control: travel, hold, curve of static states",
            |_, m| Box::new(PrescribedMotion::new(m.motions.clone())),
        ),
        e(
            "rigid_control",
            St::Control,
            Needed(|_, m, _| !m.bodies.is_empty(), "the scene has rigid bodies"),
            &[
                ("convergence", "it acts on the step's static state"),
                ("prescribed_motion", "the bodies' rows follow the motions'"),
            ],
            "rigid bodies: travel or carry a load, hold, curve of static states",
            |_, m| {
                Box::new(RigidControl::new(
                    m.bodies.iter().map(|b| b.spec.clone()).collect(),
                    &m.stages,
                ))
            },
        ),
        e(
            "load_steps",
            St::Control,
            Needed(
                |_, m, _| !m.load_steps.is_empty(),
                "the scene has loads in increments",
            ),
            &[
                ("convergence", "it acts on the step's static state"),
                ("prescribed_motion", "a load increment follows the motions' last"),
                ("rigid_control", "a load increment follows the bodies' last"),
            ],
            "load control: the next load increment at each static state",
            |_, _| Box::new(LoadControl),
        ),
        e(
            "stages",
            St::Control,
            Needed(|_, m, _| !m.stages.is_empty(), "the scene has stages"),
            &[
                ("convergence", "it acts on the step's static state"),
                ("prescribed_motion", "a stage ends once the motions are done"),
                ("rigid_control", "a stage ends once the bodies are done"),
                ("load_steps", "a stage ends once its load increments are done"),
            ],
            "loading stages: the next stage at each static state",
            |_, _| Box::new(Stages),
        ),
    ]
}

/// True when a system between `stress_update` and `volume_update` reads the volumes at the
/// step's start: the cell mean of stress (`anti_locking: CellMean`) and the undrained
/// water's cell pressure weigh by them. `volume_update` then runs on its own, after them;
/// otherwise the default schedule leaves it out and `stress_update` updates the volumes in
/// its own pass over the velocity gradient (one read of L instead of two, the same bits).
pub fn volume_read_after_stress(numerics: &Numerics, _: &Model, needs: Needs) -> bool {
    numerics.anti_locking == AntiLocking::CellMean || needs.undrained
}

/// What g2p gathers, in its own visit of each point's nodes, for the system after it that
/// moves the points ([`g2p_gathers`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gathered {
    /// Nothing: the points move with another nodal velocity (MUSL's remap maps a new one),
    /// or a system between them might change it.
    Nothing,
    /// The nodal velocity at each point, Σ_i w_ip v_i, which USF's `move_points` moves the
    /// points by.
    Velocity,
    /// The velocity gradient and the nodal velocity at each point, which USL's `kinematics`
    /// strains and moves the points with.
    Strain,
}

/// What g2p gathers for the system that moves the points: where the first system after
/// g2p but the peak watch is `kinematics` (USL) or `move_points` (USF), they read the very
/// nodal velocity g2p reads, so g2p gathers what they need in its own visit of the nodes,
/// and they only move the points by it unless the step is a reset (the same bits as two
/// passes).
pub fn g2p_gathers(names: &[String]) -> Gathered {
    let Some(g) = names.iter().position(|n| n == "g2p") else {
        return Gathered::Nothing;
    };
    match names[g + 1..]
        .iter()
        .find(|n| *n != "peak_watch")
        .map(String::as_str)
    {
        Some("kinematics") => Gathered::Strain,
        Some("move_points") => Gathered::Velocity,
        _ => Gathered::Nothing,
    }
}

/// The registry's names, kinds and rules; they do not depend on the dimension or shape.
fn entries() -> Vec<Entry<Dim2>> {
    registry::<Dim2, Linear>()
}

/// Every system a scene may name in `solver.schedule`, in registry order.
pub fn system_names() -> Vec<&'static str> {
    entries().iter().map(|e| e.name).collect()
}

/// The default list of system names for a scene's numerics and model: each scheme's stages in
/// order, and in each the systems its scheme or the scene needs.
pub fn default_names(numerics: &Numerics, model: &Model, needs: Needs) -> Vec<&'static str> {
    let entries = entries();
    let mut names = Vec::new();
    for &stage in scheme_stages(numerics.scheme) {
        for e in entries.iter().filter(|e| e.stage == stage) {
            let wanted = match e.when {
                When::Always => true,
                When::Schemes(s) => s.contains(&numerics.scheme),
                When::Needed(needed, _) | When::RequiredWhen(needed, _) => needed(numerics, model, needs),
            };
            if wanted {
                names.push(e.name);
            }
        }
    }
    names
}

/// Checks a list of system names: all known, none twice, every required stage present,
/// the optional ones present exactly when the scene needs them, and every order rule kept.
/// The error says what is wrong and why.
pub fn check_names(names: &[String], numerics: &Numerics, model: &Model, needs: Needs) -> Result<(), String> {
    let entries = entries();
    for n in names {
        if !entries.iter().any(|e| e.name == n) {
            return Err(format!(
                "unknown system `{n}`; valid names: {}",
                system_names().join(", ")
            ));
        }
        if names.iter().filter(|m| *m == n).count() > 1 {
            return Err(format!("`{n}` is listed twice"));
        }
    }
    let has = |n: &str| names.iter().any(|m| m == n);
    let pos = |n: &str| names.iter().position(|m| m == n);
    if names.first().map(String::as_str) != Some("grid_reset") {
        return Err("`grid_reset` must come first: every step starts from an empty grid".into());
    }
    // Only control systems, which act on the judged step, may follow the convergence
    // monitor.
    let control = |n: &String| entries.iter().any(|e| e.name == n && e.stage == Stage::Control);
    let before_control = names.iter().rev().find(|n| !control(n));
    if before_control.map(String::as_str) != Some("convergence") {
        return Err(
            "`convergence` must come last (but for control systems): it judges the completed step".into(),
        );
    }
    // The scheme-dependent stages: each job done by exactly one of the systems that can.
    let one_of = |a: &str, b: &str, why: &str| -> Result<(), String> {
        match (has(a), has(b)) {
            (true, true) => Err(format!("`{a}` and `{b}` both {why}: keep one")),
            (false, false) => Err(format!("the schedule lacks `{a}` (or `{b}`), which {why}")),
            _ => Ok(()),
        }
    };
    one_of("p2g", "p2g_momentum", "map mass and momentum")?;
    if !has("p2g") && !has("p2g_force") {
        return Err("the schedule lacks `p2g_force` (or `p2g`), which maps the internal force".into());
    }
    if has("p2g") && has("p2g_force") {
        return Err("`p2g` already maps the internal force: drop `p2g_force`".into());
    }
    // Without the remap a MUSL step is a USL step, which is unstable at the Courant
    // numbers MUSL is allowed (the USL limit is checked against the scheme's name).
    if numerics.scheme == Scheme::Musl && !has("remap") {
        return Err(
            "scheme Musl needs `remap` (without it the step is USL, which is unstable above \
             Courant 0.7): add `remap`, or set solver.scheme: Usl and keep its Courant limit"
                .into(),
        );
    }
    if has("p2g_momentum") && !has("nodal_velocity") {
        return Err("`p2g_momentum` needs `nodal_velocity` to turn momentum into velocity".into());
    }
    if !has("kinematics") && !has("velocity_gradient") {
        return Err(
            "the schedule lacks `kinematics` (or `velocity_gradient`): nothing strains the points".into(),
        );
    }
    if !has("kinematics") && !has("move_points") {
        return Err("the schedule lacks `kinematics` (or `move_points`): nothing moves the points".into());
    }
    for e in &entries {
        match e.when {
            When::Always if !has(e.name) => {
                return Err(format!(
                    "the schedule lacks `{}`, a stage of every explicit step",
                    e.name
                ))
            }
            When::Needed(needed, why) | When::RequiredWhen(needed, why) => {
                let needed = needed(numerics, model, needs);
                if needed && !has(e.name) {
                    return Err(format!("`{}` is required because {why}", e.name));
                }
                // A system the scene does not need may be listed only when it is optional.
                if !needed && has(e.name) && matches!(e.when, When::Needed(..)) {
                    return Err(format!("`{}` is scheduled but only belongs when {why}", e.name));
                }
            }
            _ => {}
        }
    }
    for e in &entries {
        for (before, why) in e.after {
            if let (Some(i), Some(j)) = (pos(before), pos(e.name)) {
                if i > j {
                    return Err(format!("`{before}` must run before `{}`: {why}", e.name));
                }
            }
        }
    }
    Ok(())
}

/// The registry as a Markdown table (name, stage, when, what it does), as
/// docs/writing-a-system.md lists it.
pub fn systems_table() -> String {
    let mut t = String::from("| system | stage | in the schedule | what it does |\n|---|---|---|---|\n");
    for e in entries() {
        let when = match e.when {
            When::Always => "always".to_string(),
            When::Schemes(s) => s
                .iter()
                .map(|s| format!("`{s:?}`"))
                .collect::<Vec<_>>()
                .join(", "),
            When::Needed(_, why) => format!("when {why}"),
            When::RequiredWhen(_, why) => format!("when {why} (or listed)"),
        };
        t += &format!("| `{}` | {:?} | {when} | {} |\n", e.name, e.stage, e.does);
    }
    t
}

/// The default schedule for a scene: its scheme, its shape functions, and only the optional
/// systems (gravity, point loads, peak watch) it uses.
pub fn default_schedule<D: Dim>(
    numerics: &Numerics,
    model: &Model,
    shape: ShapeKind,
    needs: Needs,
) -> Schedule<D> {
    let names: Vec<String> = default_names(numerics, model, needs)
        .into_iter()
        .map(String::from)
        .collect();
    schedule_from_names(&names, numerics, model, shape)
}

/// Builds the systems named in `names` (checked by [`check_names`]) in that order.
pub fn schedule_from_names<D: Dim>(
    names: &[String],
    numerics: &Numerics,
    model: &Model,
    shape: ShapeKind,
) -> Schedule<D> {
    let entries = match shape {
        ShapeKind::Linear => registry::<D, Linear>(),
        ShapeKind::QuadraticBSpline => registry::<D, QuadraticBSpline>(),
        ShapeKind::UniformGimp => registry::<D, UniformGimp>(),
    };
    let mut s = Schedule::new();
    for n in names {
        let e = entries
            .iter()
            .find(|e| e.name == n)
            .unwrap_or_else(|| unreachable!("checked by check_names: {n}"));
        s.push_boxed((e.build)(numerics, model));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Gravity as G;
    use crate::state::ForceNorm;

    fn settings(scheme: Scheme, damping: Damping, gravity: bool) -> (Numerics, Model) {
        let numerics = Numerics {
            dt: 1e-3,
            scheme,
            damping,
            tolerance: 0.01,
            force_norm: ForceNorm::Max,
            max_steps: Some(1),
            max_time: None,
            static_check: None,
            anti_locking: AntiLocking::Off,
            sort_every: 100,
            peak_interpolation: false,
            contact_tolerance: crate::rigid::contact::TOLERANCE,
            flip: 1.0,
            min_node_mass: 0.0,
            initial_energy: 0.0,
            virtual_mass_floor: 0.0,
        };
        let model = Model {
            gravity: gravity.then_some(G {
                acceleration: [0.0, -9.81, 0.0],
                ramp_time: 0.0,
                start: 0.0,
            }),
            ..Model::default()
        };
        (numerics, model)
    }

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn g2p_gathers_for_the_motion_only_with_the_peak_watch_between() {
        let gathers = |scheme, damping| {
            let st = settings(scheme, damping, true);
            g2p_gathers(&names(&default_names(&st.0, &st.1, Needs::default())))
        };
        assert_eq!(gathers(Scheme::Usl, Damping::Kinetic), Gathered::Strain);
        assert_eq!(gathers(Scheme::Usl, Damping::None), Gathered::Strain);
        assert_eq!(gathers(Scheme::Usf, Damping::Kinetic), Gathered::Velocity);
        // MUSL's remap maps a new nodal velocity between them.
        assert_eq!(gathers(Scheme::Musl, Damping::Kinetic), Gathered::Nothing);
        let between = names(&["g2p", "peak_watch", "probe", "kinematics"]);
        assert_eq!(g2p_gathers(&between), Gathered::Nothing);
    }

    #[test]
    fn default_schedules_pass_their_own_checks() {
        for scheme in [Scheme::Musl, Scheme::Usl, Scheme::Usf] {
            for damping in [Damping::Kinetic, Damping::None, Damping::Viscous { beta: 0.1 }] {
                for gravity in [false, true] {
                    for loads in [false, true] {
                        let st = settings(scheme, damping, gravity);
                        let needs = Needs {
                            point_loads: loads,
                            undrained: false,
                        };
                        let n = names(&default_names(&st.0, &st.1, needs));
                        assert_eq!(check_names(&n, &st.0, &st.1, needs), Ok(()), "{n:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn default_schedules_run_the_stages_of_each_scheme_in_order() {
        let mut st = settings(Scheme::Musl, Damping::Kinetic, true);
        st.0.anti_locking = AntiLocking::StrainSmoothing;
        let needs = Needs {
            point_loads: true,
            undrained: false,
        };
        assert_eq!(
            default_names(&st.0, &st.1, needs),
            [
                "grid_reset",
                "spatial_sort",
                "p2g",
                "gravity",
                "point_loads",
                "boundary",
                "integrate",
                "g2p",
                "peak_watch",
                "remap",
                "kinematics",
                "volumetric_smoothing",
                "stress_update",
                "convergence"
            ]
        );
        st.0.scheme = Scheme::Usf;
        assert_eq!(
            default_names(&st.0, &st.1, needs),
            [
                "grid_reset",
                "spatial_sort",
                "p2g_momentum",
                "nodal_velocity",
                "velocity_gradient",
                "volumetric_smoothing",
                "stress_update",
                "p2g_force",
                "gravity",
                "point_loads",
                "boundary",
                "integrate",
                "g2p",
                "peak_watch",
                "move_points",
                "convergence"
            ]
        );
        let plain = settings(Scheme::Usl, Damping::None, false);
        assert_eq!(
            default_names(&plain.0, &plain.1, Needs::default()),
            [
                "grid_reset",
                "spatial_sort",
                "p2g",
                "boundary",
                "integrate",
                "g2p",
                "kinematics",
                "stress_update",
                "convergence"
            ]
        );
        // The cell mean of stress reads the volumes after the stress update: the volume
        // update runs on its own, after it.
        st.0.scheme = Scheme::Musl;
        st.0.anti_locking = AntiLocking::CellMean;
        let names = default_names(&st.0, &st.1, needs);
        let at = |n: &str| names.iter().position(|&m| m == n).expect(n);
        assert!(at("stress_update") < at("cell_mean_stress") && at("cell_mean_stress") < at("volume_update"));
        let undrained = Needs {
            undrained: true,
            ..needs
        };
        assert!(default_names(&plain.0, &plain.1, undrained).contains(&"volume_update"));
    }

    #[test]
    fn the_docs_list_every_system_of_the_registry() {
        let docs = include_str!("../../docs/writing-a-system.md");
        assert!(
            docs.contains(&systems_table()),
            "docs/writing-a-system.md's table is not the registry's; paste this:\n{}",
            systems_table()
        );
    }

    #[test]
    fn unknown_system_names_are_rejected_with_the_valid_names() {
        let st = settings(Scheme::Musl, Damping::Kinetic, false);
        let mut n = names(&default_names(&st.0, &st.1, Needs::default()));
        n[1] = "p2g_fast".into();
        let e = check_names(&n, &st.0, &st.1, Needs::default()).unwrap_err();
        assert!(
            e.contains("unknown system `p2g_fast`") && e.contains("grid_reset, spatial_sort, p2g,"),
            "{e}"
        );
    }

    #[test]
    fn a_schedule_that_breaks_the_order_or_lacks_a_stage_is_rejected() {
        let st = settings(Scheme::Musl, Damping::Kinetic, true);
        let base = names(&default_names(&st.0, &st.1, Needs::default()));
        // Stress update before the velocity gradient exists.
        let mut n = base.clone();
        let k = n.iter().position(|s| s == "kinematics").unwrap();
        let su = n.remove(n.iter().position(|s| s == "stress_update").unwrap());
        n.insert(k, su);
        let e = check_names(&n, &st.0, &st.1, Needs::default()).unwrap_err();
        assert!(e.contains("`kinematics` must run before `stress_update`"), "{e}");
        // No boundary conditions.
        let n: Vec<String> = base.iter().filter(|s| *s != "boundary").cloned().collect();
        assert!(check_names(&n, &st.0, &st.1, Needs::default())
            .unwrap_err()
            .contains("lacks `boundary`"));
        // Gravity in the scene but not in the schedule.
        let n: Vec<String> = base.iter().filter(|s| *s != "gravity").cloned().collect();
        assert!(check_names(&n, &st.0, &st.1, Needs::default())
            .unwrap_err()
            .contains("`gravity` is required"));
        // A peak watch without kinetic damping.
        let viscous = settings(Scheme::Musl, Damping::Viscous { beta: 0.1 }, true);
        assert!(check_names(&base, &viscous.0, &viscous.1, Needs::default())
            .unwrap_err()
            .contains("`peak_watch` is scheduled"));
    }
}
