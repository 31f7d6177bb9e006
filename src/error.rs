//! Typed errors of the library. The binary reports them once, readably.

use std::path::PathBuf;
use thiserror::Error;

/// How a command ended, as a process reports it in its exit status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// It did what was asked (0).
    Done,
    /// A run or an analysis went wrong while stepping or writing (1).
    Failed,
    /// The input cannot be used: a scene, a study, a checkpoint, an output directory (2).
    BadInput,
    /// Stopped by a signal, with everything written so far whole (130, as a shell reports
    /// SIGINT).
    Interrupted,
}

impl Ending {
    /// The exit status: 0, 1, 2 or 130.
    pub fn code(self) -> u8 {
        match self {
            Ending::Done => 0,
            Ending::Failed => 1,
            Ending::BadInput => 2,
            Ending::Interrupted => crate::interrupt::INTERRUPTED_EXIT,
        }
    }
}

/// Why one part of a scene is refused, before the scene is there to place it: the field
/// (its path inside the part, or in the scene: `parts[1].geometry`,
/// `rigid_bodies[0].parts[1].geometry`) and the rule it breaks. The scene's check turns
/// it into a [`SceneError`] at the field's place in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Refusal {
    /// The field's path.
    pub field: String,
    /// The rule, in words.
    pub rule: String,
}

impl Refusal {
    /// The refusal of `field` for breaking `rule`.
    pub fn new(field: impl Into<String>, rule: String) -> Self {
        Refusal {
            field: field.into(),
            rule,
        }
    }

    /// The same refusal with its field under `prefix` (`rigid_bodies[0]` + `parts[1]`:
    /// `rigid_bodies[0].parts[1]`).
    pub fn under(self, prefix: &str) -> Self {
        Refusal {
            field: if self.field.is_empty() {
                prefix.to_string()
            } else {
                format!("{prefix}.{}", self.field)
            },
            rule: self.rule,
        }
    }
}

/// A scene that cannot be read, parsed or accepted.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read scene file {path}: {source}")]
    Read {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The text is not valid RON or does not match the scene schema.
    #[error("{path}:{line}:{column}: {field}{message}")]
    Syntax {
        /// The scene file.
        path: PathBuf,
        /// Line of the fault (1-based).
        line: usize,
        /// Column of the fault (1-based).
        column: usize,
        /// "field `name`: " for the field whose value holds the fault, when there is one.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A value breaks a rule (non-physical, inconsistent, unknown reference, ...).
    #[error("{path}:{line}:{column}: field `{field}`{note}: {rule}")]
    Invalid {
        /// The scene file.
        path: PathBuf,
        /// Line of the field (1-based; 0 when the field is absent from the text).
        line: usize,
        /// Column of the field (1-based).
        column: usize,
        /// Dotted path of the field, e.g. `materials.soil.youngs_modulus`.
        field: String,
        /// " (set by --set `path=value`)" when an override wrote the value, else empty.
        note: String,
        /// The rule it breaks and the value found.
        rule: String,
    },
    /// A `--set` override that cannot be applied.
    #[error("override `{0}`: {1}")]
    Override(String, String),
}

/// A failure while stepping: the run stops, and what was written so far stays valid.
#[derive(Debug, Error)]
pub enum StepError {
    /// A point left the background grid.
    #[error("step {step}, system `{system}`: point {point} left the grid at {position:?}")]
    PointLeftGrid {
        /// Step number (1-based) in which it happened.
        step: u64,
        /// System that detected it.
        system: &'static str,
        /// The point's [`PointId`](crate::components::PointId).
        point: u32,
        /// Where it went (m).
        position: [f64; 3],
    },
    /// A NaN or infinite value appeared.
    #[error(
        "step {step}, system `{system}`: non-finite {what} at {location}; the state of the step before is kept. \
         A smaller time step (solver.time_step: Courant(α) with a smaller α) or a larger \
         solver.virtual_mass_floor usually cures it"
    )]
    NonFinite {
        /// Step number.
        step: u64,
        /// System that detected it.
        system: &'static str,
        /// The quantity.
        what: &'static str,
        /// The point or node involved.
        location: String,
    },
    /// A static state holds a point whose material state has no physical meaning.
    #[error(
        "step {step}, system `convergence`: at this static state point {point} at {position:?} \
         has {why}: the material has no state there, and the answer would not be one"
    )]
    StateFault {
        /// Step number.
        step: u64,
        /// The point's [`PointId`](crate::components::PointId) (the smallest over ranks).
        point: u32,
        /// Where it is (m).
        position: [f64; 3],
        /// Why ([`crate::materials::MaterialState::fault`]).
        why: String,
    },
    /// The kinetic energy exceeds the work done on the body: the scheme is creating energy.
    #[error(
        "step {step}, system `convergence`: kinetic energy {kinetic_energy:.4e} J exceeds {ratio:.1}× the external \
         work {external_work:.4e} J: the run is unstable (time step too large for the stiffness or mass?)"
    )]
    Unstable {
        /// Step number.
        step: u64,
        /// E_k (J).
        kinetic_energy: f64,
        /// W_ext (J).
        external_work: f64,
        /// E_k / W_ext.
        ratio: f64,
    },
    /// A point load found no node with mass to act on.
    #[error("step {step}: point load {point} at {position:?} has no node with mass to act on")]
    LoadLost {
        /// Step number.
        step: u64,
        /// The load carrier's [`PointId`](crate::components::PointId).
        point: u32,
        /// Its position (m).
        position: [f64; 3],
    },
    /// The spatial sort met a point component it does not know (added by user code), which
    /// it could not move along with the point's other data.
    #[error(
        "step {step}, system `spatial_sort`: a point carries a component added outside kdmpm, \
         which the sort cannot move with the point: set solver.sort_every: 0 or drop `spatial_sort`"
    )]
    Unsortable {
        /// Step number.
        step: u64,
    },
    /// A rigid body's increment found no static state before the run's `max_time`.
    #[error(
        "step {step}, t = {time:.4} s: rigid body \"{body}\" found no static state in increment {increment} \
         before solver.max_time (K_F {force_ratio:.3e}{}): the soil did not come to rest \
         (a load it cannot carry, or a run that needs more time); the curve so far is kept",
        unbalanced.map_or(String::new(), |u| format!(", its load out of balance by {u:.3e} of it"))
    )]
    NoStaticState {
        /// Step number.
        step: u64,
        /// Time (s).
        time: f64,
        /// The body's name.
        body: String,
        /// The increment (1-based).
        increment: u32,
        /// K_F at the stop.
        force_ratio: f64,
        /// Under load control, the body's out-of-balance force over its load.
        unbalanced: Option<f64>,
    },
    /// A rigid body under load control moved out of the grid.
    #[error(
        "step {step}: rigid body \"{body}\" under load control left the grid in increment {increment} \
         (it spans {lo:?}..{hi:?} m): the soil does not carry its load; the curve so far is kept"
    )]
    BodyLeftGrid {
        /// Step number.
        step: u64,
        /// The body's name.
        body: String,
        /// The increment (1-based).
        increment: u32,
        /// Its bounds now (m).
        lo: [f64; 3],
        /// Its bounds now (m).
        hi: [f64; 3],
    },
    /// Writing output failed.
    #[error("writing output: {0}")]
    Io(#[from] std::io::Error),
    /// Over MPI ranks, a system failed on another rank (a point left the grid in its
    /// layers): every rank stops at the same system with the lowest failing rank's message.
    #[error("rank {rank}: {message}")]
    OnRank {
        /// The lowest rank whose system failed.
        rank: usize,
        /// Its error.
        message: String,
    },
    /// A user system failed.
    #[error("step {step}, system `{system}`: {message}")]
    User {
        /// Step number.
        step: u64,
        /// System name.
        system: String,
        /// Its message.
        message: String,
    },
}
