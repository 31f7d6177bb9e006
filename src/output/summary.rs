//! `summary.json`: the outcome of a run.

use crate::dim::Dim;
use crate::measure::{max_displacements, surface_angle, SurfaceAngle};
use crate::model::{CurvePoint, StageResult};
use crate::schedule::Timing;
use crate::simulation::{Simulation, TracedResult};
use crate::state::{ForceNorm, Peak, StopReason};
use serde::Serialize;

/// The outcome of a run, as written to `summary.json`. Nothing is written as `null`: an
/// absent optional figure is left out, and a ratio whose denominator was zero is the
/// string `"undefined"`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Scene file.
    pub scene: String,
    /// 2 or 3.
    pub dimension: usize,
    /// An axisymmetric run (x the radius): masses, forces and work are per radian.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub axisymmetric: bool,
    /// How the run ended.
    pub outcome: Outcome,
    /// True when K_F and K_E both reached the tolerance.
    pub converged: bool,
    /// Why the run stopped (absent after an error).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop_reason: Option<StopReason>,
    /// The error that stopped the run, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Steps taken.
    pub steps: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Time step (s).
    pub time_step: f64,
    /// K_F in the norm the stopping rule reads.
    #[serde(serialize_with = "ratio")]
    pub force_ratio: f64,
    /// That norm.
    pub force_norm: ForceNorm,
    /// K_F, max-norm (paper eq. 3).
    #[serde(serialize_with = "ratio")]
    pub force_ratio_max: f64,
    /// K_F, mean norm.
    #[serde(serialize_with = "ratio")]
    pub force_ratio_mean: f64,
    /// K_E (eq. 4).
    #[serde(serialize_with = "ratio")]
    pub energy_ratio: f64,
    /// Tolerance for both.
    pub tolerance: f64,
    /// Largest point movement over the last completed static-check window (m).
    #[serde(skip_serializing_if = "none_or_not_finite")]
    pub static_window_movement: Option<f64>,
    /// Kinetic-damping resets.
    pub kinetic_resets: u64,
    /// The first kinetic-energy peak (s, J).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_peak: Option<Peak>,
    /// Kinetic energy (J) at the end.
    #[serde(skip_serializing_if = "not_finite")]
    pub kinetic_energy: f64,
    /// External work (J) at the end.
    #[serde(skip_serializing_if = "not_finite")]
    pub external_work: f64,
    /// Material points (load carriers included).
    pub particles: usize,
    /// Total point mass (kg).
    #[serde(skip_serializing_if = "not_finite")]
    pub total_mass: f64,
    /// Wall time of the stepping loop (s).
    pub wall_seconds: f64,
    /// Points × steps per wall second of the stepping loop.
    pub particle_steps_per_second: f64,
    /// Peak resident memory of the process over the whole run, set-up and the writing of
    /// `points.vtu` included (bytes; Linux only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_bytes: Option<u64>,
    /// Largest displacement magnitude of any point (m), unless the scene keeps none.
    #[serde(skip_serializing_if = "none_or_not_finite")]
    pub max_displacement: Option<f64>,
    /// Largest |horizontal displacement| of any point (m), unless the scene keeps none.
    #[serde(skip_serializing_if = "none_or_not_finite")]
    pub max_horizontal_displacement: Option<f64>,
    /// Free-surface angle, when the scene asks for it (`output.surface_angle`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_angle: Option<SurfaceAngle>,
    /// Traced points.
    pub traced: Vec<TracedResult>,
    /// Per-system cost.
    pub systems: Vec<Timing>,
    /// Snapshots in the series, `points.pvd` (`output.snapshots`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub snapshots: Option<usize>,
    /// Wall-clock seconds stepping waited for the snapshot writer (s).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub output_wait_seconds: Option<f64>,
    /// The largest mean pressure of the static states of the prescribed motions given a
    /// loaded area (Pa): the limit pressure where the curve has levelled off.
    #[serde(skip_serializing_if = "none_or_not_finite")]
    pub limit_pressure: Option<f64>,
    /// How much the pressure rose over the curve's last increment, relative to the limit
    /// pressure: near 0 on a plateau, well above it while the curve still climbs.
    #[serde(skip_serializing_if = "none_or_not_finite")]
    pub last_increment_rise: Option<f64>,
    /// Static states of the load–displacement curve (`curve.csv`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub curve: Vec<CurvePoint>,
    /// The scene's rigid bodies where the run left them, with the points their contact
    /// let in (put back on the surface by `rigid_control`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rigid_bodies: Vec<BodyResult>,
    /// The static state that ended each loading stage (`stages.csv`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stages: Vec<StageResult>,
    /// Over MPI: the ranks, and how many times a point moved to another rank.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranks: Option<Ranks>,
}

/// The ranks of a run over MPI.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Ranks {
    /// Number of ranks.
    pub count: usize,
    /// Points each rank holds at the end.
    pub points: Vec<u64>,
    /// Moves of a point to another rank over the run (a point crossing two ranks counts
    /// twice).
    pub migrations: u64,
    /// Times the cell layers were split again because the ranks' loads drifted apart.
    pub rebalances: u64,
    /// The parts along the slab axis and across it (`[ranks, 1]`: slabs).
    pub split: [usize; 2],
    /// Each slab's first cell layer along the slab axis, and the end of the last (the final
    /// split).
    pub bounds: Vec<usize>,
    /// Each part's first cell layer along the second split axis, and the end of the last
    /// (`[0, cells]` for slabs).
    pub across: Vec<usize>,
    /// Bytes the ranks sent each other, all ranks together, per step (exchanges of shared
    /// nodes and of moving points, and the reductions), over the steps this invocation
    /// made (a resumed run's since its checkpoint).
    pub bytes_per_step: f64,
    /// Each rank's peak resident memory (bytes), set-up included, where the system reports
    /// it (0 where it does not).
    pub peak_memory_bytes: Vec<u64>,
    /// The grid nodes each rank holds at the end (its window: the nodes its points can
    /// reach), of `grid_nodes` in all.
    pub nodes: Vec<u64>,
    /// The grid's nodes.
    pub grid_nodes: u64,
}

/// How a run ended, as `summary.json` writes it (snake case).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// K_F and K_E met the tolerance (and the static check, if any).
    Converged,
    /// The step limit came first.
    MaxSteps,
    /// The simulated-time limit came first.
    MaxTime,
    /// A point moved farther than the analysis allows (`strength_reduction`).
    DisplacementLimit,
    /// Stopped by Ctrl-C; `kdmpm resume` continues it from its checkpoint.
    Interrupted,
    /// Stopped by an error (see `error`).
    Failed,
}

impl Outcome {
    /// The name `summary.json` writes (`fos.csv` too).
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Converged => "converged",
            Outcome::MaxSteps => "max_steps",
            Outcome::MaxTime => "max_time",
            Outcome::DisplacementLimit => "displacement_limit",
            Outcome::Interrupted => "interrupted",
            Outcome::Failed => "failed",
        }
    }
}

/// True for NaN or ±∞: a figure a run that failed on a non-finite state leaves behind. It
/// is left out of summary.json (which JSON would write as null); `error` says why.
fn not_finite(x: &f64) -> bool {
    !x.is_finite()
}

/// True for an absent or non-finite figure (left out, see [`not_finite`]).
fn none_or_not_finite(x: &Option<f64>) -> bool {
    x.is_none_or(|x| !x.is_finite())
}

/// A ratio K_F or K_E: its value, or `"undefined"` where its denominator was zero (or where
/// a failed run left it non-finite).
fn ratio<S: serde::Serializer>(r: &f64, s: S) -> Result<S::Ok, S::Error> {
    if r.is_finite() {
        s.serialize_f64(*r)
    } else {
        s.serialize_str("undefined")
    }
}

impl Summary {
    /// The per-system timing table (`kdmpm run --profile`): calls, total and mean time and
    /// share of each system, in schedule order, and the byte budget where a system counts
    /// its bytes ([`crate::infra::traffic`]): bytes a point a call (over ranks, rank 0's) and the rate
    /// they moved at. A last row sums the systems that count their bytes.
    pub fn profile_table(&self) -> String {
        let total: f64 = self.systems.iter().map(|t| t.seconds).sum();
        // The name column as wide as the longest name (`volumetric_smoothing`: 20).
        let w = self
            .systems
            .iter()
            .map(|t| t.name.chars().count())
            .fold(18, usize::max);
        // Over ranks the timings and bytes are rank 0's: per point of rank 0 (at the end).
        let points = match &self.ranks {
            None => self.particles as u64,
            Some(r) => r.points.first().copied().unwrap_or(0),
        };
        let points = (points > 0).then_some(points as f64);
        let mut text = format!(
            "{:<w$} {:>10} {:>12} {:>12} {:>7} {:>9} {:>7}\n",
            "system", "calls", "total (s)", "mean (µs)", "share", "B/point", "GB/s"
        );
        let mut row = |name: &str, calls: u64, seconds: f64, bytes: Option<u64>| {
            let mean = if calls > 0 {
                1e6 * seconds / calls as f64
            } else {
                0.0
            };
            let share = if total > 0.0 { 100.0 * seconds / total } else { 0.0 };
            let per_point = match (bytes, points) {
                (Some(b), Some(n)) if calls > 0 => format!("{:.0}", b as f64 / calls as f64 / n),
                _ => "-".into(),
            };
            let rate = match bytes {
                Some(b) if seconds > 0.0 => format!("{:.1}", b as f64 / seconds / 1e9),
                _ => "-".into(),
            };
            text += &format!(
                "{name:<w$} {calls:>10} {seconds:>12.4} {mean:>12.2} {share:>6.1}% {per_point:>9} {rate:>7}\n"
            );
        };
        for t in &self.systems {
            row(&t.name, t.calls, t.seconds, t.bytes.map(|b| b.total()));
        }
        // The step's counted part: the systems that count their bytes, their time and bytes.
        let steps = self.systems.iter().map(|t| t.calls).max().unwrap_or(0);
        let counted = self
            .systems
            .iter()
            .filter_map(|t| t.bytes.map(|b| (t.seconds, b.total())));
        let (seconds, bytes) = counted.fold((0.0, 0), |(s, b), (ts, tb)| (s + ts, b + tb));
        row("counted", steps, seconds, Some(bytes));
        text
    }

    /// Collects the summary of `sim` after a run that took `wall_seconds`.
    pub fn collect<D: Dim>(
        scene: &str,
        sim: &Simulation<D>,
        wall_seconds: f64,
        error: Option<String>,
    ) -> Self {
        let s = &sim.ctx.state;
        let (st, model) = (&sim.ctx.numerics, &sim.ctx.model);
        // Over MPI every figure here is the ranks' (each call below is a collective, made
        // by every rank in this order).
        let comm = &sim.ctx.comm;
        // Each rank's points (exact in f64), in rank order.
        let points = comm.gather_all(&[sim.point_count() as f64]);
        let particles = points.iter().sum::<f64>() as usize;
        let total_mass = sim.total_mass();
        let max_u = max_displacements(sim);
        let mut largest = max_u.map_or([f64::NEG_INFINITY; 2], |u| [u.0, u.1]);
        comm.max(&mut largest);
        let max_u = (largest[0] >= 0.0).then_some((largest[0], largest[1]));
        // This process's peak, read once: the summary's own and, over ranks, its entry in
        // every rank's list.
        let peak = peak_memory_bytes();
        let ranks = (comm.size() > 1).then(|| {
            let mut migrations = [s.ranks.migrations as f64, comm.sent_bytes() as f64];
            comm.sum(&mut migrations);
            let peaks = comm.gather_all(&[peak.unwrap_or(0) as f64]);
            let nodes = comm.gather_all(&[sim.ctx.grid.node_count() as f64]);
            Ranks {
                count: comm.size(),
                points: points.iter().map(|&p| p as u64).collect(),
                migrations: migrations[0] as u64,
                rebalances: s.ranks.rebalances,
                split: sim.ctx.decomposition.split(),
                bounds: sim.ctx.decomposition.bounds.clone(),
                across: sim.ctx.decomposition.across.clone(),
                bytes_per_step: migrations[1] / (s.clock.step - s.ranks.first_step).max(1) as f64,
                peak_memory_bytes: peaks.iter().map(|&p| p as u64).collect(),
                nodes: nodes.iter().map(|&n| n as u64).collect(),
                grid_nodes: sim.ctx.grid.all_nodes().len() as u64,
            }
        });
        let rigid_bodies = body_results(sim);
        // Under load control a static state may follow a collapse (the body rests again on
        // what it heaved): the largest pressure is a limit only under displacement control.
        let displacement_control: Vec<CurvePoint> = s
            .control
            .curve
            .iter()
            // Motions' and whole bodies' rows (a part's row has its own name), not a body's
            // under load control: its pressure is the load it was given.
            .filter(|c| {
                model.motions.iter().any(|m| m.name == c.name)
                    || model
                        .bodies
                        .iter()
                        .any(|b| b.spec.name == c.name && b.spec.load.is_none())
            })
            .cloned()
            .collect();
        Summary {
            scene: scene.to_string(),
            dimension: D::N,
            axisymmetric: D::AXISYMMETRIC,
            outcome: match (&error, s.stop) {
                (Some(_), _) | (None, None) => Outcome::Failed,
                (None, Some(StopReason::Converged)) => Outcome::Converged,
                (None, Some(StopReason::MaxSteps)) => Outcome::MaxSteps,
                (None, Some(StopReason::MaxTime)) => Outcome::MaxTime,
                (None, Some(StopReason::DisplacementLimit)) => Outcome::DisplacementLimit,
                (None, Some(StopReason::Interrupted)) => Outcome::Interrupted,
            },
            converged: s.stop == Some(StopReason::Converged),
            stop_reason: if error.is_some() { None } else { s.stop },
            error,
            steps: s.clock.step,
            time: s.clock.time,
            time_step: st.dt,
            force_ratio: s.convergence.force_ratio(st.force_norm),
            force_norm: st.force_norm,
            force_ratio_max: s.convergence.force_ratio_max,
            force_ratio_mean: s.convergence.force_ratio_mean,
            energy_ratio: s.convergence.energy_ratio,
            tolerance: st.tolerance,
            static_window_movement: s.static_window.movement,
            kinetic_resets: s.resets.count,
            first_peak: s.resets.peaks.first().copied(),
            kinetic_energy: s.energy.current(),
            external_work: s.convergence.external_work,
            particles,
            total_mass,
            wall_seconds,
            particle_steps_per_second: if wall_seconds > 0.0 {
                particles as f64 * s.clock.step as f64 / wall_seconds
            } else {
                0.0
            },
            max_displacement: max_u.map(|u| u.0),
            max_horizontal_displacement: max_u.map(|u| u.1),
            surface_angle: if sim.measure_surface_angle {
                surface_angle(sim)
            } else {
                None
            },
            peak_memory_bytes: peak,
            traced: sim.traced_results(),
            systems: sim.schedule.timings(),
            snapshots: None,
            output_wait_seconds: None,
            limit_pressure: limit_pressure(&displacement_control),
            last_increment_rise: last_increment_rise(&displacement_control),
            curve: s.control.curve.clone(),
            rigid_bodies,
            stages: s.control.stages.clone(),
            ranks,
        }
    }
}

/// Every rigid body at the end of a run, the points the ranks put back out of it summed
/// and the deepest entry of all (a collective over MPI).
fn body_results<D: Dim>(sim: &Simulation<D>) -> Vec<BodyResult> {
    let (bodies, comm) = (&sim.ctx.state.control.bodies, &sim.ctx.comm);
    let mut entries: Vec<f64> = bodies.iter().map(|b| b.entries as f64).collect();
    let mut deepest: Vec<f64> = bodies.iter().map(|b| b.deepest_entry).collect();
    comm.sum(&mut entries);
    comm.max(&mut deepest);
    bodies
        .iter()
        .zip(entries.iter().zip(&deepest))
        .map(|(b, (&entries, &deepest_entry))| BodyResult {
            name: b.name.clone(),
            offset: b.offset,
            travel: b.travel,
            entries: entries as u64,
            deepest_entry,
        })
        .collect()
}

/// A rigid body at the end of a run (`rigid_bodies` in summary.json).
#[derive(Clone, Debug, Serialize)]
pub struct BodyResult {
    /// Name given in the scene.
    pub name: String,
    /// Displacement from its scene position (m, x y z).
    pub offset: [f64; 3],
    /// Distance travelled (m).
    pub travel: f64,
    /// Points that ended a step with their centre inside the body, each put back on its
    /// surface (counted once per step each).
    pub entries: u64,
    /// The deepest of those entries (m): compare it with the cell size.
    pub deepest_entry: f64,
}

/// The largest pressure over the curve's static states (Pa).
fn limit_pressure(curve: &[CurvePoint]) -> Option<f64> {
    curve.iter().filter_map(|c| c.pressure).reduce(f64::max)
}

/// (p_last − p_before) / p_limit over the last two static states with a pressure.
fn last_increment_rise(curve: &[CurvePoint]) -> Option<f64> {
    let p: Vec<f64> = curve.iter().filter_map(|c| c.pressure).collect();
    let limit = limit_pressure(curve)?;
    match p[..] {
        [.., before, last] if limit > 0.0 => Some((last - before) / limit),
        _ => None,
    }
}

/// Peak resident set size of this process (bytes), from `/proc/self/status` (VmHWM).
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::Outcome;

    #[test]
    fn outcome_names_are_the_ones_summary_json_writes() {
        use Outcome::*;
        for o in [
            Converged,
            MaxSteps,
            MaxTime,
            DisplacementLimit,
            Interrupted,
            Failed,
        ] {
            assert_eq!(serde_json::to_value(o).unwrap(), o.name());
        }
    }
}
