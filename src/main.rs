//! The `kdmpm` command line: run or check a scene.

use clap::{Parser, Subcommand};
use kdmpm::checkpoint;
use kdmpm::comm::Comm;
use kdmpm::output::{Outcome, OutputDir, Progress, Recorder, Summary};
use kdmpm::scene::{build, CheckpointEvery, LoadedScene};
use kdmpm::state::StopReason;
use kdmpm::systems::convergence::ratio_text;
use kdmpm::{with_simulation, Dim, Simulation};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

/// Large blocks coloured, so that the columns a kernel uses together never share their
/// offset in a page (see `kdmpm::alloc`).
#[global_allocator]
static ALLOCATOR: kdmpm::alloc::Coloured = kdmpm::alloc::Coloured;

#[derive(Parser)]
#[command(
    name = "kdmpm",
    version,
    about = "Static large-deformation MPM with kinetic damping"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// How a run steps and what it prints, for `run` and `resume` alike.
#[derive(clap::Args)]
struct Stepping {
    /// Print the per-system timing table at the end.
    #[arg(long)]
    profile: bool,
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// Worker threads (default: all cores). Results are identical for any count.
    #[arg(long)]
    threads: Option<std::num::NonZeroUsize>,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene to static equilibrium (or its step/time limit).
    Run {
        /// Scene file (RON).
        scene: PathBuf,
        /// Output directory (default: out/<scene file stem>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene field, e.g. --set solver.tolerance=1e-4 (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        overrides: Vec<String>,
        #[command(flatten)]
        stepping: Stepping,
        /// Write a Chrome trace (chrome://tracing, Perfetto) of every system call to FILE
        /// (needs a build with `--features trace`).
        #[arg(long, value_name = "FILE")]
        trace: Option<PathBuf>,
    },
    /// Continue a run from the checkpoint in its output directory (`checkpoint.kdc`, written
    /// by `solver.checkpoint_every` or Ctrl-C), bit for bit as if it had not stopped.
    Resume {
        /// The run's output directory.
        dir: PathBuf,
        #[command(flatten)]
        stepping: Stepping,
    },
    /// Run a speed–accuracy study: a scene over axes of settings, each run compared with an
    /// analytic value or a reference run; writes study.csv, pareto.svg (and convergence.csv
    /// over a refinement axis) and prints the Pareto front.
    Study {
        /// Study file (RON; see docs/studies.md).
        study: PathBuf,
        /// Output directory (default: out/study-<study file stem>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads of each run (default: all cores).
        #[arg(long)]
        threads: Option<std::num::NonZeroUsize>,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Factor of safety by strength reduction: solve the scene with c and tan φ divided by
    /// trial factors, bisecting between the largest that stands and the smallest that fails
    /// (the scene's `strength_reduction` field); writes summary.json, fos.csv, fos.svg and
    /// each trial under trials/.
    Fos {
        /// Scene file (RON) with a `strength_reduction` field.
        scene: PathBuf,
        /// Output directory (default: out/fos-<scene file stem>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene field (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        overrides: Vec<String>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<std::num::NonZeroUsize>,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
    },
    /// Draw (again) the plots of a run from its output directory, finished or running:
    /// kinetic energy, K_F and K_E, traced displacements, displacement field (SVG).
    Plot {
        /// The run's output directory.
        dir: PathBuf,
    },
    /// Parse and validate a scene without running it; print the derived figures.
    Check {
        /// Scene file (RON).
        scene: PathBuf,
        /// Override a scene field (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        overrides: Vec<String>,
    },
}

/// Exit code for a scene or output directory that cannot be used.
const BAD_INPUT: u8 = 2;
/// Exit code for a run stopped by an error while stepping.
const RUN_FAILED: u8 = 1;

fn main() -> ExitCode {
    let cli = Cli::parse();
    // MPI starts before any thread pool; without `mpirun` (or the `mpi` feature) this is
    // one rank.
    let comm = match Comm::world() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(BAD_INPUT);
        }
    };
    let comm = Arc::new(comm);
    if comm.size() > 1 && !matches!(cli.command, Command::Run { .. }) {
        if comm.is_root() {
            eprintln!(
                "error: kdmpm was started on {} ranks; only `kdmpm run` is split across ranks: \
                 start the other commands without mpirun",
                comm.size()
            );
        }
        return ExitCode::from(BAD_INPUT);
    }
    match cli.command {
        Command::Check { scene, overrides } => check(&scene, &overrides),
        Command::Plot { dir } => match kdmpm::output::plots::draw(&dir) {
            Ok((written, skipped)) => {
                for w in written {
                    println!("{}", dir.join(w).display());
                }
                for s in skipped {
                    eprintln!("  not drawn: {s}");
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: cannot plot {}: {e}", dir.display());
                ExitCode::from(BAD_INPUT)
            }
        },
        Command::Study {
            study,
            out,
            threads,
            quiet,
        } => run_study(&study, out, threads, quiet),
        Command::Fos {
            scene,
            out,
            overrides,
            threads,
            quiet,
        } => match start_threads(threads) {
            Ok(()) => run_fos(&scene, out, &overrides, quiet),
            Err(code) => code,
        },
        Command::Resume { dir, stepping } => match start_threads(stepping.threads) {
            Ok(()) => resume(&dir, stepping.profile, stepping.quiet),
            Err(code) => code,
        },
        Command::Run {
            scene,
            out,
            overrides,
            stepping,
            trace,
        } => {
            let _trace = match trace.map(start_trace).transpose() {
                Ok(guard) => guard,
                Err(message) => {
                    eprintln!("error: {message}");
                    return ExitCode::from(BAD_INPUT);
                }
            };
            match start_threads(stepping.threads) {
                Ok(()) => run(&scene, out, &overrides, stepping.profile, stepping.quiet, comm),
                Err(code) => code,
            }
        }
    }
}

/// The output directory when none is given: `out/<prefix><file stem>` (`fallback` for a
/// path without a stem).
fn default_out(path: &Path, prefix: &str, fallback: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or(fallback.into(), |s| s.to_string_lossy().into_owned());
    Path::new("out").join(format!("{prefix}{stem}"))
}

/// Sizes the global thread pool when `--threads` is given.
fn start_threads(threads: Option<std::num::NonZeroUsize>) -> Result<(), ExitCode> {
    if let Some(n) = threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n.get())
            .build_global()
        {
            eprintln!("error: cannot start {n} threads: {e}");
            return Err(ExitCode::from(BAD_INPUT));
        }
    }
    Ok(())
}

/// Starts the Chrome-trace writer; the returned guard flushes the file when dropped.
#[cfg(feature = "trace")]
fn start_trace(path: PathBuf) -> Result<Box<dyn std::any::Any>, String> {
    use tracing_subscriber::prelude::*;
    let (layer, guard) = tracing_chrome::ChromeLayerBuilder::new()
        .file(path)
        .include_args(true)
        .build();
    tracing_subscriber::registry()
        .with(layer)
        .try_init()
        .map_err(|e| e.to_string())?;
    Ok(Box::new(guard))
}

#[cfg(not(feature = "trace"))]
fn start_trace(_path: PathBuf) -> Result<Box<dyn std::any::Any>, String> {
    Err(
        "--trace needs kdmpm built with the `trace` feature: cargo run --release --features trace -- run ..."
            .into(),
    )
}

fn check(path: &Path, overrides: &[String]) -> ExitCode {
    let built = LoadedScene::from_file(path, overrides).and_then(|l| build(&l));
    match built {
        Ok((_, d)) => {
            println!("{}: valid", path.display());
            println!("  points                {}", d.points);
            println!("  active nodes          {} of {}", d.active_nodes, d.grid_nodes);
            println!("  P-wave speed          {:.6} m/s", d.p_wave_speed);
            println!("  critical time step    {:.6e} s", d.critical_time_step);
            println!(
                "  time step             {:.6e} s (Courant {:.3})",
                d.time_step,
                d.time_step / d.critical_time_step
            );
            println!(
                "  memory (bound)        {:.1} MB ({} points, {} nodes at most)",
                d.estimate.bytes as f64 / 1e6,
                d.estimate.points,
                d.estimate.nodes
            );
            println!("  systems               {}", d.systems.join(" → "));
            if !d.unused_materials.is_empty() {
                println!(
                    "  unused materials      {} (no body uses them; they do not set the time step)",
                    d.unused_materials.join(", ")
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(BAD_INPUT)
        }
    }
}

fn run(
    path: &Path,
    out: Option<PathBuf>,
    overrides: &[String],
    profile: bool,
    quiet: bool,
    comm: Arc<Comm>,
) -> ExitCode {
    let (loaded, mut sim) =
        match LoadedScene::from_file(path, overrides).and_then(|l| build(&l).map(|(s, _)| (l, s))) {
            Ok(v) => v,
            Err(e) => {
                // Every rank finds the same error; one reports it.
                if comm.is_root() {
                    eprintln!("error: {e}");
                }
                return ExitCode::from(BAD_INPUT);
            }
        };
    let out = out.unwrap_or_else(|| default_out(path, "", "scene"));
    if comm.size() > 1 {
        let options = Options {
            profile,
            quiet,
            ranks: comm.size(),
        };
        return with_simulation!(&mut sim, s => run_ranks(s, &loaded, path, &out, options, comm));
    }
    let dir = match OutputDir::claim(&out) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(BAD_INPUT);
        }
    };
    // A checkpoint left by an earlier run belongs to that run: resuming it would cut this
    // run's history.csv at the old length and continue another problem.
    match std::fs::remove_file(dir.file(checkpoint::FILE_NAME)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            eprintln!("error: cannot remove the earlier run's checkpoint: {e}");
            return ExitCode::from(BAD_INPUT);
        }
        _ => {}
    }
    let header = checkpoint::Header {
        scene_path: path.to_path_buf(),
        scene_text: loaded.text.clone(),
        ..checkpoint::Header::default()
    };
    let options = Options {
        profile,
        quiet,
        ranks: 1,
    };
    with_simulation!(&mut sim, s => drive(s, &loaded, &dir, None, header, options))
}

/// `kdmpm run` over MPI ranks: each rank steps its part of the scene; rank 0 writes
/// history.csv, summary.json (the ranks' figures) and points.pvtu, every rank its own
/// `points_<rank>.vtu`.
fn run_ranks<D: Dim>(
    sim: &mut Simulation<D>,
    loaded: &LoadedScene,
    path: &Path,
    out: &Path,
    options: Options,
    comm: Arc<Comm>,
) -> ExitCode {
    let refuse = |what: String| {
        if comm.is_root() {
            eprintln!("error: {}: {what}", path.display());
        }
        ExitCode::from(BAD_INPUT)
    };
    if loaded.scene.solver.checkpoint_every.is_some() || loaded.scene.output.snapshots.is_some() {
        return refuse(format!(
            "a run over {} ranks does not yet write checkpoints or snapshots: remove \
             solver.checkpoint_every and output.snapshots, or run on one rank",
            comm.size()
        ));
    }
    if let Err(e) = kdmpm::distributed::decompose(sim, comm.clone()) {
        return refuse(e);
    }
    // Every rank gathers the traced points for rank 0's history, before it is written.
    let gather = kdmpm::output::TracedGather::new(&sim.traced);
    sim.schedule.push(gather);
    let dir = if comm.is_root() {
        match OutputDir::claim(out) {
            Ok(d) => Some(d),
            Err(e) => {
                eprintln!("error: {e}");
                None
            }
        }
    } else {
        None
    };
    // Whether rank 0 holds the directory: the others write into it.
    if comm.any(comm.is_root() && dir.is_none()) {
        return ExitCode::from(BAD_INPUT);
    }
    if let Some(dir) = dir {
        let header = checkpoint::Header {
            scene_path: path.to_path_buf(),
            scene_text: loaded.text.clone(),
            ..checkpoint::Header::default()
        };
        return drive(sim, loaded, &dir, None, header, options);
    }
    let start = Instant::now();
    let result = sim.run(|_| {});
    // A state with a non-finite value comes with the run's error, reported below.
    let written = kdmpm::output::recorder::write_final_points(sim, out);
    // The summary's figures are collectives: this rank takes part, rank 0 writes them.
    let error = result.as_ref().err().map(|e| e.to_string());
    let _ = Summary::collect(
        &path.display().to_string(),
        sim,
        start.elapsed().as_secs_f64(),
        error,
    );
    match (result, written) {
        (Ok(()), Ok(_)) => ExitCode::SUCCESS,
        (Err(e), _) => {
            eprintln!("error: rank {}: {e}", comm.rank());
            ExitCode::from(RUN_FAILED)
        }
        (_, Err(e)) => {
            eprintln!(
                "error: rank {}: cannot write its points into {}: {e}",
                comm.rank(),
                out.display()
            );
            ExitCode::from(RUN_FAILED)
        }
    }
}

/// Continues the run whose checkpoint is in `dir`.
fn resume(dir_path: &Path, profile: bool, quiet: bool) -> ExitCode {
    let file = dir_path.join(checkpoint::FILE_NAME);
    let bytes = match std::fs::read(&file) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: cannot read checkpoint {}: {e}", file.display());
            return ExitCode::from(BAD_INPUT);
        }
    };
    let fail = |e: &dyn std::fmt::Display| {
        eprintln!("error: {e}");
        ExitCode::from(BAD_INPUT)
    };
    let header = match checkpoint::header(&bytes, &file) {
        Ok(h) => h,
        Err(e) => return fail(&e),
    };
    let built = LoadedScene::from_text(&header.scene_path, &header.scene_text, &[])
        .and_then(|l| build(&l).map(|(s, _)| (l, s)));
    let (loaded, mut sim) = match built {
        Ok(v) => v,
        Err(e) => return fail(&e),
    };
    let dir = match OutputDir::claim(dir_path) {
        Ok(d) => d,
        Err(e) => return fail(&e),
    };
    let options = Options {
        profile,
        quiet,
        ranks: 1,
    };
    with_simulation!(&mut sim, s => {
        if let Err(e) = checkpoint::restore(s, &bytes, &file) {
            return fail(&e);
        }
        let mark = Some((header.history_bytes, header.history_crc));
        drive(s, &loaded, &dir, mark, header, options)
    })
}

/// What the user asked of the terminal output.
#[derive(Clone, Copy)]
struct Options {
    profile: bool,
    quiet: bool,
    /// Ranks of the run: with more than one, Ctrl-C is left to mpirun (a checkpoint would
    /// be rank 0's alone).
    ranks: usize,
}

/// Exit code of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
const INTERRUPTED_EXIT: u8 = 130;

/// Steps `sim` to its end, writing history, checkpoints, points.vtu and summary.json into
/// `dir`. `header` carries the scene and, for a resumed run, the wall time before.
fn drive<D: Dim>(
    sim: &mut Simulation<D>,
    loaded: &LoadedScene,
    dir: &OutputDir,
    history: Option<(u64, u32)>,
    mut header: checkpoint::Header,
    options: Options,
) -> ExitCode {
    let scene = &header.scene_path.clone();
    let output = &loaded.scene.output;
    let recorder = match Recorder::attach(sim, dir, output.history_every, output.snapshots, history) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot write into {}: {e}", dir.path().display());
            return ExitCode::from(BAD_INPUT);
        }
    };
    let rows = recorder.rows().clone();
    // A second Ctrl-C while the first is being honoured ends the process at once; every
    // file is written whole or not at all, so nothing torn is left.
    if options.ranks == 1 {
        let _ = ctrlc::set_handler(|| {
            if kdmpm::interrupt::request() {
                std::process::exit(INTERRUPTED_EXIT.into());
            }
        });
    }
    if !options.quiet {
        eprintln!(
            "{}: {} points, {}D, Δt = {:.4e} s{}",
            scene.display(),
            sim.point_count(),
            D::N,
            sim.ctx.settings.dt,
            if sim.ctx.state.clock.step > 0 {
                format!(", resumed at step {}", sim.ctx.state.clock.step)
            } else {
                String::new()
            }
        );
    }
    let before = header.wall_seconds;
    let start = Instant::now();
    let mut progress = Progress::new(
        options.quiet,
        loaded.scene.solver.tolerance,
        sim.ctx.state.clock.step,
    );
    let mut last_checkpoint = Instant::now();
    let every = loaded.scene.solver.checkpoint_every;
    let save = |sim: &Simulation<D>, header: &mut checkpoint::Header| -> std::io::Result<()> {
        let mut rows = kdmpm::output::history::lock(&rows);
        rows.flush()?;
        header.history_bytes = rows.committed();
        header.history_crc = rows.committed_crc();
        header.wall_seconds = before + start.elapsed().as_secs_f64();
        let bytes = checkpoint::encode(sim, header);
        dir.write_atomic(checkpoint::FILE_NAME, |out| out.write_all(&bytes))
    };
    let result = sim.run_with(|s| {
        let st = &s.ctx.state;
        progress.update(st);
        let interrupted = kdmpm::interrupt::requested();
        let due = st.stop.is_none()
            && match every {
                Some(CheckpointEvery::Steps(n)) => st.clock.step.is_multiple_of(n),
                Some(CheckpointEvery::Seconds(t)) => last_checkpoint.elapsed().as_secs_f64() >= t,
                None => false,
            };
        if interrupted || due {
            last_checkpoint = Instant::now();
            save(s, &mut header)?;
        }
        if interrupted && s.ctx.state.stop.is_none() {
            s.ctx.state.stop = Some(StopReason::Interrupted);
        }
        Ok(())
    });
    progress.finish();
    let wall = before + start.elapsed().as_secs_f64();
    let error = result.as_ref().err().map(|e| e.to_string());
    let (summary, notes) = match recorder.finish(sim, dir, &scene.display().to_string(), wall, error) {
        Ok(v) => v,
        Err(e) => {
            eprintln!(
                "error: cannot write the results into {}: {e}",
                dir.path().display()
            );
            return ExitCode::from(RUN_FAILED);
        }
    };
    if options.profile {
        print_profile(&summary);
    }
    if let Err(e) = result {
        eprintln!("error: {e}");
        for n in notes.0 {
            eprintln!("  {n}");
        }
        return ExitCode::from(RUN_FAILED);
    }
    let interrupted = summary.outcome == Outcome::Interrupted;
    if !options.quiet || interrupted {
        eprintln!(
            "{} after {} steps, t = {:.4} s: K_F = {} (max) / {} (mean), K_E = {}, {} resets, {:.2} s wall → {}",
            match summary.outcome {
                Outcome::Converged => "converged",
                Outcome::Interrupted => "interrupted (kdmpm resume continues it)",
                _ => "stopped at its limit",
            },
            summary.steps,
            summary.time,
            ratio_text(summary.force_ratio_max, 3),
            ratio_text(summary.force_ratio_mean, 3),
            ratio_text(summary.energy_ratio, 3),
            summary.kinetic_resets,
            wall,
            dir.path().display()
        );
    }
    if interrupted {
        return ExitCode::from(INTERRUPTED_EXIT);
    }
    ExitCode::SUCCESS
}

/// `kdmpm fos`: the strength-reduction analysis of a scene.
fn run_fos(path: &Path, out: Option<PathBuf>, overrides: &[String], quiet: bool) -> ExitCode {
    let loaded = match LoadedScene::from_file(path, overrides) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(BAD_INPUT);
        }
    };
    let out = out.unwrap_or_else(|| default_out(path, "fos-", "scene"));
    // Ctrl-C or SIGTERM ends the trial under way at its next step, then the analysis.
    let _ = ctrlc::set_handler(|| {
        kdmpm::interrupt::request();
    });
    let result = kdmpm::fos::strength_reduction(&loaded, &out, |t| {
        if !quiet {
            eprintln!(
                "F = {:.4}: {} ({}), largest displacement {:.3e} m, {} steps, {:.1} s",
                t.factor,
                if t.failed { "fails" } else { "stands" },
                t.outcome.name(),
                t.max_displacement,
                t.steps,
                t.wall_seconds
            );
        }
    });
    match result {
        Ok(r) => {
            println!(
                "factor of safety {:.3} (stands at {:.4}, fails at {:.4}), {} trials, {:.1} s → {}",
                r.factor_of_safety,
                r.bracket[0],
                r.bracket[1],
                r.trials.len(),
                r.wall_seconds,
                out.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(match e {
                kdmpm::fos::FosError::Scene(_)
                | kdmpm::fos::FosError::NotAnAnalysis(_)
                | kdmpm::fos::FosError::OutputDir(_) => BAD_INPUT,
                kdmpm::fos::FosError::Interrupted(_) => INTERRUPTED_EXIT,
                _ => RUN_FAILED,
            })
        }
    }
}

fn print_profile(summary: &Summary) {
    let total: f64 = summary.systems.iter().map(|t| t.seconds).sum();
    println!(
        "{:<18} {:>10} {:>12} {:>12} {:>7}",
        "system", "calls", "total (s)", "mean (µs)", "share"
    );
    for t in &summary.systems {
        let mean = if t.calls > 0 {
            1e6 * t.seconds / t.calls as f64
        } else {
            0.0
        };
        let share = if total > 0.0 {
            100.0 * t.seconds / total
        } else {
            0.0
        };
        println!(
            "{:<18} {:>10} {:>12.4} {:>12.2} {:>6.1}%",
            t.name, t.calls, t.seconds, mean, share
        );
    }
}

/// `kdmpm study`: plans and checks every run, runs the reference then the rest (skipping
/// those an earlier invocation completed), and writes the study's table and picture.
fn run_study(
    path: &Path,
    out: Option<PathBuf>,
    threads: Option<std::num::NonZeroUsize>,
    quiet: bool,
) -> ExitCode {
    use kdmpm::study::{self, Launch, Study};
    let study = match Study::from_file(path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(BAD_INPUT);
        }
    };
    let out = out.unwrap_or_else(|| default_out(path, "study-", "study"));
    let dir = match OutputDir::claim(&out) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(BAD_INPUT);
        }
    };
    let exe = match std::env::current_exe() {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: cannot find the kdmpm executable to launch runs: {e}");
            return ExitCode::from(RUN_FAILED);
        }
    };
    let launch = Launch {
        exe,
        threads: threads.map(|n| n.get()),
    };
    let total = study.runs.len() + usize::from(study.reference.is_some());
    let progress = StudyProgress::new(total as u64, quiet);
    let mut run = |planned: &study::Planned| {
        progress.start(planned);
        let r = study::run_one(&study, planned, &dir, &launch);
        if let Ok(f) = &r {
            progress.finish(f);
        }
        r
    };
    // Ctrl-C or SIGTERM: the run under way gets the signal and is waited for.
    let _ = ctrlc::set_handler(|| {
        kdmpm::interrupt::request();
    });
    let failed = |e: study::StudyError| {
        progress.done();
        eprintln!("error: {e}");
        ExitCode::from(match e {
            study::StudyError::Interrupted(_) => INTERRUPTED_EXIT,
            _ => RUN_FAILED,
        })
    };
    let reference = match study.reference.as_ref().map(&mut run).transpose() {
        Ok(r) => r,
        Err(e) => return failed(e),
    };
    if let Some(r) = &reference {
        if let Err(e) = study::check_reference(r) {
            return failed(e);
        }
    }
    let mut finished = Vec::with_capacity(study.runs.len());
    for planned in &study.runs {
        match run(planned) {
            Ok(f) => finished.push(f),
            Err(e) => return failed(e),
        }
    }
    progress.done();
    match study::write_results(&study, &dir, reference.as_ref(), &finished) {
        Ok(study::Results { rows, front, orders }) => {
            if !quiet {
                print!("{}", study::front_table(&study, &rows, &front));
                if !orders.is_empty() {
                    print!("{}", study::orders_table(&orders));
                }
                println!("→ {}", dir.path().display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(RUN_FAILED)
        }
    }
}

/// Progress over a study's runs: a bar on a terminal, a line a run otherwise, nothing
/// with `--quiet`.
struct StudyProgress {
    bar: Option<indicatif::ProgressBar>,
    lines: bool,
    total: u64,
    done: std::cell::Cell<u64>,
}

impl StudyProgress {
    fn new(total: u64, quiet: bool) -> Self {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left  {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        StudyProgress {
            bar,
            lines: !quiet && !terminal,
            total,
            done: std::cell::Cell::new(0),
        }
    }

    fn start(&self, run: &kdmpm::study::Planned) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{} {}", run.id, run.values.join(", ")));
        }
    }

    fn finish(&self, f: &kdmpm::study::Finished) {
        self.done.set(self.done.get() + 1);
        let text = format!(
            "{} [{}] {}: {} in {:.1} s{}",
            f.run.id,
            if f.run.values.is_empty() {
                "reference".into()
            } else {
                f.run.values.join(", ")
            },
            self.done.get(),
            f.outcome,
            f.wall_seconds,
            if f.reused {
                " (from an earlier invocation)"
            } else {
                ""
            }
        );
        if let Some(bar) = &self.bar {
            bar.println(text);
            bar.inc(1);
        } else if self.lines {
            eprintln!("run {}/{}: {text}", self.done.get(), self.total);
        }
    }

    fn done(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
