//! The stages of one explicit MPM step, one file each, and the default schedule.
//!
//! MUSL with kinetic damping (the default) runs, in order:
//!
//! | system          | file                 | what it does                                   |
//! |-----------------|----------------------|------------------------------------------------|
//! | `grid_reset`    | `grid_reset.rs`      | empty, undeformed grid                          |
//! | `p2g`           | `p2g.rs`             | mass, momentum, internal force to the nodes     |
//! | `gravity`       | `gravity.rs`         | body force m_i g (only with gravity)            |
//! | `point_loads`   | `point_loads.rs`     | concentrated loads (only with loads)            |
//! | `boundary`      | `boundary.rs`        | fixed components of momentum and force to zero  |
//! | `integrate`     | `integrate.rs`       | nodal acceleration and velocity (+ viscous)     |
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
pub mod nodal_velocity;
pub mod p2g;
pub mod peak_watch;
pub mod point_loads;
pub mod remap;
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
pub use nodal_velocity::NodalVelocity;
pub use p2g::{P2g, P2gPart};
pub use peak_watch::PeakWatch;
pub use point_loads::PointLoads;
pub use remap::Remap;
pub use stress_update::StressUpdate;
pub use volume_update::VolumeUpdate;
pub use volumetric_smoothing::VolumetricSmoothing;

use crate::dim::Dim;
use crate::schedule::Schedule;
use crate::shape::{Linear, QuadraticBSpline, Shape, ShapeKind};
use crate::state::{Damping, Scheme, Settings};

/// What a scene contains that decides which optional systems it needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Needs {
    /// The scene has point loads.
    pub point_loads: bool,
}

/// The schedule a scene needs: its scheme, its shape functions, and only the optional
/// systems (gravity, point loads, peak watch) it uses.
pub fn default_schedule<D: Dim>(settings: &Settings, shape: ShapeKind, needs: Needs) -> Schedule<D> {
    match shape {
        ShapeKind::Linear => build::<D, Linear>(settings, needs),
        ShapeKind::QuadraticBSpline => build::<D, QuadraticBSpline>(settings, needs),
    }
}

fn build<D: Dim, S: Shape>(settings: &Settings, needs: Needs) -> Schedule<D> {
    let mut s = Schedule::new();
    s.push(GridReset);
    let forces = |s: &mut Schedule<D>| {
        if let Some(g) = settings.gravity {
            s.push(Gravity::new(g));
        }
        if needs.point_loads {
            s.push(PointLoads::<D, S>::default());
        }
        s.push(Boundary);
        s.push(Integrate);
        s.push(G2p::<D, S>::default());
        if settings.damping == Damping::Kinetic {
            s.push(PeakWatch);
        }
    };
    match settings.scheme {
        Scheme::Musl | Scheme::Usl => {
            s.push(P2g::<D, S>::new(P2gPart::All));
            forces(&mut s);
            if settings.scheme == Scheme::Musl {
                s.push(Remap::<D, S>::default());
            }
            s.push(Kinematics::<D, S>::both());
            if settings.volumetric_smoothing {
                s.push(VolumetricSmoothing::<D, S>::default());
            }
            s.push(StressUpdate);
            s.push(VolumeUpdate);
        }
        Scheme::Usf => {
            s.push(P2g::<D, S>::new(P2gPart::MassMomentum));
            s.push(NodalVelocity);
            s.push(Kinematics::<D, S>::gradient_only());
            if settings.volumetric_smoothing {
                s.push(VolumetricSmoothing::<D, S>::default());
            }
            s.push(StressUpdate);
            s.push(VolumeUpdate);
            s.push(P2g::<D, S>::new(P2gPart::InternalForce));
            forces(&mut s);
            s.push(Kinematics::<D, S>::motion_only());
        }
    }
    s.push(Convergence);
    s
}
