//! The stages of one explicit MPM step, one file each, and the default schedule.
//!
//! MUSL with kinetic damping (the default) runs, in order:
//!
//! | system          | file                 | what it does                                   |
//! |-----------------|----------------------|------------------------------------------------|
//! | `grid_reset`    | `grid_reset.rs`      | empty, undeformed grid                          |
//! | `spatial_sort`  | `spatial_sort.rs`    | points back in cell order (every N steps)       |
//! | `p2g`           | `p2g.rs`             | mass, momentum, internal force to the nodes     |
//! | `gravity`       | `gravity.rs`         | body force m_i g (only with gravity)            |
//! | `point_loads`   | `point_loads.rs`     | concentrated loads (only with loads)            |
//! | `boundary`      | `boundary.rs`        | fixed components of momentum and force to zero  |
//! | `integrate`     | `integrate.rs`       | nodal acceleration and velocity (+ viscous)     |
//! | `mass_scaling`  | `mass_scaling.rs`    | fictitious inertia (only with mass scaling)     |
//! | `g2p`           | `g2p.rs`             | point velocities, kinetic energy                |
//! | `peak_watch`    | `peak_watch.rs`      | kinetic damping reset (only kinetic damping)    |
//! | `remap`         | `remap.rs`           | MUSL: point velocities back to the grid         |
//! | `kinematics`    | `kinematics.rs`      | velocity gradient, position update              |
//! | `stress_update` | `stress_update.rs`   | Jaumann rotation + material law                 |
//! | `volume_update` | `volume_update.rs`   | V ← V det(I + LΔt)                              |
//! | `convergence`   | `convergence.rs`     | K_F, W_ext, K_E, stopping rule                  |
//!
//! USL drops `remap` (points move with the updated grid velocity); USF maps momentum first
//! (`p2g_momentum`, `nodal_velocity`), updates stress (`velocity_gradient`,
//! `stress_update`, `volume_update`), then maps forces (`p2g_force`) and moves the points
//! at the end (`move_points`).

pub mod boundary;
pub mod convergence;
pub mod g2p;
pub mod gravity;
pub mod grid_reset;
pub mod integrate;
pub mod kinematics;
pub mod mass_scaling;
pub mod nodal_velocity;
pub mod p2g;
pub mod peak_watch;
pub mod point_loads;
pub mod remap;
pub mod spatial_sort;
pub mod stress_update;
pub mod volume_update;
pub mod volumetric_smoothing;

pub use boundary::Boundary;
pub use convergence::Convergence;
pub use g2p::G2p;
pub use gravity::Gravity;
pub use grid_reset::GridReset;
pub use integrate::Integrate;
pub use kinematics::Kinematics;
pub use mass_scaling::MassScaling;
pub use nodal_velocity::NodalVelocity;
pub use p2g::{P2g, P2gPart};
pub use peak_watch::PeakWatch;
pub use point_loads::PointLoads;
pub use remap::Remap;
pub use spatial_sort::SpatialSort;
pub use stress_update::StressUpdate;
pub use volume_update::VolumeUpdate;
pub use volumetric_smoothing::VolumetricSmoothing;

use crate::dim::Dim;
use crate::schedule::{Schedule, System};
use crate::shape::{Linear, QuadraticBSpline, Shape, ShapeKind, UniformGimp};
use crate::state::{Damping, Scheme, Settings};

/// What a scene contains that decides which optional systems it needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// The scene has point loads.
    pub point_loads: bool,
}

/// Every system a scene may name in `solver.schedule`.
pub const SYSTEM_NAMES: &[&str] = &[
    "grid_reset",
    "spatial_sort",
    "p2g",
    "p2g_momentum",
    "nodal_velocity",
    "velocity_gradient",
    "p2g_force",
    "gravity",
    "point_loads",
    "boundary",
    "integrate",
    "mass_scaling",
    "g2p",
    "peak_watch",
    "remap",
    "kinematics",
    "move_points",
    "volumetric_smoothing",
    "stress_update",
    "volume_update",
    "convergence",
];

/// Pairs (a, b): when both are scheduled, a must run before b.
const ORDER: &[(&str, &str, &str)] = &[
    (
        "spatial_sort",
        "p2g",
        "the points are put in cell order before the step maps them",
    ),
    (
        "spatial_sort",
        "p2g_momentum",
        "the points are put in cell order before the step maps them",
    ),
    ("p2g", "gravity", "gravity acts on the nodal mass that p2g maps"),
    (
        "p2g_momentum",
        "gravity",
        "gravity acts on the nodal mass that p2g_momentum maps",
    ),
    (
        "p2g",
        "point_loads",
        "point loads go to nodes that carry mapped mass",
    ),
    (
        "p2g_momentum",
        "point_loads",
        "point loads go to nodes that carry mapped mass",
    ),
    (
        "p2g_momentum",
        "nodal_velocity",
        "the nodal velocity needs the mapped momentum",
    ),
    (
        "nodal_velocity",
        "velocity_gradient",
        "the velocity gradient needs the nodal velocity",
    ),
    (
        "velocity_gradient",
        "stress_update",
        "the stress update needs the velocity gradient",
    ),
    (
        "kinematics",
        "stress_update",
        "the stress update needs the velocity gradient",
    ),
    (
        "velocity_gradient",
        "volumetric_smoothing",
        "smoothing works on the velocity gradient",
    ),
    (
        "kinematics",
        "volumetric_smoothing",
        "smoothing works on the velocity gradient",
    ),
    (
        "volumetric_smoothing",
        "stress_update",
        "the stress must see the smoothed strain",
    ),
    (
        "stress_update",
        "volume_update",
        "the volume update follows the stress update",
    ),
    ("stress_update", "p2g_force", "p2g_force maps the updated stress"),
    (
        "p2g",
        "boundary",
        "boundary conditions act on mapped momentum and force",
    ),
    (
        "p2g_force",
        "boundary",
        "boundary conditions act on the complete nodal force",
    ),
    (
        "gravity",
        "boundary",
        "boundary conditions act on the complete nodal force",
    ),
    (
        "point_loads",
        "boundary",
        "boundary conditions act on the complete nodal force",
    ),
    (
        "boundary",
        "integrate",
        "integration needs constrained momentum and force",
    ),
    ("integrate", "g2p", "g2p interpolates the nodal accelerations"),
    (
        "integrate",
        "mass_scaling",
        "mass scaling rescales the integrated accelerations",
    ),
    (
        "mass_scaling",
        "g2p",
        "g2p interpolates the rescaled accelerations",
    ),
    (
        "g2p",
        "peak_watch",
        "the peak watch reads the kinetic energy g2p computes",
    ),
    ("g2p", "remap", "the remap maps the updated point velocities"),
    (
        "peak_watch",
        "remap",
        "a reset must happen before the velocities are remapped",
    ),
    (
        "remap",
        "kinematics",
        "MUSL strains and moves the points with the remapped velocity",
    ),
    ("peak_watch", "kinematics", "points must not move in a reset step"),
    (
        "peak_watch",
        "move_points",
        "points must not move in a reset step",
    ),
    (
        "integrate",
        "move_points",
        "points move with the integrated velocity",
    ),
    (
        "integrate",
        "kinematics",
        "points move with the integrated velocity",
    ),
];

/// The default list of system names for a scene's settings.
pub fn default_names(settings: &Settings, needs: Needs) -> Vec<&'static str> {
    let mut n = vec!["grid_reset"];
    if settings.sort_every > 0 {
        n.push("spatial_sort");
    }
    let forces = |n: &mut Vec<&'static str>| {
        if settings.gravity.is_some() {
            n.push("gravity");
        }
        if needs.point_loads {
            n.push("point_loads");
        }
        n.extend(["boundary", "integrate"]);
        if settings.mass_scaling() {
            n.push("mass_scaling");
        }
        n.push("g2p");
        if settings.damping == Damping::Kinetic {
            n.push("peak_watch");
        }
    };
    match settings.scheme {
        Scheme::Musl | Scheme::Usl => {
            n.push("p2g");
            forces(&mut n);
            if settings.scheme == Scheme::Musl {
                n.push("remap");
            }
            n.push("kinematics");
            if settings.volumetric_smoothing {
                n.push("volumetric_smoothing");
            }
            n.extend(["stress_update", "volume_update"]);
        }
        Scheme::Usf => {
            n.extend(["p2g_momentum", "nodal_velocity", "velocity_gradient"]);
            if settings.volumetric_smoothing {
                n.push("volumetric_smoothing");
            }
            n.extend(["stress_update", "volume_update", "p2g_force"]);
            forces(&mut n);
            n.push("move_points");
        }
    }
    n.push("convergence");
    n
}

/// Checks a list of system names: all known, none twice, every required stage present,
/// the optional ones present exactly when the scene needs them, and every order rule kept.
/// The error says what is wrong and why.
pub fn check_names(names: &[String], settings: &Settings, needs: Needs) -> Result<(), String> {
    for n in names {
        if !SYSTEM_NAMES.contains(&n.as_str()) {
            return Err(format!(
                "unknown system `{n}`; valid names: {}",
                SYSTEM_NAMES.join(", ")
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
    if names.last().map(String::as_str) != Some("convergence") {
        return Err("`convergence` must come last: it judges the completed step".into());
    }
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
    for required in ["boundary", "integrate", "g2p", "stress_update", "volume_update"] {
        if !has(required) {
            return Err(format!(
                "the schedule lacks `{required}`, a stage of every explicit step"
            ));
        }
    }
    let optional = [
        (
            "spatial_sort",
            settings.sort_every > 0,
            "solver.sort_every is above 0",
        ),
        ("gravity", settings.gravity.is_some(), "the scene has gravity"),
        ("point_loads", needs.point_loads, "the scene has point loads"),
        (
            "mass_scaling",
            settings.mass_scaling(),
            "solver.mass_scaling is true",
        ),
        (
            "peak_watch",
            settings.damping == Damping::Kinetic,
            "solver.damping is Kinetic",
        ),
        (
            "volumetric_smoothing",
            settings.volumetric_smoothing,
            "solver.volumetric_smoothing is true",
        ),
    ];
    for (name, needed, why) in optional {
        if needed && !has(name) {
            return Err(format!("`{name}` is required because {why}"));
        }
        if !needed && has(name) {
            return Err(format!("`{name}` is scheduled but only belongs when {why}"));
        }
    }
    for (a, b, why) in ORDER {
        if let (Some(i), Some(j)) = (pos(a), pos(b)) {
            if i > j {
                return Err(format!("`{a}` must run before `{b}`: {why}"));
            }
        }
    }
    Ok(())
}

/// The default schedule for a scene: its scheme, its shape functions, and only the optional
/// systems (gravity, point loads, peak watch) it uses.
pub fn default_schedule<D: Dim>(settings: &Settings, shape: ShapeKind, needs: Needs) -> Schedule<D> {
    let names: Vec<String> = default_names(settings, needs)
        .into_iter()
        .map(String::from)
        .collect();
    schedule_from_names(&names, settings, shape)
}

/// Builds the systems named in `names` (checked by [`check_names`]) in that order.
pub fn schedule_from_names<D: Dim>(names: &[String], settings: &Settings, shape: ShapeKind) -> Schedule<D> {
    let mut s = Schedule::new();
    for n in names {
        s.push_boxed(match shape {
            ShapeKind::Linear => make::<D, Linear>(n, settings),
            ShapeKind::QuadraticBSpline => make::<D, QuadraticBSpline>(n, settings),
            ShapeKind::UniformGimp => make::<D, UniformGimp>(n, settings),
        });
    }
    s
}

fn make<D: Dim, S: Shape>(name: &str, settings: &Settings) -> Box<dyn System<D>> {
    match name {
        "grid_reset" => Box::new(GridReset),
        "spatial_sort" => Box::new(SpatialSort::new(settings.sort_every)),
        "p2g" => Box::new(P2g::<D, S>::new(P2gPart::All)),
        "p2g_momentum" => Box::new(P2g::<D, S>::new(P2gPart::MassMomentum)),
        "p2g_force" => Box::new(P2g::<D, S>::new(P2gPart::InternalForce)),
        "nodal_velocity" => Box::new(NodalVelocity),
        "velocity_gradient" => Box::new(Kinematics::<D, S>::gradient_only()),
        "move_points" => Box::new(Kinematics::<D, S>::motion_only()),
        "kinematics" => Box::new(Kinematics::<D, S>::both()),
        "gravity" => Box::new(Gravity::new(
            settings.gravity.expect("checked: the scene has gravity"),
        )),
        "point_loads" => Box::new(PointLoads::<D, S>::default()),
        "boundary" => Box::new(Boundary),
        "integrate" => Box::new(Integrate),
        "mass_scaling" => Box::new(MassScaling::<D, S>::default()),
        "g2p" => Box::new(G2p::<D, S>::default()),
        "peak_watch" => Box::new(PeakWatch),
        "remap" => Box::new(Remap::<D, S>::default()),
        "volumetric_smoothing" => Box::new(VolumetricSmoothing::<D, S>::default()),
        "stress_update" => Box::new(StressUpdate),
        "volume_update" => Box::new(VolumeUpdate),
        "convergence" => Box::new(Convergence),
        other => unreachable!("checked by check_names: {other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::state::{ForceNorm, Gravity as G};

    fn settings(scheme: Scheme, damping: Damping, gravity: bool) -> Settings {
        Settings {
            scheme,
            damping,
            tolerance: 0.01,
            force_norm: ForceNorm::Max,
            max_steps: Some(1),
            max_time: None,
            static_check: None,
            gravity: gravity.then_some(G {
                acceleration: [0.0, -9.81, 0.0],
                ramp_time: 0.0,
            }),
            volumetric_smoothing: false,
            sort_every: 100,
            peak_interpolation: false,
            inertia_factors: Vec::new(),
            flip: 1.0,
            min_node_mass: 0.0,
            virtual_mass_floor: 0.0,
        }
    }

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn default_schedules_pass_their_own_checks() {
        for scheme in [Scheme::Musl, Scheme::Usl, Scheme::Usf] {
            for damping in [Damping::Kinetic, Damping::None, Damping::Viscous { beta: 0.1 }] {
                for gravity in [false, true] {
                    for loads in [false, true] {
                        let st = settings(scheme, damping, gravity);
                        let needs = Needs { point_loads: loads };
                        let n = names(&default_names(&st, needs));
                        assert_eq!(check_names(&n, &st, needs), Ok(()), "{n:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn unknown_system_names_are_rejected_with_the_valid_names() {
        let st = settings(Scheme::Musl, Damping::Kinetic, false);
        let mut n = names(&default_names(&st, Needs::default()));
        n[1] = "p2g_fast".into();
        let e = check_names(&n, &st, Needs::default()).unwrap_err();
        assert!(
            e.contains("unknown system `p2g_fast`") && e.contains("grid_reset, spatial_sort, p2g,"),
            "{e}"
        );
    }

    #[test]
    fn a_schedule_that_breaks_the_order_or_lacks_a_stage_is_rejected() {
        let st = settings(Scheme::Musl, Damping::Kinetic, true);
        let base = names(&default_names(&st, Needs::default()));
        // Stress update before the velocity gradient exists.
        let mut n = base.clone();
        let k = n.iter().position(|s| s == "kinematics").unwrap();
        let su = n.remove(n.iter().position(|s| s == "stress_update").unwrap());
        n.insert(k, su);
        let e = check_names(&n, &st, Needs::default()).unwrap_err();
        assert!(e.contains("`kinematics` must run before `stress_update`"), "{e}");
        // No boundary conditions.
        let n: Vec<String> = base.iter().filter(|s| *s != "boundary").cloned().collect();
        assert!(check_names(&n, &st, Needs::default())
            .unwrap_err()
            .contains("lacks `boundary`"));
        // Gravity in the scene but not in the schedule.
        let n: Vec<String> = base.iter().filter(|s| *s != "gravity").cloned().collect();
        assert!(check_names(&n, &st, Needs::default())
            .unwrap_err()
            .contains("`gravity` is required"));
        // A peak watch without kinetic damping.
        let viscous = settings(Scheme::Musl, Damping::Viscous { beta: 0.1 }, true);
        assert!(check_names(&base, &viscous, Needs::default())
            .unwrap_err()
            .contains("`peak_watch` is scheduled"));
    }
}
