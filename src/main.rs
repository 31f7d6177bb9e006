//! The `kdmpm` command line: run or check a scene.
//!
//! The binary parses the command line and reports; the library runs: [`kdmpm::run::Run`]
//! for `run` and `resume`, [`kdmpm::fos`] and [`kdmpm::study`]. Bad input exits with 2, a
//! run that went wrong with 1, an interrupted one with 130.

use clap::{Parser, Subcommand};
use kdmpm::infra::comm::Comm;
use kdmpm::interrupt::INTERRUPTED_EXIT;
use kdmpm::output::{Outcome, OutputDir};
use kdmpm::run::{Run, RunError, RunReport};
use kdmpm::scene::{build, LoadedScene};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

/// Large blocks coloured, so that the columns a kernel uses together never share their
/// offset in a page (see `kdmpm::infra::alloc`).
#[global_allocator]
static ALLOCATOR: kdmpm::infra::alloc::Coloured = kdmpm::infra::alloc::Coloured;

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

/// Threads and terminal output, for every command that runs.
#[derive(clap::Args, Clone, Copy)]
struct Workers {
    /// Print nothing but errors.
    #[arg(long, short)]
    quiet: bool,
    /// Worker threads (default: all cores; a study gives each run this many). Results are
    /// identical for any count.
    #[arg(long)]
    threads: Option<std::num::NonZeroUsize>,
}

/// How a run steps and what it prints, for `run` and `resume` alike.
#[derive(clap::Args, Clone, Copy)]
struct Stepping {
    /// Print the per-system timing table at the end.
    #[arg(long)]
    profile: bool,
    #[command(flatten)]
    workers: Workers,
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
        #[command(flatten)]
        workers: Workers,
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
        #[command(flatten)]
        workers: Workers,
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
        Ok(c) => Arc::new(c),
        Err(e) => return fail(&e, BAD_INPUT),
    };
    if comm.size() > 1 && !matches!(cli.command, Command::Run { .. }) {
        let only = "only `kdmpm run` is split across ranks: start the other commands without mpirun";
        return match comm.is_root() {
            true => fail(
                &format!("kdmpm was started on {} ranks; {only}", comm.size()),
                BAD_INPUT,
            ),
            false => ExitCode::from(BAD_INPUT),
        };
    }
    // Over several ranks a signal is mpirun's to pass on (a checkpoint would be rank 0's
    // alone).
    if comm.size() == 1 {
        kdmpm::interrupt::catch_signals();
    }
    let (threads, trace) = match &cli.command {
        Command::Run { stepping, trace, .. } => (stepping.workers.threads, trace.clone()),
        Command::Resume { stepping, .. } => (stepping.workers.threads, None),
        Command::Fos { workers, .. } => (workers.threads, None),
        _ => (None, None),
    };
    // The trace's guard flushes the file when main returns.
    let _trace = match trace.map(kdmpm::infra::trace::start).transpose() {
        Ok(guard) => guard,
        Err(message) => return fail(&message, BAD_INPUT),
    };
    if let Some(n) = threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n.get())
            .build_global()
        {
            return fail(&format!("cannot start {n} threads: {e}"), BAD_INPUT);
        }
    }
    match cli.command {
        Command::Check { scene, overrides } => check(&scene, &overrides),
        Command::Plot { dir } => plot(&dir),
        Command::Study { study, out, workers } => run_study(&study, out, workers),
        Command::Fos {
            scene,
            out,
            overrides,
            workers,
        } => run_fos(&scene, out, &overrides, workers.quiet),
        Command::Resume { dir, stepping } => report(
            Run::resume(dir).quiet(stepping.workers.quiet).go(),
            stepping,
            &comm,
        ),
        Command::Run {
            scene,
            out,
            overrides,
            stepping,
            ..
        } => {
            let out = out.unwrap_or_else(|| default_out(&scene, "", "scene"));
            let run = LoadedScene::from_file(&scene, &overrides)
                .map_err(RunError::from)
                .and_then(|l| {
                    Run::scene(l)
                        .into_dir(out)
                        .quiet(stepping.workers.quiet)
                        .over(comm.clone())
                        .go()
                });
            report(run, stepping, &comm)
        }
    }
}

/// Prints `error: {message}` and returns `code`.
fn fail(message: &dyn std::fmt::Display, code: u8) -> ExitCode {
    eprintln!("error: {message}");
    ExitCode::from(code)
}

/// The output directory when none is given: `out/<prefix><file stem>` (`fallback` for a
/// path without a stem).
fn default_out(path: &Path, prefix: &str, fallback: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or(fallback.into(), |s| s.to_string_lossy().into_owned());
    Path::new("out").join(format!("{prefix}{stem}"))
}

/// `kdmpm check`: validates a scene and prints what it derives.
fn check(path: &Path, overrides: &[String]) -> ExitCode {
    match LoadedScene::from_file(path, overrides).and_then(|l| build(&l)) {
        Ok((_, derived)) => {
            print!("{}: valid\n{derived}", path.display());
            ExitCode::SUCCESS
        }
        Err(e) => fail(&e, BAD_INPUT),
    }
}

/// `kdmpm plot`: draws the plots of a run directory again.
fn plot(dir: &Path) -> ExitCode {
    match kdmpm::output::plots::draw(dir) {
        Ok((written, skipped)) => {
            written.iter().for_each(|w| println!("{}", dir.join(w).display()));
            skipped.iter().for_each(|s| eprintln!("  not drawn: {s}"));
            ExitCode::SUCCESS
        }
        Err(e) => fail(&format!("cannot plot {}: {e}", dir.display()), BAD_INPUT),
    }
}

/// Reports a run (`run`, `resume`) as the user asked: the profile, the error with what the
/// outputs left out, or the last line. Over several ranks, rank 0 reports bad input (every
/// rank finds the same) and the run, each other rank its own failure.
fn report(run: Result<RunReport, RunError>, stepping: Stepping, comm: &Comm) -> ExitCode {
    let rank = match comm.is_root() {
        true => String::new(),
        false => format!("rank {}: ", comm.rank()),
    };
    let r = match run {
        Err(e) if e.is_bad_input() && !comm.is_root() => return ExitCode::from(BAD_INPUT),
        Err(e) => {
            return fail(
                &format_args!("{rank}{e}"),
                if e.is_bad_input() { BAD_INPUT } else { RUN_FAILED },
            )
        }
        Ok(r) => r,
    };
    if stepping.profile && comm.is_root() {
        print!("{}", r.summary.profile_table());
    }
    if let Some(e) = &r.error {
        eprintln!("error: {rank}{e}");
        if comm.is_root() {
            r.notes.iter().for_each(|n| eprintln!("  {n}"));
        }
        return ExitCode::from(RUN_FAILED);
    }
    let interrupted = r.summary.outcome == Outcome::Interrupted;
    if comm.is_root() && (!stepping.workers.quiet || interrupted) {
        eprintln!("{}", r.describe());
    }
    ExitCode::from(if interrupted { INTERRUPTED_EXIT } else { 0 })
}

/// `kdmpm fos`: the strength-reduction analysis of a scene.
fn run_fos(path: &Path, out: Option<PathBuf>, overrides: &[String], quiet: bool) -> ExitCode {
    let loaded = match LoadedScene::from_file(path, overrides) {
        Ok(l) => l,
        Err(e) => return fail(&e, BAD_INPUT),
    };
    let out = out.unwrap_or_else(|| default_out(path, "fos-", "scene"));
    let show = |t: &kdmpm::fos::Trial| {
        if !quiet {
            eprintln!("{}", t.describe());
        }
    };
    match kdmpm::fos::strength_reduction(&loaded, &out, show) {
        Ok(r) => {
            println!("{} → {}", r.describe(), out.display());
            ExitCode::SUCCESS
        }
        Err(e @ kdmpm::fos::FosError::Interrupted(_)) => fail(&e, INTERRUPTED_EXIT),
        Err(e) => fail(&e, if e.is_bad_input() { BAD_INPUT } else { RUN_FAILED }),
    }
}

/// `kdmpm study`: plans and checks every run, then has the library conduct the study.
fn run_study(path: &Path, out: Option<PathBuf>, workers: Workers) -> ExitCode {
    use kdmpm::study::{self, Launch, Study, StudyError};
    let study = match Study::from_file(path) {
        Ok(s) => s,
        Err(e) => return fail(&e, BAD_INPUT),
    };
    let out = out.unwrap_or_else(|| default_out(path, "study-", "study"));
    let dir = match OutputDir::claim(&out) {
        Ok(d) => d,
        Err(e) => return fail(&e, BAD_INPUT),
    };
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(e) => {
            return fail(
                &format!("cannot find the kdmpm executable to launch runs: {e}"),
                RUN_FAILED,
            )
        }
    };
    let threads = workers.threads.map(|n| n.get());
    match study::conduct(&study, &dir, &Launch { exe, threads }, workers.quiet) {
        Ok(results) => {
            if !workers.quiet {
                println!("{}→ {}", results.describe(&study), dir.path().display());
            }
            ExitCode::SUCCESS
        }
        Err(e @ StudyError::Interrupted(_)) => fail(&e, INTERRUPTED_EXIT),
        Err(e) => fail(&e, RUN_FAILED),
    }
}
