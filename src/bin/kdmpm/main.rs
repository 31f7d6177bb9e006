//! The `kdmpm` command line: run or check a scene.
//!
//! The binary parses the command line (`cli.rs`) and reports; the library runs:
//! [`kdmpm::run::Run`] for `run` and `resume`, [`kdmpm::fos`], [`kdmpm::refine`] and
//! [`kdmpm::study`]. Bad input exits with 2, a run that went wrong with 1, an interrupted
//! one with 130.

use clap::Parser;
use cli::{Cli, Command, Stepping, Workers};
use kdmpm::infra::comm::Comm;
use kdmpm::output::{Outcome, OutputDir};
use kdmpm::run::{Run, RunError, RunReport};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::Ending;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

/// Large blocks coloured, so that the columns a kernel uses together never share their
/// offset in a page (see `kdmpm::infra::alloc`).
#[global_allocator]
static ALLOCATOR: kdmpm::infra::alloc::Coloured = kdmpm::infra::alloc::Coloured;

mod cli;

fn main() -> ExitCode {
    // Writing to a closed pipe (`kdmpm check scene.ron | head -3`) ends the process quietly,
    // as it ends other command-line tools, instead of panicking in `println!`. Rust starts a
    // program with SIGPIPE ignored; this puts back the default.
    // SAFETY: `signal` only sets the process's disposition of SIGPIPE; it runs first, before
    // any thread is started, and replaces no handler of ours.
    #[cfg(unix)]
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    // MPI starts before any thread pool; without `mpirun` (or the `mpi` feature) this is
    // one rank. A study starts no MPI of its own: its runs are processes it launches (over
    // ranks through `--launcher`), and a child of an MPI process would inherit its MPI.
    let comm = match &cli.command {
        Command::Study { .. } => match Comm::launched() {
            // Every process is refused alike; the first says why.
            Some(_) if Comm::launched_rank() != Some(0) => return ExitCode::from(Ending::BadInput.code()),
            Some(n) => {
                return Fault::bad(format!(
                    "kdmpm study was started as one of {n} MPI processes: start it without \
                     mpirun and it launches each run over the ranks, `kdmpm study STUDY \
                     --launcher \"mpirun -n {n}\"` (in a Slurm job, \"srun -n {n}\")"
                ))
                .report()
            }
            None => Ok(Comm::single()),
        },
        _ => Comm::world(),
    };
    // The ranks' layout over the grid, when asked.
    let layout = match &cli.command {
        Command::Run { layout, .. } | Command::Fos { layout, .. } => layout.split,
        _ => None,
    };
    let comm = comm.and_then(|c| match layout {
        Some(l) => c.with_layout(l),
        None => Ok(c),
    });
    let comm = match comm {
        Ok(c) => Arc::new(c),
        Err(e) => return Fault::bad(e).report(),
    };
    match command(cli.command, &comm) {
        Ok(code) => code,
        // Over several ranks, bad input is alike on every rank: rank 0 prints it.
        Err(f) if f.1 == Ending::BadInput && !comm.is_root() => ExitCode::from(f.1.code()),
        Err(f) => f.report(),
    }
}

/// `kdmpm triaxial`: the element test of a scene's material, written to triaxial.csv.
fn triaxial(args: cli::TriaxialArgs) -> Result<(), Fault> {
    let cli::TriaxialArgs {
        scene,
        material,
        cell_pressure,
        undrained,
        axial_strain,
        steps,
        out,
        overrides,
    } = args;
    let loaded = LoadedScene::from_file(&scene, &overrides).map_err(Fault::bad)?;
    let Some(spec) = loaded.scene.materials.get(&material) else {
        let names: Vec<&String> = loaded.scene.materials.keys().collect();
        return Err(Fault::bad(format!(
            "{}: no material \"{material}\" (the scene has {names:?})",
            scene.display()
        )));
    };
    let at = |f: &str| format!("materials.{material}.{f}");
    let model = spec
        .model(&at)
        .map_err(|r| Fault::bad(loaded.invalid(&r.field, r.rule)))?;
    let drainage = if undrained {
        kdmpm::element_test::Drainage::Undrained
    } else {
        kdmpm::element_test::Drainage::Drained
    };
    let test = kdmpm::element_test::Triaxial {
        cell_pressure,
        drainage,
        axial_strain,
        steps,
    };
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(format!("triaxial-{material}")));
    let path = out.join("triaxial.csv");
    let rows = kdmpm::element_test::triaxial(&model, &test).map_err(|e| match e {
        kdmpm::element_test::ElementError::Input(..) => Fault::bad(e),
        // A test that stopped leaves no earlier test's rows looking like its own.
        _ => match std::fs::remove_file(&path) {
            Err(r) if r.kind() != std::io::ErrorKind::NotFound => Fault(
                format!(
                    "{e}; {} of an earlier test could not be removed: {r}",
                    path.display()
                ),
                Ending::Failed,
            ),
            _ => Fault(e.to_string(), Ending::Failed),
        },
    })?;
    std::fs::create_dir_all(&out)
        .and_then(|_| kdmpm::element_test::write_csv(&rows, &path))
        .map_err(|e| Fault(format!("cannot write {}: {e}", path.display()), Ending::Failed))?;
    let last = rows.last().expect("the start is a row");
    println!(
        "{}: ε_a {:.4}, ε_v {:.4}, p′ {:.1} kPa, q {:.1} kPa, u {:.1} kPa",
        path.display(),
        last.axial_strain,
        last.volumetric_strain,
        last.mean_stress / 1e3,
        last.deviator / 1e3,
        last.pore_pressure / 1e3
    );
    for (name, v) in &last.state {
        println!("  {name} {v:.6e}");
    }
    Ok(())
}

/// An error message and how the command ends with it.
struct Fault(String, Ending);

impl Fault {
    /// Input that cannot be used.
    fn bad(e: impl std::fmt::Display) -> Fault {
        Fault(e.to_string(), Ending::BadInput)
    }

    /// Prints `error: {message}` and ends.
    fn report(self) -> ExitCode {
        eprintln!("error: {}", self.0);
        ExitCode::from(self.1.code())
    }
}

/// Sets up the process for the command (signals, trace, threads) and runs it.
fn command(command: Command, comm: &Arc<Comm>) -> Result<ExitCode, Fault> {
    if comm.size() > 1
        && !matches!(
            command,
            Command::Run { .. } | Command::Resume { .. } | Command::Fos { .. }
        )
    {
        return Err(Fault::bad(format!(
            "kdmpm was started on {} ranks; only `kdmpm run`, `kdmpm resume` and `kdmpm fos` \
             are split across ranks: start the other commands without mpirun",
            comm.size()
        )));
    }
    // Over several ranks each rank catches the signal the launcher passes on (mpirun: SIGTERM
    // before it kills the job, SIGUSR1 as it is; Slurm: SIGTERM at the time limit), and the
    // ranks stop together after the same step.
    kdmpm::catch_signals();
    let (threads, trace) = match &command {
        Command::Run { stepping, trace, .. } => (stepping.workers.threads, trace.clone()),
        Command::Resume { stepping, .. } => (stepping.workers.threads, None),
        Command::Fos { workers, .. } => (workers.threads, None),
        Command::Study { workers, .. } => {
            check_threads(workers.threads)?;
            (None, None)
        }
        _ => (None, None),
    };
    check_threads(threads)?;
    // The trace's guard flushes the file when the command returns.
    let _trace = trace
        .map(kdmpm::infra::trace::start)
        .transpose()
        .map_err(Fault::bad)?;
    if let Some(n) = threads {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(n.get());
        pool.build_global()
            .map_err(|e| Fault::bad(format!("cannot start {n} threads: {e}")))?;
    }
    match command {
        Command::Check { scene, overrides } => {
            let (_, derived) = LoadedScene::from_file(&scene, &overrides)
                .and_then(|l| build(&l))
                .map_err(Fault::bad)?;
            print!("{}: valid\n{derived}", scene.display());
        }
        Command::Triaxial(args) => triaxial(args)?,
        Command::Plot { dir } => {
            let (written, skipped) = kdmpm::output::plots::draw(&dir)
                .map_err(|e| Fault::bad(format!("cannot plot {}: {e}", dir.display())))?;
            written.iter().for_each(|w| println!("{}", dir.join(w).display()));
            skipped.iter().for_each(|s| eprintln!("  not drawn: {s}"));
        }
        Command::Study {
            study,
            out,
            launcher,
            workers,
        } => run_study(&study, out, launcher, workers)?,
        Command::Fos {
            scene,
            out,
            overrides,
            refining,
            workers,
            ..
        } => run_fos(&scene, out, &overrides, refining.refine, workers.quiet, comm)?,
        Command::Resume { dir, stepping } => {
            let run = Run::resume(dir).quiet(stepping.workers.quiet).over(comm.clone());
            return report(run.go(), stepping, comm);
        }
        Command::Run {
            scene,
            out,
            overrides,
            refining,
            mean_from,
            stepping,
            ..
        } => {
            let out = out.unwrap_or_else(|| default_out(&scene, "", "scene"));
            let what = match mean_from {
                Some(m) => mean_from_arg(&m)?,
                None => kdmpm::refine::RunQuantity::LimitPressure,
            };
            let loaded = LoadedScene::from_file(&scene, &overrides).map_err(Fault::bad)?;
            if let Some(levels) = refining.refine {
                return run_refined(&loaded, &out, levels, &what, stepping.workers.quiet, comm);
            }
            let run = Run::scene(loaded).into_dir(out).quiet(stepping.workers.quiet);
            return report(run.over(comm.clone()).go(), stepping, comm);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Refuses more threads than 4 a core this process may use: a step's work is shared
/// among them, so more only queue for the cores (10 000 threads on 2 cores spent minutes
/// starting before the first step).
fn check_threads(threads: Option<std::num::NonZeroUsize>) -> Result<(), Fault> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match threads {
        Some(n) if n.get() > 4 * cores => Err(Fault::bad(format!(
            "--threads {n}: at most 4 a core, {} on the {cores} core(s) this process may use \
             (results are the same for any count; more threads only queue for the cores)",
            4 * cores
        ))),
        _ => Ok(()),
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

/// Reports a run (`run`, `resume`) as the user asked: the profile, the error with what the
/// outputs left out, or the last line. Over several ranks rank 0 reports the run, each
/// other rank its own failure.
fn report(run: Result<RunReport, RunError>, stepping: Stepping, comm: &Comm) -> Result<ExitCode, Fault> {
    let rank = match comm.is_root() {
        true => String::new(),
        false => format!("rank {}: ", comm.rank()),
    };
    let r = run.map_err(|e| Fault(format!("{rank}{e}"), e.ending()))?;
    if stepping.profile && comm.is_root() {
        print!("{}", r.summary.profile_table());
    }
    if let Some(e) = &r.error {
        // A step's error is every rank's (the failing rank's message reaches rank 0):
        // rank 0 speaks for all.
        if comm.is_root() {
            eprintln!("error: {e}");
            r.notes.iter().for_each(|n| eprintln!("  {n}"));
        }
        return Ok(ExitCode::from(Ending::Failed.code()));
    }
    let interrupted = r.summary.outcome == Outcome::Interrupted;
    if comm.is_root() && (!stepping.workers.quiet || interrupted) {
        eprintln!("{}", r.describe());
    }
    Ok(ExitCode::from(
        if interrupted {
            Ending::Interrupted
        } else {
            Ending::Done
        }
        .code(),
    ))
}

/// `--mean-from ROW=FROM`: the curve row and the displacement (m) from which its static
/// states count.
fn mean_from_arg(arg: &str) -> Result<kdmpm::refine::RunQuantity, Fault> {
    let bad = || {
        Fault::bad(format!(
            "--mean-from {arg}: give ROW=FROM, a curve row and a displacement in m (tbar=0.5)"
        ))
    };
    let (row, from) = arg.rsplit_once('=').ok_or_else(bad)?;
    let from: f64 = from.trim().parse().map_err(|_| bad())?;
    Ok(kdmpm::refine::RunQuantity::MeanPressure {
        row: row.trim().to_string(),
        from,
    })
}

/// `kdmpm run --refine`: the scene's limit pressure, or the mean pressure `what` names, at
/// two or three cell sizes.
fn run_refined(
    loaded: &LoadedScene,
    out: &Path,
    levels: u32,
    what: &kdmpm::refine::RunQuantity,
    quiet: bool,
    comm: &Arc<Comm>,
) -> Result<ExitCode, Fault> {
    // Over several ranks rank 0 speaks for all.
    let quiet = quiet || !comm.is_root();
    let show = |l: &kdmpm::refine::Level| {
        if !quiet {
            eprintln!("h = {} m done ({:.1} s)", l.cell_size, l.wall_seconds);
        }
    };
    let (r, refinement) = kdmpm::refine::pressure_over(loaded, out, levels, quiet, what, comm, show)
        .map_err(|e| Fault(e.to_string(), e.ending()))?;
    if !quiet {
        println!("{}\n{}", r.describe(), refinement.describe());
    }
    Ok(ExitCode::SUCCESS)
}

/// `kdmpm fos`: the strength-reduction analysis of a scene (at two or three cell sizes with
/// `--refine`).
fn run_fos(
    path: &Path,
    out: Option<PathBuf>,
    overrides: &[String],
    refine: Option<u32>,
    quiet: bool,
    comm: &Arc<Comm>,
) -> Result<(), Fault> {
    // Over several ranks rank 0 speaks for all.
    let quiet = quiet || !comm.is_root();
    let loaded = LoadedScene::from_file(path, overrides).map_err(Fault::bad)?;
    let out = out.unwrap_or_else(|| default_out(path, "fos-", "scene"));
    if let Some(levels) = refine {
        let show = |h: f64, t: &kdmpm::fos::Trial| {
            if !quiet {
                eprintln!("h = {h} m, {}", t.describe());
            }
        };
        let (r, refinement) = kdmpm::refine::factor_of_safety_over(&loaded, &out, levels, comm, show)
            .map_err(|e| Fault(e.to_string(), e.ending()))?;
        if !quiet {
            println!("{} → {}\n{}", r.describe(), out.display(), refinement.describe());
        }
        return Ok(());
    }
    let show = |t: &kdmpm::fos::Trial| {
        if !quiet {
            eprintln!("{}", t.describe());
        }
    };
    let r = kdmpm::fos::strength_reduction_over(&loaded, &out, comm, show)
        .map_err(|e| Fault(e.to_string(), e.ending()))?;
    if !quiet {
        println!("{} → {}", r.describe(), out.display());
    }
    Ok(())
}

/// `kdmpm study`: plans and checks every run, then has the library conduct the study.
fn run_study(
    path: &Path,
    out: Option<PathBuf>,
    launcher: Option<String>,
    workers: Workers,
) -> Result<(), Fault> {
    use kdmpm::study::{conduct, Launch, Study};
    let study = Study::from_file(path).map_err(Fault::bad)?;
    let out = out.unwrap_or_else(|| default_out(path, "study-", "study"));
    let dir = OutputDir::claim(&out).map_err(Fault::bad)?;
    let exe = std::env::current_exe().map_err(|e| {
        Fault(
            format!("cannot find kdmpm to launch the runs: {e}"),
            Ending::Failed,
        )
    })?;
    let threads = workers.threads.map(|n| n.get());
    let launcher: Vec<String> = launcher
        .iter()
        .flat_map(|l| l.split_whitespace())
        .map(String::from)
        .collect();
    let launch = Launch {
        exe,
        threads,
        launcher,
    };
    let results =
        conduct(&study, &dir, &launch, workers.quiet).map_err(|e| Fault(e.to_string(), e.ending()))?;
    if !workers.quiet {
        println!("{}→ {}", results.describe(&study), dir.path().display());
    }
    Ok(())
}
