//! Speed against accuracy: a study runs one scene over axes of settings, each run a normal
//! `kdmpm run` into its own directory, and tabulates outcome, cost and the signed relative
//! error of each measured quantity; it marks the Pareto front of error against wall time
//! and, over a `Refine` axis, the observed order of convergence.
//!
//! A run that fails, diverges or does not stop is a row with its outcome. A run whose
//! directory holds a completion record for the same overrides is not run again, so an
//! interrupted study started again continues where it stopped.

mod plot;
mod progress;
mod report;
mod spec;

pub use report::{convergence_orders, pareto_front, Order, Row};
pub use spec::{
    expected, read, relative_error, Axis, Combine, Compare, Planned, Quantity, QuantitySpec, Study, StudySpec,
};

use crate::output::{dir::write_atomic, OutputDir};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The file in a run's directory that records a completed run: its overrides, exit status
/// and wall time. Written last, atomically.
pub const RECORD: &str = "study-run.txt";

/// How the runs are launched.
#[derive(Clone, Debug)]
pub struct Launch {
    /// The `kdmpm` executable.
    pub exe: PathBuf,
    /// `--threads` for each run.
    pub threads: Option<usize>,
    /// The command that starts each run over MPI ranks (`["mpirun", "-n", "4"]`), the
    /// executable and its arguments after it; empty: each run is one process.
    pub launcher: Vec<String>,
}

/// Why a study could not go on (its runs' own failures are rows, not errors).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The study's output directory or a file in it could not be used.
    #[error("{0}")]
    Output(String),
    /// The reference run found no static state: errors measured against it would mean
    /// nothing.
    #[error("{0}")]
    Reference(String),
    /// The study was stopped by a signal; the run under way was stopped and waited for,
    /// and is run again when the study is started again.
    #[error("interrupted: run {0} was stopped and will be run again when the study is started again")]
    Interrupted(String),
}

impl StudyError {
    /// An interrupted study, or one that went wrong (its bad input is refused before it
    /// starts, as a [`crate::error::SceneError`] from [`Study::from_file`]).
    pub fn ending(&self) -> crate::error::Ending {
        match self {
            StudyError::Interrupted(_) => crate::error::Ending::Interrupted,
            StudyError::Output(_) | StudyError::Reference(_) => crate::error::Ending::Failed,
        }
    }
}

/// Refuses a reference run that did not converge: it ended at its step or time limit, or
/// failed, so its figures are not the static answer the other runs are compared with.
pub fn check_reference(reference: &Finished) -> Result<(), StudyError> {
    if report::answered(&reference.outcome) {
        return Ok(());
    }
    Err(StudyError::Reference(format!(
        "the reference run ({}) did not converge: it {}; its figures are no static answer to \
         measure errors against: give the reference a larger max_steps or max_time (or a \
         looser tolerance), then start the study again",
        reference.run.id,
        match reference.outcome.as_str() {
            "max_steps" | "max_time" | "stopped" => format!("ended at its limit ({})", reference.outcome),
            other => format!("ended as `{other}`"),
        }
    )))
}

/// Asks the child run to stop as Ctrl-C would (it writes its checkpoint and exits).
fn pass_signal(child: &std::process::Child) {
    // SAFETY: `kill` with a valid signal number has no memory effects; the pid is our
    // own child's, not yet waited for, so it cannot have been reused.
    unsafe {
        libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
    }
}

/// What one finished (or reused) run left.
#[derive(Clone, Debug)]
pub struct Finished {
    /// The planned run.
    pub run: Planned,
    /// Outcome: the summary's, or `crashed (exit N)` / `timeout` / `no summary`.
    pub outcome: String,
    /// Wall-clock seconds of the whole command (set-up, stepping, output).
    pub wall_seconds: f64,
    /// The run's `summary.json`, when it wrote one.
    pub summary: Option<serde_json::Value>,
    /// True when an earlier invocation ran it.
    pub reused: bool,
}

/// Runs (or reuses) one planned run in `dir/<id>`.
pub fn run_one(
    study: &Study,
    run: &Planned,
    dir: &OutputDir,
    launch: &Launch,
) -> Result<Finished, StudyError> {
    if let Some(rule) = &run.refused {
        return Ok(Finished {
            run: run.clone(),
            outcome: format!("refused: {rule}"),
            wall_seconds: 0.0,
            summary: None,
            reused: false,
        });
    }
    let out = dir.file(&run.id);
    let record_text = record_head(run);
    if let Ok(text) = std::fs::read_to_string(out.join(RECORD)) {
        if let Some(rest) = text.strip_prefix(&record_text) {
            let mut outcome = None;
            let mut wall = None;
            for line in rest.lines() {
                if let Some(v) = line.strip_prefix("outcome=") {
                    outcome = Some(v.to_string());
                }
                if let Some(v) = line.strip_prefix("wall_seconds=") {
                    wall = v.parse().ok();
                }
            }
            if let (Some(outcome), Some(wall_seconds)) = (outcome, wall) {
                return Ok(Finished {
                    run: run.clone(),
                    outcome,
                    wall_seconds,
                    summary: read_summary(&out),
                    reused: true,
                });
            }
        }
    }
    let mut cmd = match launch.launcher.split_first() {
        Some((first, rest)) => {
            let mut c = Command::new(first);
            c.args(rest).arg(&launch.exe);
            c
        }
        None => Command::new(&launch.exe),
    };
    cmd.arg(study.command())
        .arg(&study.scene)
        .arg("--out")
        .arg(&out)
        .arg("--quiet");
    if let Some(n) = launch.threads {
        cmd.arg("--threads").arg(n.to_string());
    }
    for o in &run.overrides {
        cmd.arg("--set").arg(o);
    }
    // A run directory another process holds (a run of an earlier study still going) is
    // an error of the study's, not a row of "bad input" with that run's numbers.
    drop(OutputDir::claim(&out).map_err(|e| StudyError::Output(e.to_string()))?);
    let stderr = std::fs::File::create(out.join("stderr.txt"))
        .map_err(|e| StudyError::Output(format!("cannot write {}: {e}", out.join("stderr.txt").display())))?;
    cmd.stdout(Stdio::null()).stderr(stderr);
    let start = Instant::now();
    let mut child = cmd.spawn().map_err(|e| {
        let what = launch
            .launcher
            .first()
            .map_or(launch.exe.display().to_string(), String::clone);
        StudyError::Output(format!("cannot start {what}: {e}"))
    })?;
    let limit = study.spec.run_limit.map(Duration::from_secs_f64);
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) => {}
            Err(e) => return Err(StudyError::Output(format!("cannot wait for run {}: {e}", run.id))),
        }
        if crate::interrupt::requested() {
            pass_signal(&child);
            let _ = child.wait();
            return Err(StudyError::Interrupted(run.id.clone()));
        }
        if limit.is_some_and(|l| start.elapsed() > l) {
            // A run past its limit is stopped; it is a row with outcome `timeout`.
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let wall_seconds = start.elapsed().as_secs_f64();
    let summary = read_summary(&out);
    let outcome = match (&status, &summary) {
        (None, _) => "timeout".to_string(),
        (Some(_), Some(s)) if s.get("factor_of_safety").is_some() => report::BRACKETED.into(),
        (Some(_), Some(s)) => s["outcome"].as_str().unwrap_or("unknown").to_string(),
        (Some(st), None) => match st.code() {
            Some(2) => "bad input (exit 2)".into(),
            Some(c) => format!("crashed (exit {c})"),
            None => "crashed (signal)".into(),
        },
    };
    let record = format!("{record_text}outcome={outcome}\nwall_seconds={wall_seconds}\n");
    write_atomic(&out.join(RECORD), |w| w.write_all(record.as_bytes()))
        .map_err(|e| StudyError::Output(format!("cannot write {}: {e}", out.join(RECORD).display())))?;
    Ok(Finished {
        run: run.clone(),
        outcome,
        wall_seconds,
        summary,
        reused: false,
    })
}

/// The part of a completion record that names the run: a record for other overrides is
/// not this run's.
fn record_head(run: &Planned) -> String {
    let mut s = String::new();
    for o in &run.overrides {
        s.push_str("set ");
        s.push_str(o);
        s.push('\n');
    }
    s
}

fn read_summary(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// A study's table, its Pareto front (row indices, fastest first) and the observed orders.
#[derive(Clone, Debug)]
pub struct Results {
    /// One row a run.
    pub rows: Vec<Row>,
    /// Indices into `rows` of the Pareto-optimal runs.
    pub front: Vec<usize>,
    /// Orders of convergence over a `Refine` axis.
    pub orders: Vec<Order>,
}

impl Results {
    /// The Pareto front and, over a `Refine` axis, the observed orders, as `kdmpm study`
    /// prints them.
    pub fn describe(&self, study: &Study) -> String {
        let mut text = front_table(study, &self.rows, &self.front);
        if !self.orders.is_empty() {
            text += &orders_table(&self.orders);
        }
        text
    }
}

/// Everything a study writes: `study.csv`, `pareto.svg`, and `convergence.csv` over a
/// `Refine` axis.
pub fn write_results(
    study: &Study,
    dir: &OutputDir,
    reference: Option<&Finished>,
    finished: &[Finished],
) -> Result<Results, StudyError> {
    let rows: Vec<Row> = finished.iter().map(|f| Row::new(study, f, reference)).collect();
    let io = |file: &str, e: std::io::Error| {
        StudyError::Output(format!("cannot write {}: {e}", dir.file(file).display()))
    };
    let csv = report::csv(study, &rows);
    dir.write_atomic("study.csv", |w| w.write_all(csv.as_bytes()))
        .map_err(|e| io("study.csv", e))?;
    let front = pareto_front(&rows);
    let svg = plot::pareto_svg(study, &rows, &front);
    dir.write_atomic("pareto.svg", |w| w.write_all(svg.as_bytes()))
        .map_err(|e| io("pareto.svg", e))?;
    let orders = convergence_orders(study, &rows);
    if !orders.is_empty() {
        let text = report::orders_csv(&orders);
        dir.write_atomic("convergence.csv", |w| w.write_all(text.as_bytes()))
            .map_err(|e| io("convergence.csv", e))?;
    }
    Ok(Results { rows, front, orders })
}

pub use report::{front_table, orders_table};

/// Runs a whole study into `dir`: the reference first (refused when it did not converge),
/// then every planned run (skipping those an earlier invocation completed), and writes the
/// study's table and picture. Progress goes to stderr unless `quiet`. A signal
/// ([`crate::catch_signals`]) stops the run under way and the study.
pub fn conduct(study: &Study, dir: &OutputDir, launch: &Launch, quiet: bool) -> Result<Results, StudyError> {
    let total = study.runs.len() + usize::from(study.reference.is_some());
    let progress = progress::StudyProgress::new(total as u64, quiet);
    let run = |planned: &Planned| {
        progress.start(planned);
        let r = run_one(study, planned, dir, launch);
        if let Ok(f) = &r {
            progress.finish(f);
        }
        r
    };
    let runs = || -> Result<(Option<Finished>, Vec<Finished>), StudyError> {
        let reference = study.reference.as_ref().map(run).transpose()?;
        if let Some(r) = &reference {
            check_reference(r)?;
        }
        let finished = study.runs.iter().map(run).collect::<Result<Vec<_>, _>>()?;
        Ok((reference, finished))
    };
    let ran = runs();
    progress.done();
    let (reference, finished) = ran?;
    write_results(study, dir, reference.as_ref(), &finished)
}
