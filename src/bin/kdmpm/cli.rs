//! The command line of `kdmpm`: its commands and their options (the `--help` text is
//! the doc comments here).

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "kdmpm",
    version,
    about = "Static large-deformation MPM with kinetic damping"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// Threads and terminal output, for every command that runs.
#[derive(clap::Args, Clone, Copy)]
pub struct Workers {
    /// Print nothing but errors.
    #[arg(long, short)]
    pub quiet: bool,
    /// Worker threads (default: all cores; a study gives each run this many). Results are
    /// identical for any count.
    #[arg(long)]
    pub threads: Option<std::num::NonZeroUsize>,
}

/// How a run steps and what it prints, for `run` and `resume` alike.
#[derive(clap::Args, Clone, Copy)]
pub struct Stepping {
    /// Print the per-system timing table at the end.
    #[arg(long)]
    pub profile: bool,
    #[command(flatten)]
    pub workers: Workers,
}

/// The discretisation error of the answer, for `run` and `fos` alike.
#[derive(clap::Args, Clone, Copy)]
pub struct Refining {
    /// Also run the analysis at h/2 and h/4 (`--refine 2`: h/2 only) and report the
    /// extrapolated answer and the discretisation error of the answer at h (in
    /// summary.json too); the finer runs go into <out>/refine/.
    #[arg(long, value_name = "LEVELS", num_args = 0..=1, default_missing_value = "3")]
    pub refine: Option<u32>,
}

/// How a run over MPI ranks lays them over the grid, for `run` and `fos` alike.
#[derive(clap::Args, Clone, Copy)]
pub struct Layout {
    /// Under mpirun: lay the ranks as SLABS slabs along the grid's slab axis, each cut
    /// into ACROSS parts along a second axis (e.g. `--split 2x2` on 4 ranks; default: the
    /// layout that keeps the most ranks holding cells, a part at least 4 cell layers wide
    /// for B-splines and 3 for linear shapes, with the fewest cuts across among those).
    #[arg(long, value_name = "SLABSxACROSS", value_parser = parse_split)]
    pub split: Option<[usize; 2]>,
}

/// `AxB` as the two counts.
fn parse_split(s: &str) -> Result<[usize; 2], String> {
    let bad = || format!("`{s}` is not SLABSxACROSS, two counts of 1 or more joined by x (e.g. 2x2)");
    let (a, b) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let n = |t: &str| t.trim().parse::<usize>().ok().filter(|&n| n > 0).ok_or_else(bad);
    Ok([n(a)?, n(b)?])
}

#[derive(Subcommand)]
pub enum Command {
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
        refining: Refining,
        /// With --refine: estimate the mean pressure of curve row ROW over its static states
        /// at a displacement of FROM m or more (a penetrometer's steady resistance, e.g.
        /// `--mean-from tbar=0.5`) instead of the limit pressure.
        #[arg(long, value_name = "ROW=FROM", requires = "refine")]
        mean_from: Option<String>,
        #[command(flatten)]
        stepping: Stepping,
        #[command(flatten)]
        layout: Layout,
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
        /// Start each run over MPI ranks with this launcher command, split at spaces (e.g.
        /// "mpirun -n 4" or, in a Slurm job, "srun -n 4"): the study stays one process and
        /// each of its runs spans the ranks.
        #[arg(long, value_name = "COMMAND")]
        launcher: Option<String>,
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
        refining: Refining,
        #[command(flatten)]
        workers: Workers,
        #[command(flatten)]
        layout: Layout,
    },
    /// Draw (again) the plots of a run from its output directory, finished or running:
    /// kinetic energy, K_F and K_E, traced displacements, displacement field (SVG).
    Plot {
        /// The run's output directory.
        dir: PathBuf,
    },
    /// A triaxial compression test on one point of a scene's material (an element test,
    /// without a grid): isotropic start at the cell pressure, then equal axial strain
    /// increments, drained (radial effective stress held) or undrained (no volume change);
    /// writes triaxial.csv (compression positive: ε_a, ε_v, p′, q, excess pore pressure and
    /// the material's state) and prints the last row.
    Triaxial(TriaxialArgs),
    /// Parse and validate a scene without running it; print the derived figures.
    Check {
        /// Scene file (RON).
        scene: PathBuf,
        /// Override a scene field (repeatable).
        #[arg(long = "set", value_name = "PATH=VALUE")]
        overrides: Vec<String>,
    },
}

/// The element test of `kdmpm triaxial`.
#[derive(clap::Args)]
pub struct TriaxialArgs {
    /// Scene file (RON) whose `materials` holds the material.
    pub scene: PathBuf,
    /// The material's name in the scene.
    #[arg(long)]
    pub material: String,
    /// The isotropic effective stress the sample starts at (Pa).
    #[arg(long, value_name = "PA")]
    pub cell_pressure: f64,
    /// No water leaves the sample: its volume stays as it was.
    #[arg(long)]
    pub undrained: bool,
    /// The last axial strain (compression positive).
    #[arg(long, default_value_t = 0.3)]
    pub axial_strain: f64,
    /// Equal axial increments.
    #[arg(long, default_value_t = 3000)]
    pub steps: usize,
    /// Output directory (default: out/triaxial-<material>).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Override a scene field (repeatable).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    pub overrides: Vec<String>,
}
