//! Factor of safety by strength reduction (`kdmpm fos SCENE`).
//!
//! Every Mohr-Coulomb material's strength is divided by a trial factor F: c/F,
//! φ_F = atan(tan φ / F), ψ_F = atan(tan ψ / F) and an explicit tension cut-off /F. The
//! scene is solved to its static state for each F. A trial *fails* when no static state is
//! found: a point moves farther than `failure_displacement`, the run reaches its time or step
//! limit, or it stops on an error (a failing slope running off its grid). The factor of
//! safety is bracketed between the largest F that stands and the smallest that fails, by
//! bisection to `tolerance` (Griffiths & Lane 1999, Géotechnique 49(3), who take a finite
//! element run's failure to converge as the criterion).
//!
//! Each trial is a normal run into `trials/F<factor>/` (history, points, plots); the
//! analysis writes `fos.csv` (the F–displacement curve), `fos.svg` and `summary.json` with
//! `factor_of_safety` and its `bracket`. The failure mechanism is the displacement field of
//! the trial at the smallest failing F (`mechanism`).

use crate::error::{Ending, SceneError};
use crate::infra::comm::Comm;
use crate::output::dir::write_atomic;
use crate::output::{Outcome, OutputDir};
use crate::run::{DisplacementLimit, Run, RunError};
use crate::scene::{LoadedScene, StrengthReductionSpec};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// One strength-reduction trial.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Trial {
    /// The strength reduction factor F.
    pub factor: f64,
    /// True when the trial found no static state.
    pub failed: bool,
    /// How the run ended.
    pub outcome: Outcome,
    /// The largest point displacement at the end (m).
    pub max_displacement: f64,
    /// Steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the trial.
    pub wall_seconds: f64,
    /// The trial's output directory, relative to the analysis's.
    pub dir: String,
}

impl Trial {
    /// One line on how the trial ended, as `kdmpm fos` prints it.
    pub fn describe(&self) -> String {
        format!(
            "F = {:.4}: {} ({}), largest displacement {:.3e} m, {} steps, {:.1} s",
            self.factor,
            if self.failed { "fails" } else { "stands" },
            self.outcome.name(),
            self.max_displacement,
            self.steps,
            self.wall_seconds
        )
    }
}

/// What the analysis found.
#[derive(Clone, Debug, Serialize)]
pub struct FosReport {
    /// The scene.
    pub scene: String,
    /// The middle of the final bracket.
    pub factor_of_safety: f64,
    /// The largest factor that stands and the smallest that fails.
    pub bracket: [f64; 2],
    /// The width the bisection stopped at.
    pub tolerance: f64,
    /// A trial fails when a point moves farther than this (m).
    pub failure_displacement: f64,
    /// The trial directory whose displacement field shows the failure mechanism.
    pub mechanism: String,
    /// Every trial, in the order run.
    pub trials: Vec<Trial>,
    /// Steps of every trial together.
    pub steps: u64,
    /// The water the trials held (pore pressures are not reduced), when the scene has some.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub water: Option<crate::water::WaterSpec>,
    /// The water of each stage that moves it, by stage name, in stage order: the trials end
    /// in the last one's (a drawdown's lowered table).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub stage_water: Vec<(String, crate::water::StageWaterSpec)>,
    /// Wall-clock seconds of the whole analysis.
    pub wall_seconds: f64,
}

/// Why the analysis could not give a factor of safety.
#[derive(Debug, thiserror::Error)]
pub enum FosError {
    /// The scene is unusable (exit 2).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene has no `strength_reduction` or no Mohr-Coulomb material (exit 2).
    #[error("{0}")]
    NotAnAnalysis(String),
    /// The bracket does not hold the factor of safety: the trials are in their folders.
    #[error("{0}")]
    NotBracketed(String),
    /// Stopped by a signal ([`crate::catch_signals`]) during the trial at this factor.
    #[error("interrupted during the trial at F = {0}: the trials so far are in their folders")]
    Interrupted(f64),
    /// The output directory cannot be used (exit 2).
    #[error("{0}")]
    OutputDir(String),
    /// The trial at this factor could not be run (its directory, its results).
    #[error("the trial at F = {0}: {1}")]
    Trial(f64, RunError),
    /// The output could not be written.
    #[error("cannot write into {0}: {1}")]
    Output(PathBuf, std::io::Error),
}

impl FosReport {
    /// The analysis's result in one line, as `kdmpm fos` prints it.
    pub fn describe(&self) -> String {
        format!(
            "factor of safety {:.3} (stands at {:.4}, fails at {:.4}), {} trials, {:.1} s",
            self.factor_of_safety,
            self.bracket[0],
            self.bracket[1],
            self.trials.len(),
            self.wall_seconds
        )
    }
}

impl FosError {
    /// Bad input (the scene, the output directory), an interrupted analysis, or one that
    /// went wrong.
    pub fn ending(&self) -> Ending {
        match self {
            FosError::Scene(_) | FosError::NotAnAnalysis(_) | FosError::OutputDir(_) => Ending::BadInput,
            FosError::Trial(_, e) => e.ending(),
            FosError::Interrupted(_) => Ending::Interrupted,
            FosError::NotBracketed(_) | FosError::Output(..) => Ending::Failed,
        }
    }
}

/// The scene with the strength of every material that has one divided by `factor`
/// ([`crate::materials::SceneMaterial::reduce_strength`]), in the scene and in every stage
/// that sets a material (a geostatic stage, then the soil's strength).
pub fn reduced(loaded: &LoadedScene, factor: f64) -> LoadedScene {
    let mut l = loaded.clone();
    for (_, m) in l.scene.every_material_mut() {
        m.reduce_strength(factor);
    }
    l
}

/// True when some material of the scene or of a stage has a strength to reduce.
fn has_strength(loaded: &LoadedScene) -> bool {
    loaded
        .scene
        .every_material()
        .any(|(_, m)| m.clone().reduce_strength(1.0))
}

/// Runs the analysis of `loaded` into `out`; `report` sees each trial as it ends.
pub fn strength_reduction(
    loaded: &LoadedScene,
    out: &Path,
    report: impl FnMut(&Trial),
) -> Result<FosReport, FosError> {
    strength_reduction_over(loaded, out, &Arc::new(Comm::single()), report)
}

/// [`strength_reduction`] with every trial split over the ranks of `comm` (under
/// `mpirun`): the ranks run each trial together, every rank finds the same outcome (the
/// trial's figures are the ranks'), so all bisect alike; rank 0 writes the analysis's files.
pub fn strength_reduction_over(
    loaded: &LoadedScene,
    out: &Path,
    comm: &Arc<Comm>,
    mut report: impl FnMut(&Trial),
) -> Result<FosReport, FosError> {
    let spec = loaded.scene.strength_reduction.clone().ok_or_else(|| {
        FosError::NotAnAnalysis(format!(
            "{}: the scene has no `strength_reduction` field (bracket, tolerance, \
             failure_displacement): see docs/scene-format.md",
            loaded.path.display()
        ))
    })?;
    // The scene as given, bracket and tolerance included, before any trial reduces it.
    crate::scene::check(loaded)?;
    if !has_strength(loaded) {
        return Err(FosError::NotAnAnalysis(format!(
            "{}: no material with a strength (such as MohrCoulomb), in the scene or its \
             stages: there is no strength to reduce",
            loaded.path.display()
        )));
    }
    let start = Instant::now();
    let io = |e: std::io::Error| FosError::Output(out.to_path_buf(), e);
    let _dir = claim_over(out, comm)?;
    let mut trials: Vec<Trial> = Vec::new();
    let mut trial = |f: f64| run_trial(loaded, &spec, f, out, comm, &mut report, &mut trials);
    let [lo, hi] = [spec.bracket[0], spec.bracket[1]];
    if trial(lo)?.failed {
        return Err(FosError::NotBracketed(format!(
            "the slope fails at F = {lo}, the bracket's low end: its factor of safety is below \
             {lo}; lower strength_reduction.bracket[0]"
        )));
    }
    if !trial(hi)?.failed {
        return Err(FosError::NotBracketed(format!(
            "the slope stands at F = {hi}, the bracket's high end: its factor of safety is above \
             {hi}; raise strength_reduction.bracket[1]"
        )));
    }
    let [lo, hi] = bisect([lo, hi], spec.tolerance, &mut trial)?;
    let fos = FosReport {
        scene: loaded.path.display().to_string(),
        factor_of_safety: 0.5 * (lo + hi),
        bracket: [lo, hi],
        tolerance: spec.tolerance,
        failure_displacement: spec.failure_displacement,
        mechanism: trial_dir(hi),
        steps: trials.iter().map(|t| t.steps).sum(),
        water: loaded.scene.water.clone(),
        stage_water: loaded
            .scene
            .stages
            .iter()
            .filter_map(|st| Some((st.name.clone(), st.water.clone()?)))
            .collect(),
        trials,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    if comm.is_root() {
        write_report(&fos, out).map_err(io)?;
    }
    Ok(fos)
}

/// Goes on with the bisection of the analysis `fos` of `loaded` (in `out`) from its
/// bracket until the bracket is no wider than `tolerance`: its trials are added to the
/// analysis's, its factor, bracket, mechanism, steps and wall time brought up to date, and
/// its files written again. `report` sees each new trial as it ends. (`--refine` narrows
/// two answers that lie closer than their brackets resolve.)
pub fn narrow(
    loaded: &LoadedScene,
    out: &Path,
    fos: &mut FosReport,
    tolerance: f64,
    report: impl FnMut(&Trial),
) -> Result<(), FosError> {
    narrow_over(loaded, out, fos, tolerance, &Arc::new(Comm::single()), report)
}

/// [`narrow`] with every trial split over the ranks of `comm`, as
/// [`strength_reduction_over`]; rank 0 writes the files.
pub fn narrow_over(
    loaded: &LoadedScene,
    out: &Path,
    fos: &mut FosReport,
    tolerance: f64,
    comm: &Arc<Comm>,
    mut report: impl FnMut(&Trial),
) -> Result<(), FosError> {
    let spec = loaded.scene.strength_reduction.clone().ok_or_else(|| {
        FosError::NotAnAnalysis(format!(
            "{}: the scene has no `strength_reduction` field",
            loaded.path.display()
        ))
    })?;
    let start = Instant::now();
    let _dir = claim_over(out, comm)?;
    let mut trials = Vec::new();
    let [lo, hi] = bisect(fos.bracket, tolerance, &mut |f| {
        run_trial(loaded, &spec, f, out, comm, &mut report, &mut trials)
    })?;
    fos.steps += trials.iter().map(|t| t.steps).sum::<u64>();
    fos.trials.extend(trials);
    fos.factor_of_safety = 0.5 * (lo + hi);
    fos.bracket = [lo, hi];
    fos.tolerance = tolerance;
    fos.mechanism = trial_dir(hi);
    fos.wall_seconds += start.elapsed().as_secs_f64();
    if !comm.is_root() {
        return Ok(());
    }
    write_report(fos, out).map_err(|e| FosError::Output(out.to_path_buf(), e))
}

/// The analysis's own directory, held by rank 0 for its whole run: one that cannot be made
/// (a file of that name, no permission) or that another run holds is bad input, on every
/// rank (a collective).
fn claim_over(out: &Path, comm: &Comm) -> Result<Option<OutputDir>, FosError> {
    let dir = comm.is_root().then(|| OutputDir::claim(out)).transpose();
    if comm.any(dir.is_err()) {
        return Err(FosError::OutputDir(match dir {
            Err(e) => e.to_string(),
            Ok(_) => format!("rank 0 could not take {}", out.display()),
        }));
    }
    Ok(dir.expect("checked above"))
}

/// Halves `[lo, hi]` (the slope stands at lo and fails at hi) by a trial at its middle
/// until it is no wider than `tolerance`, or no float lies between its ends (as narrow as
/// f64 allows).
fn bisect(
    [mut lo, mut hi]: [f64; 2],
    tolerance: f64,
    trial: &mut impl FnMut(f64) -> Result<Trial, FosError>,
) -> Result<[f64; 2], FosError> {
    while hi - lo > tolerance {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if trial(mid)?.failed {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok([lo, hi])
}

/// The folder of the trial at `factor`, relative to the analysis's: the factor's shortest
/// exact decimal, so that two trials never share a folder however fine the bisection.
fn trial_dir(factor: f64) -> String {
    format!("trials/F{factor}")
}

/// Runs the scene at `factor` into its trial folder, stopping early once a point moved
/// farther than the spec allows; `report` sees the trial and it joins `trials`. A trial a
/// signal stopped ends the analysis.
fn run_trial(
    loaded: &LoadedScene,
    spec: &StrengthReductionSpec,
    factor: f64,
    out: &Path,
    comm: &Arc<Comm>,
    report: &mut impl FnMut(&Trial),
    trials: &mut Vec<Trial>,
) -> Result<Trial, FosError> {
    let rel = trial_dir(factor);
    let path = out.join(&rel);
    let start = Instant::now();
    let run = Run::scene(reduced(loaded, factor))
        .into_dir(&path)
        .quiet(true)
        .without_checkpoints()
        .over(comm.clone())
        .displacement_limit(DisplacementLimit {
            every: spec.check_every,
            limit: spec.failure_displacement,
        })
        .go()
        .map_err(|e| match e {
            RunError::Scene(e) => FosError::Scene(e),
            e => FosError::Trial(factor, e),
        })?;
    let s = run.summary;
    let max_u = s.max_displacement.unwrap_or(0.0);
    let t = Trial {
        factor,
        failed: s.outcome != Outcome::Converged || max_u > spec.failure_displacement,
        outcome: s.outcome,
        max_displacement: max_u,
        steps: s.steps,
        wall_seconds: start.elapsed().as_secs_f64(),
        dir: rel,
    };
    if t.outcome == Outcome::Interrupted {
        return Err(FosError::Interrupted(factor));
    }
    report(&t);
    trials.push(t.clone());
    Ok(t)
}

/// `fos.csv`, `fos.svg` and `summary.json` of the analysis.
fn write_report(fos: &FosReport, out: &Path) -> std::io::Result<()> {
    let mut rows: Vec<&Trial> = fos.trials.iter().collect();
    rows.sort_by(|a, b| a.factor.total_cmp(&b.factor));
    write_atomic(&out.join("fos.csv"), |w| {
        writeln!(w, "factor,failed,outcome,max_displacement,steps,wall_seconds,dir")?;
        for t in &rows {
            writeln!(
                w,
                "{},{},{},{:.9e},{},{:.3},{}",
                t.factor,
                t.failed,
                t.outcome.name(),
                t.max_displacement,
                t.steps,
                t.wall_seconds,
                t.dir
            )?;
        }
        Ok(())
    })?;
    write_atomic(&out.join("fos.svg"), |w| w.write_all(plot(fos, &rows).as_bytes()))?;
    write_atomic(&out.join("summary.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, fos).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
}

/// The F–displacement curve: each trial's largest displacement against its factor,
/// standing trials filled, failing ones open, the bracket shaded.
fn plot(fos: &FosReport, rows: &[&Trial]) -> String {
    use plotters::prelude::*;
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, (960, 600)).into_drawing_area();
        let _ = root.fill(&WHITE);
        let draw = || -> Result<(), Box<dyn std::error::Error>> {
            let (f0, f1) = rows.iter().fold((f64::INFINITY, 0.0f64), |(a, b), t| {
                (a.min(t.factor), b.max(t.factor))
            });
            let u_hi = rows
                .iter()
                .map(|t| t.max_displacement)
                .fold(fos.failure_displacement, f64::max);
            let u_lo = rows
                .iter()
                .map(|t| t.max_displacement)
                .filter(|u| *u > 0.0)
                .fold(u_hi, f64::min);
            let (y0, y1) = crate::output::plots::log_range([u_lo, u_hi].into_iter());
            let pad = 0.05 * (f1 - f0).max(1e-3);
            let mut c = crate::output::plots::log_chart(
                &root,
                &format!(
                    "Strength reduction: F = {:.3} (bracket {:.4}–{:.4})",
                    fos.factor_of_safety, fos.bracket[0], fos.bracket[1]
                ),
                ((f0 - pad)..(f1 + pad), "strength reduction factor F"),
                ((y0, y1), "largest displacement (m)"),
                90,
            )?;
            c.draw_series(std::iter::once(Rectangle::new(
                [(fos.bracket[0], y0), (fos.bracket[1], y1)],
                RED.mix(0.15).filled(),
            )))?;
            let limit = fos.failure_displacement;
            c.draw_series(LineSeries::new(
                vec![(f0 - pad, limit), (f1 + pad, limit)],
                RED.stroke_width(2),
            ))?
            .label(format!("failure displacement {limit} m"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .map(|t| (t.factor, t.max_displacement.max(y0)))
                .collect();
            c.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?;
            c.draw_series(rows.iter().map(|t| {
                let p = (t.factor, t.max_displacement.max(y0));
                if t.failed {
                    Circle::new(p, 6, BLUE.stroke_width(2))
                } else {
                    Circle::new(p, 6, BLUE.filled())
                }
            }))?
            .label("trial (filled: stands, open: fails)")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, BLUE.filled()));
            c.configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .border_style(BLACK)
                .background_style(WHITE.mix(0.9))
                .label_font(("sans-serif", 14))
                .draw()?;
            Ok(())
        };
        let _ = draw();
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bisecting [1, 2] to the finest tolerance allowed (1e-7 × 2) gives 24 factors, each
    /// its own folder; with four decimals once 22 trials shared 15 folders, and `mechanism`
    /// named a trial that stood.
    #[test]
    fn every_trial_of_the_finest_bisection_has_its_own_folder() {
        let (mut lo, mut hi) = (1.0f64, 2.0f64);
        let mut dirs = vec![trial_dir(lo), trial_dir(hi)];
        let mut k = 0;
        while hi - lo > 2e-7 {
            let mid = 0.5 * (lo + hi);
            dirs.push(trial_dir(mid));
            // Alternate the sides, as a bisection that finds the factor in the middle does.
            if k % 2 == 0 {
                hi = mid
            } else {
                lo = mid
            }
            k += 1;
        }
        let mut unique = dirs.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), dirs.len(), "{dirs:?}");
        assert_eq!(dirs.len(), 25);
    }
}
