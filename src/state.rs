//! The solver's numerics and its state through a run: plain structs outside the ECS world.

use crate::grid::NodeBox;
use crate::model::Control;
use serde::{Deserialize, Serialize};

/// Where the stress update sits in the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// Update stress first, with the velocities mapped at the start of the step.
    Usf,
    /// Update stress last, with the updated grid velocities.
    Usl,
    /// Modified USL: remap the updated point velocities to the grid and use those
    /// (Sulsky et al. 1995). The default: it is the most robust with small nodal masses.
    #[default]
    Musl,
}

/// Artificial damping that turns the dynamic problem into a static solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Damping {
    /// No damping: the plain dynamic problem.
    None,
    /// Kinetic damping: zero every velocity at each peak of the kinetic energy (paper §2.2).
    #[default]
    Kinetic,
    /// Viscous damping F_damp = 2β M v (β in 1/s).
    Viscous {
        /// Damping factor β (1/s).
        beta: f64,
    },
    /// Local non-viscous damping (Cundall 1987, FLAC's default): each free nodal force
    /// component is opposed by α |F| in the direction of the node's velocity,
    /// F_damp = −α |F| sign(v), so a node speeding up and a node slowing down are both
    /// held back in proportion to their unbalanced force, not their speed.
    Local {
        /// Damping fraction α, 0 ≤ α < 1 (FLAC: 0.8).
        alpha: f64,
    },
}

/// How the points' volume change is discretised, against volumetric locking.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum AntiLocking {
    /// Each point strains and is stressed on its own: the plain method.
    #[default]
    Off,
    /// The volumetric strain rate smoothed through the nodes (`volumetric_smoothing.rs`):
    /// for isochoric plastic flow only (ψ = 0), refused on a dilatant material.
    StrainSmoothing,
    /// Cell means of the volumetric strain rate and of the mean stress (`cell_mean.rs`):
    /// consistent in the nodal forces' power, for any plastic flow.
    CellMean,
}

/// Which norm of the out-of-balance force the stopping rule reads (both are always reported).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum ForceNorm {
    /// The paper's eq. (3): max |F_ext + F_int| / max |F_ext| over free degrees of freedom.
    #[default]
    Max,
    /// Σ |F_ext + F_int| / Σ |F_ext| over the same degrees of freedom (FLAC's ratio-average).
    Mean,
}

/// Why a run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// K_F and K_E both at or below the tolerance.
    Converged,
    /// Stopped from outside (Ctrl-C); a checkpoint holds the state to resume from.
    Interrupted,
    /// The step limit was reached first.
    MaxSteps,
    /// The time limit was reached first.
    MaxTime,
    /// A point moved farther than an analysis allows (a strength-reduction trial that
    /// fails).
    DisplacementLimit,
}

/// A confirmation that a state meeting K_F and K_E is really static: the run goes on for
/// `window` seconds and stops only if no point moved more than `max_displacement` in that
/// time (and both ratios are still met). A creeping slope meets K_F and K_E between
/// kinetic-damping resets; it does not meet this.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StaticCheck {
    /// Confirmation window (s).
    pub window: f64,
    /// Largest point movement allowed over the window (m).
    pub max_displacement: f64,
}

/// The numerics of a run: how the model is solved (time step, scheme, damping, the
/// stopping rule, the treatments of the grid), fixed for the run and `Copy`, as rapier's
/// `IntegrationParameters`. What is solved is the [`Model`](crate::model::Model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Numerics {
    /// Time step Δt (s), from the scene (`solver.time_step`).
    pub dt: f64,
    /// Update scheme.
    pub scheme: Scheme,
    /// Damping.
    pub damping: Damping,
    /// Tolerance for K_F and K_E.
    pub tolerance: f64,
    /// Norm of K_F that the stopping rule reads.
    pub force_norm: ForceNorm,
    /// Step limit.
    pub max_steps: Option<u64>,
    /// Simulated-time limit (s).
    pub max_time: Option<f64>,
    /// Confirmation that a converged state is static, if asked for.
    pub static_check: Option<StaticCheck>,
    /// FLIP fraction α of the point velocity update (1 = FLIP, 0 = PIC).
    pub flip: f64,
    /// The volumetric treatment against locking.
    pub anti_locking: AntiLocking,
    /// Put the points back in cell order every this many steps (0: never).
    pub sort_every: u64,
    /// Kinetic damping places each reset at the peak of a parabola through the last three
    /// kinetic energies instead of at the step where the drop was seen.
    pub peak_interpolation: bool,
    /// Smallest mass that accelerates an interior node (kg): a_i = f_i / max(m_i, floor),
    /// scaled on the grid's faces by the node's share ([`crate::grid::Grid::inertia`]).
    pub virtual_mass_floor: f64,
    /// A rigid-body contact solve stops when no sweep changes a contact's velocity by more
    /// than this fraction of its scale ([`crate::rigid::contact::solve`]).
    pub contact_tolerance: f64,
    /// Interior nodes lighter than this carry no degrees of freedom (kg); scaled on the
    /// grid's faces by the node's share ([`crate::grid::Grid::carries`]).
    ///
    /// Leaving a node out drops its share of Σ_i ∇w_ip = 0, which acts as a spurious force
    /// V_p σ_p ∇w_ip: keep this tiny and tame light nodes with `virtual_mass_floor`.
    pub min_node_mass: f64,
    /// Strain energy the points' initial stress may give up, at most (J; J/m in 2D, J/rad
    /// axisymmetric): the energy guard counts it beside the external work.
    pub initial_energy: f64,
}

/// A kinetic-energy peak at which velocities were reset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    /// Time of the peak (s).
    pub time: f64,
    /// Kinetic energy at the peak (J).
    pub energy: f64,
}

/// Solver-wide quantities updated by the systems every step, in named parts. The parts a
/// checkpoint holds save and load themselves (`checkpoint.rs`), each by an exhaustive
/// destructure, so that a field added to one cannot be left out of the file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SolverState {
    /// Step count and simulated time.
    pub clock: Clock,
    /// The kinetic energy of the last three steps, which the peak watch reads.
    pub energy: EnergyWindow,
    /// The kinetic-damping resets so far and this step's.
    pub resets: Resets,
    /// K_F, K_E and the external work.
    pub convergence: Convergence,
    /// The static check's window.
    pub static_window: StaticWindow,
    /// Set when the run should stop after this step.
    pub stop: Option<StopReason>,
    /// Prescribed motions, their curve, the stages and the loads under control.
    pub control: Control,
    /// Counters of a run over MPI ranks.
    pub ranks: RankCounters,
    /// The nodes the points reached this step. Every node outside holds zeros (mass,
    /// momentum, forces, acceleration, velocity), so grid passes skip it: a scatter adds the
    /// nodes it reaches, the grid reset zeroes the box and empties it. Rebuilt each step.
    pub active_nodes: NodeBox,
    /// True when this step's spatial sort moved point data between rows: holders of row
    /// indices or entities (traced points) must look their points up again by [`PointId`].
    ///
    /// [`PointId`]: crate::components::PointId
    pub points_reordered: bool,
}

/// Step count and simulated time; Δt is a setting ([`Numerics::dt`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clock {
    /// Number of the current step (1-based while the schedule runs; steps done afterwards).
    pub step: u64,
    /// Simulated time at the end of the current step (s).
    pub time: f64,
}

impl Clock {
    /// The limit this step reached, if any: `max_steps`, then `max_time` (to round-off of
    /// n·Δt).
    pub fn limit(&self, numerics: &Numerics) -> Option<StopReason> {
        if numerics.max_steps.is_some_and(|m| self.step >= m) {
            Some(StopReason::MaxSteps)
        } else if numerics.max_time.is_some_and(|t| self.time >= t * (1.0 - 1e-12)) {
            Some(StopReason::MaxTime)
        } else {
            None
        }
    }
}

/// The kinetic energy of the last three steps (J), from which the peak watch finds a peak
/// (paper §2.2): the energy fell, so the step before was its peak.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyWindow {
    current: f64,
    previous: f64,
    earlier: f64,
}

impl EnergyWindow {
    /// Sets this step's kinetic energy, eq. (5) (J).
    pub fn set(&mut self, energy: f64) {
        self.current = energy;
    }

    /// This step's kinetic energy (J); 0 after a reset.
    pub fn current(&self) -> f64 {
        self.current
    }

    /// The energies of the steps n − 2, n − 1 and n (J) when step n − 1 was a peak
    /// (E(n) < E(n − 1)); `None` otherwise.
    pub fn peak(&self) -> Option<[f64; 3]> {
        (self.current < self.previous).then_some([self.earlier, self.previous, self.current])
    }

    /// Moves the window on by a step that was no peak.
    pub fn push(&mut self) {
        self.earlier = self.previous;
        self.previous = self.current;
    }

    /// Empties the window (at a reset, or as a stage begins): the next step cannot count
    /// as a peak.
    pub fn reset(&mut self) {
        *self = EnergyWindow::default();
    }

    /// The three energies, earliest first, for a checkpoint.
    pub fn to_array(&self) -> [f64; 3] {
        [self.earlier, self.previous, self.current]
    }

    /// The window of three energies, earliest first, from a checkpoint.
    pub fn from_array([earlier, previous, current]: [f64; 3]) -> Self {
        EnergyWindow {
            current,
            previous,
            earlier,
        }
    }
}

/// The kinetic-damping resets: how many, at which peaks, and this step's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Resets {
    /// Resets so far.
    pub count: u64,
    /// Every peak at which velocities were reset.
    pub peaks: Vec<Peak>,
    /// True when this step's peak watch zeroed the velocities (points move only by
    /// `fraction`; see [`Resets::motion_dt`]).
    pub this_step: bool,
    /// At a reset step, the fraction of Δt the points still move: 0 (they stay where the
    /// previous step left them) or, with `peak_interpolation`, the fitted peak's offset
    /// from that step in (−½, ½).
    pub fraction: f64,
}

impl Resets {
    /// The time over which this step moves the points and integrates their strain (s): Δt,
    /// or at a kinetic-damping reset the fitted peak's offset `fraction`·Δt; `None` when a
    /// reset leaves the points where they are.
    pub fn motion_dt(&self, dt: f64) -> Option<f64> {
        match (self.this_step, self.fraction) {
            (false, _) => Some(dt),
            (true, f) if f != 0.0 => Some(f * dt),
            _ => None,
        }
    }
}

/// The measures of the stopping rule (paper eqs. 3–6).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Convergence {
    /// Cumulative external work, eq. (6) (J).
    pub external_work: f64,
    /// K_F in the max-norm, eq. (3).
    pub force_ratio_max: f64,
    /// K_F in the mean norm.
    pub force_ratio_mean: f64,
    /// K_E, eq. (4).
    pub energy_ratio: f64,
    /// The external force K_F is measured against while none is applied (N: max and sum of
    /// |F_ext| over free degrees of freedom): the last applied load's. A stage that removes
    /// every load (gravity set to 0) relaxes towards an unloaded state, and its
    /// out-of-balance force is judged against the load it took away; `None` before any
    /// load acted.
    pub force_reference: Option<[f64; 2]>,
}

impl Convergence {
    /// K_F in the norm the stopping rule reads.
    pub fn force_ratio(&self, norm: ForceNorm) -> f64 {
        match norm {
            ForceNorm::Max => self.force_ratio_max,
            ForceNorm::Mean => self.force_ratio_mean,
        }
    }
}

/// The static check's window ([`StaticCheck`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StaticWindow {
    /// Time at which the current window opened (s).
    pub start: Option<f64>,
    /// Largest point movement over the last completed window (m). Where each point was
    /// when the window opened is its [`WindowStart`](crate::components::WindowStart).
    pub movement: Option<f64>,
}

/// Counters of a run over MPI ranks (empty or zero on one rank).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RankCounters {
    /// The traced points' displacements (m) gathered from the ranks that hold them this
    /// step (`output::history::TracedGather`); empty with one rank.
    pub traced_displacements: Vec<[f64; 3]>,
    /// The points this rank sent to another so far.
    pub migrations: u64,
    /// How many times the cell layers were split again.
    pub rebalances: u64,
    /// The step this process started from (a resumed run's checkpoint step; 0 otherwise):
    /// the bytes sent are this process's, over the steps since.
    pub first_step: u64,
}

impl SolverState {
    /// Goes on after a static state that a control system consumed (an increment, a
    /// stage): the stop is lifted unless the step or time limit is reached, which ends the
    /// run even while increments are left (a load in 10⁹ increments that each balance at
    /// once would otherwise never reach `max_steps`).
    pub fn go_on(&mut self, numerics: &Numerics) {
        self.static_window.start = None;
        self.stop = self.clock.limit(numerics);
    }
}
