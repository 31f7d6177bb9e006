//! The discretisation error of an answer, by refinement (`--refine` of `kdmpm run` and
//! `kdmpm fos`).
//!
//! The analysis is repeated with the cell size halved, once or twice: h, h/2 (and h/4);
//! everything the scene gives in metres and seconds stays as it is, and what it counts in
//! steps grows with the steps (see [`finer`]). From the answers f₁ (h), f₂ (h/2), f₃ (h/4)
//! Richardson's extrapolation (Richardson 1911; Roache 1998, *Verification and Validation
//! in Computational Science and Engineering*, ch. 5) gives
//!
//! - the observed order p = ln((f₁ − f₂)/(f₂ − f₃)) / ln 2,
//! - the extrapolated answer f* = f₃ + (f₃ − f₂)/(2^p − 1),
//! - the discretisation error of the scene's own answer, f₁ − f*.
//!
//! The order is observed only when the answers converge cleanly: the differences have one
//! sign, shrink, and stand above what each answer resolves (a factor of safety is known to
//! half its bisection bracket, a limit load to the stopping tolerance K_F). Otherwise
//! nothing is extrapolated and the report says why, with the spread of the answers. With
//! two cell sizes the order cannot be observed: it is taken as 1, the order of limit loads
//! in MPM, whose error comes from the edge of the loaded area, about h/B (said in the
//! report).

use crate::error::Ending;
use crate::fos::{FosError, FosReport, Trial};
use crate::infra::comm::Comm;
use crate::output::dir::write_atomic;
use crate::output::Outcome;
use crate::run::{Run, RunError, RunReport};
use crate::scene::{CheckpointEvery, LoadedScene, Scene, TimeStep};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Cell sizes an estimate may use: the scene's and one or two halvings.
pub const LEVELS: std::ops::RangeInclusive<u32> = 2..=3;

/// The scene at cell size h/`ratio`: `grid.cell_size` divided, `grid.cells` multiplied;
/// what counts steps (`max_steps`, `history_every`, snapshots and checkpoints every N
/// steps, the strength reduction's `check_every`) multiplied, a fixed Δt divided, as the
/// Courant number does by itself. Lengths, times, loads and points a cell side stay.
///
/// The changes are made to the scene's text ([`finer_overrides`]), so that a checkpoint of
/// the finer run, which keeps the text, resumes at the finer cell size.
pub fn finer(loaded: &LoadedScene, ratio: u32) -> Result<LoadedScene, crate::error::SceneError> {
    loaded.with_overrides(&finer_overrides(&loaded.scene, ratio))
}

/// The `path=value` overrides that make [`finer`]'s scene: the one list of what a
/// refinement changes, which `kdmpm study`'s `Refine` axis passes to its runs as well.
pub fn finer_overrides(s: &Scene, ratio: u32) -> Vec<String> {
    let r = u64::from(ratio);
    let times = |n: u64| n.saturating_mul(r);
    let cells: Vec<String> = s
        .grid
        .cells
        .iter()
        .map(|&c| (c * ratio as usize).to_string())
        .collect();
    let mut o = vec![
        format!("grid.cell_size={:?}", s.grid.cell_size / f64::from(ratio)),
        format!("grid.cells=[{}]", cells.join(", ")),
        format!("output.history_every={}", times(s.output.history_every)),
    ];
    if let TimeStep::Fixed(dt) = s.solver.time_step {
        o.push(format!("solver.time_step=Fixed({:?})", dt / f64::from(ratio)));
    }
    if let Some(n) = s.solver.max_steps {
        o.push(format!("solver.max_steps={}", times(n)));
    }
    if let Some(n) = s.output.snapshots.as_ref().and_then(|sn| sn.every_steps) {
        o.push(format!("output.snapshots.every_steps={}", times(n)));
    }
    if let Some(CheckpointEvery::Steps(n)) = s.solver.checkpoint_every {
        o.push(format!("solver.checkpoint_every=Steps({})", times(n)));
    }
    if let Some(sr) = &s.strength_reduction {
        o.push(format!(
            "strength_reduction.check_every={}",
            times(sr.check_every)
        ));
    }
    o
}

/// One answer of a refinement.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Level {
    /// The cell size h (m).
    pub cell_size: f64,
    /// The answer at that cell size.
    pub value: f64,
    /// How finely the answer is known by itself (half the bisection bracket of a factor of
    /// safety; the stopping tolerance times a limit load).
    pub resolution: f64,
    /// Where its run wrote its files, relative to the analysis's directory ("." for the
    /// scene's own cell size).
    pub dir: String,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

/// What refinement says about an answer.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refinement {
    /// What was refined (`limit_pressure`, `factor_of_safety`).
    pub quantity: String,
    /// Its unit ("kPa", "" for a factor).
    pub unit: String,
    /// The answers, scene's cell size first, each half the cell size of the one before.
    pub levels: Vec<Level>,
    /// The observed order p, when three answers converge cleanly.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// The order the extrapolation used: observed, or 1 assumed from two answers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub order_used: Option<f64>,
    /// The extrapolated answer f*.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolated: Option<f64>,
    /// The discretisation error of the scene's own answer, f₁ − f* (positive: the scene's
    /// answer is above the converged one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<f64>,
    /// The spread of the answers, largest less smallest.
    pub spread: f64,
    /// How the estimate was made, or why there is none.
    pub note: String,
}

/// Richardson's estimate from `levels` (h, h/2, h/4 ...; two or three), see the module.
pub fn estimate(quantity: &str, unit: &str, levels: Vec<Level>) -> Refinement {
    let f: Vec<f64> = levels.iter().map(|l| l.value).collect();
    let res: Vec<f64> = levels.iter().map(|l| l.resolution).collect();
    let noise = |a: usize, b: usize| res[a] + res[b];
    let spread =
        f.iter().copied().fold(f64::NEG_INFINITY, f64::max) - f.iter().copied().fold(f64::INFINITY, f64::min);
    // What narrows an answer's resolution, for the note.
    let narrower = match quantity {
        "factor_of_safety" => " even bisected to an eighth of strength_reduction.tolerance",
        _ => " (a smaller solver.tolerance narrows each answer)",
    };
    let mut out = Refinement {
        quantity: quantity.into(),
        unit: unit.into(),
        levels,
        order: None,
        order_used: None,
        extrapolated: None,
        error: None,
        spread,
        note: String::new(),
    };
    let (order, finest, step) = match f[..] {
        [f1, f2] => {
            if (f1 - f2).abs() <= noise(0, 1) {
                out.note = format!(
                    "the two answers differ by less than they resolve{narrower}: no trend to extrapolate"
                );
                return out;
            }
            out.note = "two cell sizes: order 1 assumed (limit loads in MPM converge about as h/B)".into();
            (None, f2, f2 - f1)
        }
        [f1, f2, f3] => {
            let (d1, d2) = (f1 - f2, f2 - f3);
            let why = if d1.abs() <= noise(0, 1) || d2.abs() <= noise(1, 2) {
                Some(format!("two answers differ by less than they resolve{narrower}"))
            } else if d1.signum() != d2.signum() {
                Some("the answers are not monotone in the cell size".to_string())
            } else if d2.abs() >= d1.abs() {
                Some("the differences do not shrink with the cell size".to_string())
            } else {
                None
            };
            if let Some(why) = why {
                out.note = format!("no clean order: {why}; not extrapolated");
                return out;
            }
            let p = (d1 / d2).ln() / 2f64.ln();
            out.note = "three cell sizes: order observed".into();
            (Some(p), f3, f3 - f2)
        }
        _ => unreachable!("a refinement has two or three cell sizes"),
    };
    let p = order.unwrap_or(1.0);
    let extrapolated = finest + step / (2f64.powf(p) - 1.0);
    out.order = order;
    out.order_used = Some(p);
    out.extrapolated = Some(extrapolated);
    out.error = Some(f[0] - extrapolated);
    out
}

impl Refinement {
    /// The estimate in a few lines, as the terminal shows it.
    pub fn describe(&self) -> String {
        let unit = |v: f64| match self.unit.as_str() {
            "" => format!("{v:.4}"),
            "Pa" => format!("{:.2} kPa", v / 1e3),
            u => format!("{v:.4e} {u}"),
        };
        let mut s = String::new();
        for l in &self.levels {
            s += &format!(
                "  h = {} m: {} {} ± {} ({:.1} s)\n",
                l.cell_size,
                self.quantity.replace('_', " "),
                unit(l.value),
                unit(l.resolution),
                l.wall_seconds
            );
        }
        let f1 = self.levels[0].value;
        match (self.extrapolated, self.error) {
            (Some(x), Some(e)) => {
                let order = match self.order {
                    Some(p) => format!("observed order {p:.2}"),
                    None => "order 1 assumed".into(),
                };
                s += &format!(
                    "  extrapolated {} ({order}); the answer at h = {} m is {} ± {} ({:+.1} %)\n",
                    unit(x),
                    self.levels[0].cell_size,
                    unit(f1),
                    unit(e.abs()),
                    100.0 * e / x
                );
            }
            _ => {
                s += &format!("  {}: the answers spread over {}\n", self.note, unit(self.spread));
            }
        }
        s
    }
}

/// Why a refinement could not give its estimate.
#[derive(Debug, thiserror::Error)]
pub enum RefineError {
    /// The scene or the request cannot be refined (exit 2).
    #[error("{0}")]
    NotRefinable(String),
    /// The run at this cell size could not be made.
    #[error("at h = {0} m: {1}")]
    Run(f64, Box<RunError>),
    /// The strength-reduction analysis at this cell size could not be made.
    #[error("at h = {0} m: {1}")]
    Fos(f64, Box<FosError>),
    /// The run at this cell size gave no answer (an error, or no limit pressure); the runs
    /// before it are in their folders.
    #[error("at h = {0} m: {1}")]
    NoAnswer(f64, String),
    /// Stopped by a signal during the run at this cell size.
    #[error("interrupted during the run at h = {0} m: the cell sizes before it are in their folders")]
    Interrupted(f64),
    /// The summary could not be written.
    #[error("cannot write {0}: {1}")]
    Output(PathBuf, std::io::Error),
}

impl RefineError {
    /// How a command ends with this error.
    pub fn ending(&self) -> Ending {
        match self {
            RefineError::NotRefinable(_) => Ending::BadInput,
            RefineError::Run(_, e) => e.ending(),
            RefineError::Fos(_, e) => e.ending(),
            RefineError::Interrupted(_) => Ending::Interrupted,
            RefineError::NoAnswer(..) | RefineError::Output(..) => Ending::Failed,
        }
    }
}

/// Refuses a number of cell sizes outside [`LEVELS`].
fn check_levels(count: u32) -> Result<(), RefineError> {
    match LEVELS.contains(&count) {
        true => Ok(()),
        false => Err(RefineError::NotRefinable(format!(
            "--refine takes {} or {} cell sizes (h, h/2 and h/4), found {count}",
            LEVELS.start(),
            LEVELS.end()
        ))),
    }
}

/// Where the analysis at `ratio` (1, 2, 4) writes: the scene's own cell size in `out`, the
/// finer ones in `out/refine/h<cell size>/`.
fn level_dir(out: &Path, ratio: u32, cell_size: f64) -> (PathBuf, String) {
    match ratio {
        1 => (out.to_path_buf(), ".".into()),
        _ => {
            let rel = format!("refine/h{cell_size}");
            (out.join(&rel), rel)
        }
    }
}

/// Adds `refinement` to the `summary.json` in `out` (written whole, as every summary).
fn add_to_summary(out: &Path, refinement: &Refinement) -> Result<(), RefineError> {
    let path = out.join("summary.json");
    let io = |e: std::io::Error| RefineError::Output(path.clone(), e);
    let text = std::fs::read_to_string(&path).map_err(io)?;
    let mut summary: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| io(std::io::Error::other(e)))?;
    summary["refinement"] = serde_json::to_value(refinement).map_err(|e| io(std::io::Error::other(e)))?;
    write_atomic(&path, |w| {
        serde_json::to_writer_pretty(&mut *w, &summary).map_err(std::io::Error::other)?;
        writeln!(w)
    })
    .map_err(io)
}

/// One answer of an analysis at one cell size: the analysis's own report, the answer, how
/// finely it is known ([`Level::resolution`]) and the wall time.
type Answer<T> = (T, f64, f64, f64);

/// Makes the analysis `at` (the scene at a cell size, its folder, the cell size) at
/// `count` cell sizes (checked by the caller), adds Richardson's estimate of `quantity` (in `unit`) to the
/// `summary.json` in `out`, and returns the report at the scene's own cell size with it.
/// Over the ranks of `comm` every rank makes every analysis; rank 0 writes.
///
/// Where two neighbouring answers lie closer than they resolve, `narrow` is asked to know
/// each of them more finely (a factor of safety bisects on); it says whether it could.
/// They are compared again until they are resolved or neither can narrow.
fn refine<T>(
    loaded: &LoadedScene,
    (out, comm): (&Path, &Comm),
    count: u32,
    (quantity, unit): (&str, &str),
    mut at: impl FnMut(LoadedScene, PathBuf, f64) -> Result<Answer<T>, RefineError>,
    mut narrow: impl FnMut(&mut T, &mut Level) -> Result<bool, RefineError>,
    mut show: impl FnMut(&Level),
) -> Result<(T, Refinement), RefineError> {
    // The finer levels of an earlier analysis into the same folder (`--refine 3`, then
    // `--refine 2`) would stand beside this one's as if they were its own.
    // Rank 0's to remove, before any rank writes (the first run's start is a collective).
    let earlier = out.join("refine");
    let removed = match comm.is_root().then(|| std::fs::remove_dir_all(&earlier)) {
        Some(Err(e)) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    };
    if comm.any(removed.is_err()) {
        let e = removed
            .err()
            .unwrap_or_else(|| std::io::Error::other("rank 0 could not remove it"));
        return Err(RefineError::Output(earlier, e));
    }
    let mut reports = Vec::new();
    let mut levels = Vec::new();
    for k in 0..count {
        let ratio = 1u32 << k;
        let scene = finer(loaded, ratio).map_err(|e| RefineError::NotRefinable(e.to_string()))?;
        let h = scene.scene.grid.cell_size;
        let (dir, rel) = level_dir(out, ratio, h);
        let (report, value, resolution, wall_seconds) = at(scene, dir, h)?;
        let level = Level {
            cell_size: h,
            value,
            resolution,
            dir: rel,
            wall_seconds,
        };
        show(&level);
        levels.push(level);
        reports.push(report);
    }
    let unresolved = |l: &[Level]| {
        (1..l.len()).find(|&k| (l[k].value - l[k - 1].value).abs() <= l[k].resolution + l[k - 1].resolution)
    };
    while let Some(k) = unresolved(&levels) {
        let (coarse, fine) = reports.split_at_mut(k);
        let (lc, lf) = levels.split_at_mut(k);
        let a = narrow(&mut coarse[k - 1], &mut lc[k - 1])?;
        let b = narrow(&mut fine[0], &mut lf[0])?;
        if !(a || b) {
            break;
        }
    }
    let refinement = estimate(quantity, unit, levels);
    if comm.is_root() {
        add_to_summary(out, &refinement)?;
    }
    Ok((reports.swap_remove(0), refinement))
}

/// What `kdmpm run --refine` estimates.
#[derive(Clone, Debug, PartialEq)]
pub enum RunQuantity {
    /// The largest pressure of the motions' static states (`limit_pressure`): a footing.
    LimitPressure,
    /// The mean pressure of `curve.csv`'s rows named `row` whose displacement is at least
    /// `from` (m): a penetrometer's steady resistance (a T-bar over its second diameter).
    MeanPressure {
        /// The rows' name (a motion, a rigid body, or a body's part as `body.part`, with
        /// an `area`).
        row: String,
        /// The displacement from which rows count (m, ≥ 0).
        from: f64,
    },
}

/// `kdmpm run --refine`: the scene's limit pressure (`limit_pressure` of its motions) at
/// `count` cell sizes, with Richardson's estimate. Returns the report of the run at the
/// scene's own cell size (in `out`) and the estimate, which is added to its `summary.json`.
/// `show` hears of each cell size as it finishes.
pub fn limit_pressure(
    loaded: &LoadedScene,
    out: &Path,
    count: u32,
    quiet: bool,
    show: impl FnMut(&Level),
) -> Result<(RunReport, Refinement), RefineError> {
    pressure(loaded, out, count, quiet, &RunQuantity::LimitPressure, show)
}

/// `kdmpm run --refine` of `what` ([`RunQuantity`]) at `count` cell sizes, as
/// [`limit_pressure`]. A limit pressure is known to the stopping tolerance times it; a
/// mean over static states to that, or to the standard error of their mean where their
/// swing is wider.
pub fn pressure(
    loaded: &LoadedScene,
    out: &Path,
    count: u32,
    quiet: bool,
    what: &RunQuantity,
    show: impl FnMut(&Level),
) -> Result<(RunReport, Refinement), RefineError> {
    pressure_over(loaded, out, count, quiet, what, &Arc::new(Comm::single()), show)
}

/// [`pressure`] with every run split over the ranks of `comm` (under `mpirun`): the ranks
/// find the same answers (a run's figures are the ranks'); rank 0 writes the files.
pub fn pressure_over(
    loaded: &LoadedScene,
    out: &Path,
    count: u32,
    quiet: bool,
    what: &RunQuantity,
    comm: &Arc<Comm>,
    show: impl FnMut(&Level),
) -> Result<(RunReport, Refinement), RefineError> {
    check_levels(count)?;
    let name = loaded.path.display();
    let quantity = match what {
        RunQuantity::LimitPressure if !loaded.scene.has_limit_pressure() => {
            return Err(RefineError::NotRefinable(format!(
                "{name}: --refine estimates the error of a limit pressure, and the scene has no \
                 motion with a loaded `area`"
            )));
        }
        RunQuantity::LimitPressure => "limit_pressure",
        RunQuantity::MeanPressure { row, from } => match loaded.scene.pressure_window_fault(row, *from) {
            Some(rule) => return Err(RefineError::NotRefinable(format!("{name}: --mean-from: {rule}"))),
            None => "mean_pressure",
        },
    };
    let tolerance = loaded.scene.solver.tolerance;
    let run = |scene: LoadedScene, dir: PathBuf, h: f64| {
        let start = Instant::now();
        let report = Run::scene(scene)
            .into_dir(dir)
            .quiet(quiet)
            .over(comm.clone())
            .go()
            .map_err(|e| RefineError::Run(h, Box::new(e)))?;
        if report.summary.outcome == Outcome::Interrupted {
            return Err(RefineError::Interrupted(h));
        }
        if let Some(e) = &report.error {
            return Err(RefineError::NoAnswer(h, e.to_string()));
        }
        let (value, resolution) = match what {
            RunQuantity::LimitPressure => {
                let Some(value) = report.summary.limit_pressure else {
                    return Err(RefineError::NoAnswer(
                        h,
                        "the run reached no static state of its motions: no limit pressure".into(),
                    ));
                };
                (value, tolerance * value.abs())
            }
            RunQuantity::MeanPressure { row, from } => {
                let states: Vec<f64> = report
                    .summary
                    .curve
                    .iter()
                    .filter(|c| c.name == *row && c.displacement >= *from)
                    .filter_map(|c| c.pressure)
                    .collect();
                mean_and_resolution(&states, tolerance).ok_or_else(|| {
                    RefineError::NoAnswer(
                        h,
                        format!("no static state of `{row}` at a displacement of {from} m or more"),
                    )
                })?
            }
        };
        let wall = start.elapsed().as_secs_f64();
        Ok((report, value, resolution, wall))
    };
    // A pressure is known to the stopping tolerance; a run at a finer one would be a new
    // run, not a continuation.
    refine(
        loaded,
        (out, comm),
        count,
        (quantity, "Pa"),
        run,
        |_, _| Ok(false),
        show,
    )
}

/// The mean of `states` (Pa) and how finely it is known: the stopping `tolerance` times
/// it, or the standard error of the mean, s/√n, where the states swing more.
fn mean_and_resolution(states: &[f64], tolerance: f64) -> Option<(f64, f64)> {
    let n = states.len() as f64;
    if states.is_empty() {
        return None;
    }
    let mean = states.iter().sum::<f64>() / n;
    let spread = if states.len() > 1 {
        (states.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt()
    } else {
        0.0
    };
    Some((mean, spread.max(tolerance * mean.abs())))
}

/// `kdmpm fos --refine`: the factor of safety at `count` cell sizes, with Richardson's
/// estimate. Returns the analysis at the scene's own cell size (in `out`) and the
/// estimate, which is added to its `summary.json`. `show` hears of every trial.
pub fn factor_of_safety(
    loaded: &LoadedScene,
    out: &Path,
    count: u32,
    show: impl FnMut(f64, &Trial),
) -> Result<(FosReport, Refinement), RefineError> {
    factor_of_safety_over(loaded, out, count, &Arc::new(Comm::single()), show)
}

/// [`factor_of_safety`] with every trial split over the ranks of `comm` (under `mpirun`),
/// as [`crate::fos::strength_reduction_over`]; rank 0 writes the files.
pub fn factor_of_safety_over(
    loaded: &LoadedScene,
    out: &Path,
    count: u32,
    comm: &Arc<Comm>,
    show: impl FnMut(f64, &Trial),
) -> Result<(FosReport, Refinement), RefineError> {
    check_levels(count)?;
    let show = std::cell::RefCell::new(show);
    let fail = |h: f64| {
        move |e| match e {
            FosError::Interrupted(_) => RefineError::Interrupted(h),
            e => RefineError::Fos(h, Box::new(e)),
        }
    };
    // An analysis's answer, how finely its bracket knows it, and its wall time.
    let answer = |r: &FosReport| {
        (
            r.factor_of_safety,
            0.5 * (r.bracket[1] - r.bracket[0]),
            r.wall_seconds,
        )
    };
    let analyse = |scene: LoadedScene, dir: PathBuf, h: f64| {
        let report = crate::fos::strength_reduction_over(&scene, &dir, comm, |t| (show.borrow_mut())(h, t))
            .map_err(fail(h))?;
        let (value, resolution, wall) = answer(&report);
        Ok(((report, scene, dir), value, resolution, wall))
    };
    // Each bisection halved again, to an eighth of the scene's tolerance at most.
    let floor = loaded
        .scene
        .strength_reduction
        .as_ref()
        .map_or(0.0, |sr| sr.tolerance / NARROWEST);
    let narrow = |(report, scene, dir): &mut (FosReport, LoadedScene, PathBuf), level: &mut Level| {
        let tolerance = 0.5 * report.tolerance;
        if tolerance < floor * (1.0 - 1e-12) {
            return Ok(false);
        }
        let h = level.cell_size;
        crate::fos::narrow_over(scene, dir, report, tolerance, comm, |t| (show.borrow_mut())(h, t))
            .map_err(fail(h))?;
        (level.value, level.resolution, level.wall_seconds) = answer(report);
        Ok(true)
    };
    let ((report, _, _), refinement) = refine(
        loaded,
        (out, comm),
        count,
        ("factor_of_safety", ""),
        analyse,
        narrow,
        |_| {},
    )?;
    Ok((report, refinement))
}

/// How far `--refine` narrows a factor of safety's bisection below the scene's
/// `strength_reduction.tolerance` (a divisor): two answers closer than their brackets
/// resolve are bisected on, each halving one trial more, to tolerance/8.
pub const NARROWEST: f64 = 8.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn levels(values: &[f64], resolution: f64) -> Vec<Level> {
        values
            .iter()
            .enumerate()
            .map(|(k, &value)| Level {
                cell_size: 0.5f64.powi(k as i32),
                value,
                resolution,
                dir: String::new(),
                wall_seconds: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_first_order_sequence_extrapolates_to_its_limit() {
        // f = 50 + 8 h: 58, 54, 52.
        let r = estimate("limit_pressure", "kPa", levels(&[58.0, 54.0, 52.0], 0.1));
        assert!((r.order.unwrap() - 1.0).abs() < 1e-12);
        assert!((r.extrapolated.unwrap() - 50.0).abs() < 1e-12);
        assert!((r.error.unwrap() - 8.0).abs() < 1e-12);
    }

    #[test]
    fn a_second_order_sequence_shows_order_two() {
        // f = 1.4 + 0.16 h²: 1.56, 1.44, 1.41.
        let r = estimate("factor_of_safety", "", levels(&[1.56, 1.44, 1.41], 0.001));
        assert!((r.order.unwrap() - 2.0).abs() < 1e-9);
        assert!((r.extrapolated.unwrap() - 1.4).abs() < 1e-12);
    }

    #[test]
    fn two_levels_assume_first_order() {
        let r = estimate("limit_pressure", "kPa", levels(&[55.58, 52.92], 0.5));
        assert_eq!(r.order, None);
        assert_eq!(r.order_used, Some(1.0));
        assert!((r.extrapolated.unwrap() - 50.26).abs() < 1e-9);
    }

    #[test]
    fn a_non_monotone_sequence_is_not_extrapolated() {
        let r = estimate("factor_of_safety", "", levels(&[1.414, 1.383, 1.39], 0.001));
        assert_eq!(r.extrapolated, None);
        assert!(r.note.contains("not monotone"), "{}", r.note);
        assert!((r.spread - 0.031).abs() < 1e-12);
    }

    #[test]
    fn differences_within_the_resolution_are_not_a_trend() {
        let r = estimate("factor_of_safety", "", levels(&[1.414, 1.406, 1.40], 0.01));
        assert_eq!(r.extrapolated, None);
        assert!(r.note.contains("resolve"), "{}", r.note);
    }

    #[test]
    fn growing_differences_are_not_extrapolated() {
        let r = estimate("limit_pressure", "kPa", levels(&[55.0, 54.0, 52.0], 0.1));
        assert_eq!(r.extrapolated, None);
        assert!(r.note.contains("do not shrink"), "{}", r.note);
    }
}
