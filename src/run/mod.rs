//! One runner for every way a scene is stepped: `kdmpm run` and `kdmpm resume`, each trial
//! of `kdmpm fos`, the tests' in-memory runs and a library user's program.
//!
//! [`Run`] starts from a scene ([`Run::scene`]) or from the checkpoint in a run's directory
//! ([`Run::resume`]), builds the simulation, attaches the outputs ([`Recorder`]) when it
//! writes into a directory, and steps to the stop with small hooks called after every step,
//! in this order:
//!
//! 1. the caller's observer ([`Run::observe`]);
//! 2. progress on stderr, unless quiet ([`Progress`]);
//! 3. the stop request ([`StopSignal`]): the run ends as `Interrupted`;
//! 4. checkpoints, at `solver.checkpoint_every` and when interrupted ([`Run::without_checkpoints`]
//!    turns them off);
//! 5. a strength-reduction trial's displacement limit ([`Run::displacement_limit`]).
//!
//! Over MPI ([`Run::over`] a communicator of several ranks) each rank steps its part of the
//! scene; rank 0 writes the shared files, each rank its own points.
//!
//! ```no_run
//! use kdmpm::run::Run;
//! use kdmpm::scene::LoadedScene;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let scene = LoadedScene::from_file("scenes/bar.ron".as_ref(), &[])?;
//! let report = Run::scene(scene).into_dir("out/bar").quiet(true).go()?;
//! println!("{}", report.describe());
//! # Ok(())
//! # }
//! ```

pub mod distribute;
mod hooks;
mod ranks;

pub use hooks::DisplacementLimit;

use crate::checkpoint::{self, CheckpointError};
use crate::dim::Dim;
use crate::error::{Ending, SceneError, StepError};
use crate::infra::comm::Comm;
use crate::interrupt::StopSignal;
use crate::output::{Outcome, OutputDir, Progress, Recorder, Summary};
use crate::scene::{build, build_part, LoadedScene, RankPart};
use crate::simulation::Simulation;
use crate::state::SolverState;
use crate::systems::convergence::ratio_text;
use hooks::{Checkpoints, Hook, Observer, ShowProgress, StopOnRequest};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The caller's observer of the state after each step.
type ObserveFn<'a> = Box<dyn FnMut(&SolverState) + Send + 'a>;

/// Where a run starts.
enum Start {
    /// A scene, from step 0.
    Scene(Box<LoadedScene>),
    /// The checkpoint in this run directory.
    Checkpoint(PathBuf),
}

/// A run to be made: what it starts from, where it writes, and what watches it.
pub struct Run<'a> {
    start: Start,
    watch: Watch<'a>,
}

/// Where a run writes and what watches its steps.
struct Watch<'a> {
    out: Option<PathBuf>,
    quiet: bool,
    checkpoints: bool,
    limit: Option<DisplacementLimit>,
    stop: StopSignal,
    comm: Arc<Comm>,
    observer: Option<ObserveFn<'a>>,
}

/// Why a run could not be made, or its results not written. A run that stepped and
/// stopped on an error is not one of these: its [`RunReport`] carries the error.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene is unusable.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The checkpoint cannot be read or does not fit.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The output directory cannot be used (held by another run, not creatable, not
    /// writable).
    #[error("{0}")]
    OutputDir(String),
    /// The scene cannot be split over the ranks.
    #[error("{0}")]
    Ranks(String),
    /// The run stepped, but its results could not be written.
    #[error("{0}")]
    Results(String),
}

impl RunError {
    /// Bad input (a scene, a checkpoint, an output directory, a split over ranks) or a run
    /// that went wrong (its results could not be written).
    pub fn ending(&self) -> Ending {
        match self {
            RunError::Results(_) => Ending::Failed,
            _ => Ending::BadInput,
        }
    }
}

/// What a run that stepped gives back.
#[derive(Debug)]
pub struct RunReport {
    /// The summary (as written to `summary.json` when the run has a directory).
    pub summary: Summary,
    /// The error the run stopped on, if it did (its outcome is then `Failed`).
    pub error: Option<StepError>,
    /// What the outputs left out, and why (a `points.vtu` not written over a NaN).
    pub notes: Vec<String>,
    /// The directory written into.
    pub dir: Option<PathBuf>,
}

impl RunReport {
    /// The run's last line: how it ended, its steps, time, ratios, resets and wall time.
    pub fn describe(&self) -> String {
        let s = &self.summary;
        format!(
            "{} after {} steps, t = {:.4} s: K_F = {} (max) / {} (mean), K_E = {}, {} resets, {:.2} s wall{}",
            match s.outcome {
                Outcome::Converged => "converged",
                Outcome::Interrupted => "interrupted (kdmpm resume continues it)",
                Outcome::Failed => "failed",
                _ => "stopped at its limit",
            },
            s.steps,
            s.time,
            ratio_text(s.force_ratio_max, 3),
            ratio_text(s.force_ratio_mean, 3),
            ratio_text(s.energy_ratio, 3),
            s.kinetic_resets,
            s.wall_seconds,
            self.dir
                .as_ref()
                .map_or(String::new(), |d| format!(" → {}", d.display()))
        )
    }
}

impl<'a> Run<'a> {
    fn new(start: Start) -> Self {
        Run {
            start,
            watch: Watch {
                out: None,
                quiet: false,
                checkpoints: true,
                limit: None,
                stop: StopSignal::process(),
                comm: Arc::new(Comm::single()),
                observer: None,
            },
        }
    }

    /// A run of `scene` from its start. Without [`Run::into_dir`] it writes nothing.
    pub fn scene(scene: LoadedScene) -> Self {
        Run::new(Start::Scene(Box::new(scene)))
    }

    /// Continues the run whose directory `dir` holds its checkpoint, bit for bit as if it had
    /// not stopped, writing on into the same directory.
    pub fn resume(dir: impl Into<PathBuf>) -> Self {
        let dir = dir.into();
        Run::new(Start::Checkpoint(dir.clone())).into_dir(dir)
    }

    /// Writes the run's files into `out` (created if needed, and held while the run lasts):
    /// history.csv, snapshots, points.vtu, summary.json, the plots and checkpoints.
    pub fn into_dir(mut self, out: impl Into<PathBuf>) -> Self {
        self.watch.out = Some(out.into());
        self
    }

    /// Prints nothing (no start line, no progress).
    pub fn quiet(mut self, quiet: bool) -> Self {
        self.watch.quiet = quiet;
        self
    }

    /// Writes no checkpoint, neither at the scene's cadence nor when interrupted.
    pub fn without_checkpoints(mut self) -> Self {
        self.watch.checkpoints = false;
        self
    }

    /// Stops the run once a point has moved farther than the limit (a strength-reduction
    /// trial that fails).
    pub fn displacement_limit(mut self, limit: DisplacementLimit) -> Self {
        self.watch.limit = Some(limit);
        self
    }

    /// The signal that interrupts the run (by default the process's: Ctrl-C, SIGTERM).
    pub fn stop_signal(mut self, stop: StopSignal) -> Self {
        self.watch.stop = stop;
        self
    }

    /// Splits the run over the ranks of `comm` (one rank: as without).
    pub fn over(mut self, comm: Arc<Comm>) -> Self {
        self.watch.comm = comm;
        self
    }

    /// Calls `observe` with the solver state after every step.
    pub fn observe(mut self, observe: impl FnMut(&SolverState) + Send + 'a) -> Self {
        self.watch.observer = Some(Box::new(observe));
        self
    }

    /// Builds the simulation and steps it to its stop.
    pub fn go(self) -> Result<RunReport, RunError> {
        let Run { start, watch } = self;
        match start {
            Start::Scene(loaded) => {
                if watch.comm.size() > 1 {
                    let (mut sim, derived) = build_part(&loaded, Some(watch.part()))?;
                    return with_simulation!(&mut sim, s => ranks::go(s, &loaded, watch, derived.points, None));
                }
                let (mut sim, _) = build(&loaded)?;
                let dir = watch.out.as_deref().map(claim).transpose()?;
                if let Some(dir) = &dir {
                    // A checkpoint left by an earlier run belongs to that run: resuming it
                    // would cut this run's history.csv at the old length and continue
                    // another problem.
                    checkpoint::parts::remove_earlier(dir.path()).map_err(|e| {
                        RunError::OutputDir(format!("cannot remove the earlier run's checkpoint: {e}"))
                    })?;
                }
                let header = checkpoint::Header {
                    scene_path: loaded.path.clone(),
                    scene_text: loaded.text.clone(),
                    meshes_crc: loaded.mesh_crc(),
                    ..checkpoint::Header::default()
                };
                with_simulation!(&mut sim, s => watch.drive(s, &loaded, dir.as_ref(), None, header))
            }
            Start::Checkpoint(dir) if watch.comm.size() > 1 => {
                let comm = watch.comm.clone();
                // Every rank reads the manifest and its own part; one that cannot, stops all.
                let read = checkpoint::parts::read(&dir, comm.rank(), comm.size());
                if let Some((rank, e)) = comm.first_error(&read) {
                    return Err(RunError::Ranks(format!("rank {rank}: {e}")));
                }
                let (manifest, part, file) = read.expect("read above");
                let header = &manifest.header;
                let loaded = LoadedScene::from_text(&header.scene_path, &header.scene_text, &[])?;
                check_meshes(&loaded, header, &dir.join(checkpoint::FILE_NAME))?;
                let (mut sim, derived) = build_part(&loaded, Some(watch.part()))?;
                let resume = ranks::Resume {
                    manifest: &manifest,
                    part: &part,
                    file: &file,
                };
                with_simulation!(&mut sim, s => ranks::go(s, &loaded, watch, derived.points, Some(resume)))
            }
            Start::Checkpoint(dir) => {
                let file = dir.join(checkpoint::FILE_NAME);
                let bytes = std::fs::read(&file).map_err(|source| CheckpointError::Io {
                    path: file.clone(),
                    source,
                })?;
                let header = checkpoint::header(&bytes, &file)?;
                let loaded = LoadedScene::from_text(&header.scene_path, &header.scene_text, &[])?;
                check_meshes(&loaded, &header, &file)?;
                let (mut sim, _) = build(&loaded)?;
                let dir = claim(&dir)?;
                with_simulation!(&mut sim, s => {
                    checkpoint::restore(s, &bytes, &file)?;
                    let mark = Some((header.history_bytes, header.history_crc));
                    watch.drive(s, &loaded, Some(&dir), mark, header)
                })
            }
        }
    }
}

impl Watch<'_> {
    /// This process's part of a run over the ranks of its communicator.
    fn part(&self) -> RankPart {
        RankPart {
            ranks: self.comm.size(),
            rank: self.comm.rank(),
            split: self.comm.layout(),
        }
    }

    /// Steps `sim` to its end with the hooks, writing into `dir` when there is one. `header`
    /// carries the scene and, for a resumed run, the wall time before and the history's
    /// mark (`history`).
    fn drive<D: Dim>(
        self,
        sim: &mut Simulation<D>,
        loaded: &LoadedScene,
        dir: Option<&OutputDir>,
        history: Option<(u64, u32)>,
        header: checkpoint::Header,
    ) -> Result<RunReport, RunError> {
        let scene = header.scene_path.display().to_string();
        let output = &loaded.scene.output;
        let recorder = dir
            .map(|d| {
                Recorder::attach(sim, d, output.history_every, output.snapshots, history).map_err(|e| {
                    RunError::OutputDir(format!("cannot write into {}: {e}", d.path().display()))
                })
            })
            .transpose()?;
        if !self.quiet {
            eprintln!(
                "{scene}: {} points, {}, Δt = {:.4e} s{}",
                sim.point_count(),
                if D::AXISYMMETRIC {
                    "axisymmetric (per radian)".to_string()
                } else {
                    format!("{}D", D::N)
                },
                sim.ctx.numerics.dt,
                if sim.ctx.state.clock.step > 0 {
                    format!(", resumed at step {}", sim.ctx.state.clock.step)
                } else {
                    String::new()
                }
            );
        }
        let before = header.wall_seconds;
        let start = Instant::now();
        let mut hooks: Vec<Box<dyn Hook<D> + Send + '_>> = Vec::new();
        if let Some(observe) = self.observer {
            hooks.push(Box::new(Observer(observe)));
        }
        hooks.push(Box::new(ShowProgress(Progress::new(
            self.quiet,
            loaded.scene.solver.tolerance,
            sim.ctx.state.clock.step,
        ))));
        hooks.push(Box::new(StopOnRequest(self.stop)));
        if let (true, Some(dir), Some(recorder)) = (self.checkpoints, dir, &recorder) {
            hooks.push(Box::new(Checkpoints {
                dir: dir.path().to_path_buf(),
                every: loaded.scene.solver.checkpoint_every,
                header,
                rows: Some(recorder.rows().clone()),
                before,
                start,
                last: Instant::now(),
            }));
        }
        if let Some(limit) = self.limit {
            hooks.push(Box::new(limit));
        }
        let result = sim.run_with(|s| hooks.iter_mut().try_for_each(|h| h.after_step(s)));
        hooks.iter_mut().for_each(|h| h.finish());
        drop(hooks);
        let wall = before + start.elapsed().as_secs_f64();
        let error = result.err();
        let message = error.as_ref().map(|e| e.to_string());
        let checkpointed = dir.is_some_and(|d| d.file(checkpoint::FILE_NAME).exists());
        let (summary, notes) = match (recorder, dir) {
            (Some(recorder), Some(dir)) => {
                let (summary, notes) = recorder
                    .finish(sim, dir, &scene, (wall, checkpointed), message)
                    .map_err(|e| {
                        RunError::Results(format!(
                            "cannot write the results into {}: {e}",
                            dir.path().display()
                        ))
                    })?;
                (summary, notes.0)
            }
            _ => (Summary::collect(&scene, sim, wall, message), Vec::new()),
        };
        Ok(RunReport {
            summary,
            error,
            notes,
            dir: dir.map(|d| d.path().to_path_buf()),
        })
    }
}

/// A resumed run's scene reads the STL meshes it was started with (`file`: the checkpoint).
fn check_meshes(loaded: &LoadedScene, header: &checkpoint::Header, file: &Path) -> Result<(), RunError> {
    if loaded.mesh_crc() == header.meshes_crc {
        return Ok(());
    }
    Err(CheckpointError::Format {
        path: file.to_path_buf(),
        reason: "an STL mesh of the scene differs from the one the run was started with \
                 (replaced or moved since): put the file back, or start the run again"
            .into(),
    }
    .into())
}

/// Takes the output directory `path` for this run.
fn claim(path: &Path) -> Result<OutputDir, RunError> {
    OutputDir::claim(path).map_err(|e| RunError::OutputDir(e.to_string()))
}
