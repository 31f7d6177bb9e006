//! The `kdmpm` command line: run or check a scene.

use clap::{Parser, Subcommand};
use kdmpm::output::{History, Summary};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{with_simulation, Dim, Simulation};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
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
        /// Print the per-system timing table at the end.
        #[arg(long)]
        profile: bool,
        /// Print nothing but errors.
        #[arg(long, short)]
        quiet: bool,
        /// Worker threads (default: all cores). Results are identical for any count.
        #[arg(long)]
        threads: Option<std::num::NonZeroUsize>,
        /// Write a Chrome trace (chrome://tracing, Perfetto) of every system call to FILE
        /// (needs a build with `--features trace`).
        #[arg(long, value_name = "FILE")]
        trace: Option<PathBuf>,
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
    match Cli::parse().command {
        Command::Check { scene, overrides } => check(&scene, &overrides),
        Command::Run {
            scene,
            out,
            overrides,
            profile,
            quiet,
            threads,
            trace,
        } => {
            let _trace = match trace.map(start_trace).transpose() {
                Ok(guard) => guard,
                Err(message) => {
                    eprintln!("error: {message}");
                    return ExitCode::from(BAD_INPUT);
                }
            };
            if let Some(n) = threads {
                if let Err(e) = rayon::ThreadPoolBuilder::new()
                    .num_threads(n.get())
                    .build_global()
                {
                    eprintln!("error: cannot start {n} threads: {e}");
                    return ExitCode::from(BAD_INPUT);
                }
            }
            run(&scene, out, &overrides, profile, quiet)
        }
    }
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

fn run(path: &Path, out: Option<PathBuf>, overrides: &[String], profile: bool, quiet: bool) -> ExitCode {
    let (loaded, mut sim) =
        match LoadedScene::from_file(path, overrides).and_then(|l| build(&l).map(|(s, _)| (l, s))) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(BAD_INPUT);
            }
        };
    let stem = path
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let out = out.unwrap_or_else(|| Path::new("out").join(&stem));
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create output directory {}: {e}", out.display());
        return ExitCode::from(BAD_INPUT);
    }
    let every = loaded.scene.output.history_every;
    with_simulation!(&mut sim, s => run_dim(s, path, &out, every, profile, quiet))
}

fn run_dim<D: Dim>(
    sim: &mut Simulation<D>,
    scene: &Path,
    out: &Path,
    every: u64,
    profile: bool,
    quiet: bool,
) -> ExitCode {
    let history = match History::<D>::create(&out.join("history.csv"), every, &sim.traced) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: cannot write {}: {e}", out.join("history.csv").display());
            return ExitCode::from(BAD_INPUT);
        }
    };
    sim.schedule.push(history);
    if !quiet {
        eprintln!(
            "{}: {} points, {}D, Δt = {:.4e} s",
            scene.display(),
            sim.point_count(),
            D::N,
            sim.ctx.state.dt
        );
    }
    let start = Instant::now();
    let mut last_report = Instant::now();
    let result = sim.run(|s| {
        if !quiet && last_report.elapsed().as_secs_f64() > 2.0 {
            last_report = Instant::now();
            eprintln!(
                "  step {:>8}  t = {:<10.4}  K_F = {:.3e}  K_E = {:.3e}  resets {}",
                s.step, s.time, s.force_ratio_max, s.energy_ratio, s.resets
            );
        }
    });
    let wall = start.elapsed().as_secs_f64();
    let error = result.as_ref().err().map(|e| e.to_string());
    if let Err(e) = kdmpm::output::vtk::write_points(sim, &out.join("points.vtu")) {
        eprintln!("error: cannot write points.vtu: {e}");
        return ExitCode::from(BAD_INPUT);
    }
    // After the output, so that the peak memory covers the whole run.
    let summary = Summary::collect(&scene.display().to_string(), sim, wall, error);
    let json = serde_json::to_string_pretty(&summary).expect("summary serialises");
    if let Err(e) = std::fs::write(out.join("summary.json"), json) {
        eprintln!("error: cannot write summary.json: {e}");
        return ExitCode::from(BAD_INPUT);
    }
    if profile {
        print_profile(&summary);
    }
    if let Err(e) = result {
        eprintln!("error: {e}");
        return ExitCode::from(RUN_FAILED);
    }
    if !quiet {
        eprintln!(
            "{} after {} steps, t = {:.4} s: K_F = {:.3e} (max) / {:.3e} (mean), K_E = {:.3e}, {} resets, {:.2} s wall → {}",
            if summary.converged { "converged" } else { "stopped" },
            summary.steps,
            summary.time,
            summary.force_ratio_max,
            summary.force_ratio_mean,
            summary.energy_ratio,
            summary.kinetic_resets,
            wall,
            out.display()
        );
    }
    ExitCode::SUCCESS
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
