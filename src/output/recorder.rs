//! Everything a run writes, for any [`Simulation`]: attach a [`Recorder`] before stepping
//! and finish it after. The `kdmpm` binary does exactly this; a library user gets the same
//! files (`examples/write_results.rs`).

use crate::dim::Dim;
use crate::model::{CurvePoint, StageResult};
use crate::output::dir::OutputDir;
use crate::output::history::{self, History};
use crate::output::snapshots::{SnapshotSpec, SnapshotWriter, Snapshots};
use crate::output::summary::Summary;
use crate::output::vtk::{write_parallel_points, write_points};
use crate::output::RowFile;
use crate::simulation::Simulation;
use crate::systems::convergence::ratio_cell;
use std::io::Write;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// The load–displacement curve's file.
pub const CURVE: &str = "curve.csv";

/// `curve.csv`: one row a static state of a prescribed motion: name, step, time (s),
/// displacement along the motion (m), force on the body (N; N/m in 2D) and, when a row has
/// a loaded area, the mean pressure (Pa; the cell is empty in the rows without one, a
/// body's part without an `area`).
fn curve_csv<D: Dim>(curve: &[CurvePoint]) -> String {
    let pressure = curve.iter().any(|c| c.pressure.is_some());
    let axes = &["x", "y", "z"][..D::N];
    let mut t = format!(
        "name,step,time,displacement,{}{}\n",
        axes.iter()
            .map(|a| format!("force_{a}"))
            .collect::<Vec<_>>()
            .join(","),
        if pressure { ",pressure" } else { "" }
    );
    for c in curve {
        t += &format!("{},{},{:.9e},{:.9e}", c.name, c.step, c.time, c.displacement);
        for f in &c.force[..D::N] {
            t += &format!(",{f:.9e}");
        }
        match (pressure, c.pressure) {
            (true, Some(p)) => t += &format!(",{p:.9e}"),
            (true, None) => t += ",",
            _ => {}
        }
        t += "\n";
    }
    t
}

/// The log of `body` read as the piezocone `cpt`: each static state of its tip's row of
/// `curve` with its sleeve's and filter's rows of the same step, against `ground`.
fn cpt_log(
    body: &crate::rigid::RigidBodySpec,
    cpt: &crate::rigid::Cpt,
    ground: &crate::rigid::InSitu,
    curve: &[CurvePoint],
    n: usize,
) -> Vec<crate::rigid::cpt::LogRow> {
    let row = |name: String| format!("{}.{name}", body.name);
    let tip = row(body.parts[cpt.tip].name.clone());
    let sleeve = cpt.sleeve.map(|k| row(body.parts[k].name.clone()));
    let filter = cpt.filter.map(|k| row(body.filters[k].name.clone()));
    let at = |name: &Option<String>, step: u64| -> Option<f64> {
        let name = name.as_ref()?;
        (curve.iter())
            .find(|c| c.step == step && c.name == *name)?
            .pressure
    };
    (curve.iter().filter(|c| c.name == tip))
        .filter_map(|c| {
            let readings = crate::rigid::cpt::Readings {
                step: c.step,
                travel: c.displacement,
                tip: c.pressure?,
                sleeve: at(&sleeve, c.step),
                u2: at(&filter, c.step),
            };
            crate::rigid::cpt::log_row(body, cpt, ground, n, &readings)
        })
        .collect()
}

/// The loading stages' file.
pub const STAGES: &str = "stages.csv";

/// `stages.csv`: one row a finished stage: name, step, time (s), K_F, K_E, resets so far.
fn stages_csv(stages: &[StageResult]) -> String {
    let mut t = String::from("stage,step,time,force_ratio,energy_ratio,resets\n");
    for s in stages {
        t += &format!(
            "{},{},{:.9e},{},{},{}\n",
            s.name,
            s.step,
            s.time,
            ratio_cell(s.force_ratio, 9),
            ratio_cell(s.energy_ratio, 9),
            s.resets
        );
    }
    t
}

/// Writes this rank's final points into `dir`: `points.vtu`, or over MPI
/// `points_<rank>.vtu`, which rank 0's `points.pvtu` ties together. When the state holds a non-finite value
/// nothing is written, and the note says why.
pub fn write_final_points<D: Dim>(sim: &Simulation<D>, dir: &Path) -> std::io::Result<Option<String>> {
    let comm = &sim.ctx.comm;
    let points = match comm.size() {
        1 => "points.vtu".to_string(),
        _ => format!("points_{}.vtu", comm.rank()),
    };
    if comm.size() > 1 && comm.is_root() {
        let parts: Vec<String> = (0..comm.size()).map(|r| format!("points_{r}.vtu")).collect();
        write_parallel_points(sim, &dir.join("points.pvtu"), &parts)?;
    }
    match sim.first_non_finite() {
        None => write_points(sim, &dir.join(&points)).map(|()| None),
        Some(what) => Ok(Some(format!(
            "{points} not written: the state holds a non-finite {what}"
        ))),
    }
}

/// Removes what an earlier run left in `dir` as its results (summary, points, curve,
/// stages, plots, snapshot series), so that after a crash of the new run nothing of the old
/// one sits beside the new history.csv looking current.
fn clear_earlier_results(dir: &OutputDir) -> std::io::Result<()> {
    let fixed = [
        "summary.json",
        "points.vtu",
        "points.pvtu",
        CURVE,
        crate::rigid::cpt::LOG_FILE,
        STAGES,
        crate::output::plots::CURVE_PLOT,
        crate::output::plots::CPT_PLOT,
    ];
    let names = fixed.iter().chain(&crate::output::plots::FILES);
    for name in names {
        crate::output::dir::remove_if_there(&dir.file(name))?;
    }
    for e in std::fs::read_dir(dir.path())?.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        // Over MPI, each rank's points.
        if name.starts_with("points_") && name.ends_with(".vtu") {
            crate::output::dir::remove_if_there(&e.path())?;
        }
    }
    crate::output::snapshots::clear(dir.path())
}

/// The outputs a run writes into its directory: `history.csv` every `history_every` steps,
/// the snapshot series when `snapshots` is set, and at the end `points.vtu`,
/// `summary.json` and the plots ([`crate::output::plots`]).
pub struct Recorder {
    rows: Arc<Mutex<RowFile>>,
    snapshots: Option<SnapshotWriter>,
}

/// What [`Recorder::finish`] left out, for the run's report (never an error: the files it
/// did write are whole).
#[derive(Clone, Debug, Default)]
pub struct Notes(pub Vec<String>);

impl Recorder {
    /// Adds the history and (with `snapshots`) the snapshot systems to the end of `sim`'s
    /// schedule, writing into `dir`. A run resumed from a checkpoint passes the history
    /// file's committed length and its CRC-32 in `history`; a new run passes `None`.
    pub fn attach<D: Dim>(
        sim: &mut Simulation<D>,
        dir: &OutputDir,
        history_every: u64,
        snapshots: Option<SnapshotSpec>,
        history: Option<(u64, u32)>,
    ) -> std::io::Result<Recorder> {
        let history_bytes = history.map(|h| h.0);
        if history.is_none() {
            clear_earlier_results(dir)?;
        }
        let file = dir.file("history.csv");
        let history = match history {
            None => History::<D>::create(&file, history_every, &sim.traced, &sim.ctx.state.control.drives)?,
            Some(mark) => History::<D>::resume(&file, mark, history_every, &sim.traced)?,
        };
        let rows = history.rows();
        sim.schedule.push(history);
        let snapshots = match snapshots {
            Some(spec) => {
                let resumed = history_bytes.map(|_| sim.ctx.state.clock.time);
                let ranks = (sim.ctx.comm.rank(), sim.ctx.comm.size());
                let (system, writer) = Snapshots::<D>::start(dir.path(), spec, resumed, ranks)?;
                sim.schedule.push(system);
                Some(writer)
            }
            None => None,
        };
        Ok(Recorder { rows, snapshots })
    }

    /// The history rows, shared with a checkpoint writer (it flushes them and notes their
    /// length).
    pub fn rows(&self) -> &Arc<Mutex<RowFile>> {
        &self.rows
    }

    /// Flushes the history, waits for the snapshot writer, writes `points.vtu` (unless the
    /// state holds a non-finite value: nothing is ever written as NaN) and `summary.json`,
    /// and returns the summary with what was left out. `checkpointed`: the directory holds
    /// a checkpoint of the run (the note of a state not written says it can be resumed).
    pub fn finish<D: Dim>(
        self,
        sim: &Simulation<D>,
        dir: &OutputDir,
        scene: &str,
        (wall_seconds, checkpointed): (f64, bool),
        error: Option<String>,
    ) -> std::io::Result<(Summary, Notes)> {
        history::lock(&self.rows).flush()?;
        let series = self.snapshots.map(SnapshotWriter::finish).transpose()?;
        let mut notes = Notes::default();
        if let Some(note) = write_final_points(sim, dir.path())? {
            notes.0.push(format!(
                "{note}{}",
                if checkpointed {
                    "; the last checkpoint holds a finite state (kdmpm resume)"
                } else {
                    ""
                }
            ));
        }
        if !sim.ctx.state.control.stages.is_empty() {
            dir.write_atomic(STAGES, |out| {
                out.write_all(stages_csv(&sim.ctx.state.control.stages).as_bytes())
            })?;
        }
        if !sim.ctx.state.control.curve.is_empty() {
            dir.write_atomic(CURVE, |out| {
                out.write_all(curve_csv::<D>(&sim.ctx.state.control.curve).as_bytes())
            })?;
        }
        let control = &sim.ctx.state.control;
        for (body, b) in sim.ctx.model.bodies.iter().zip(&control.bodies) {
            // One piezocone a run (`scene::validate` refuses a second).
            if let (Some(cpt), Some(ground)) = (&body.cpt, &b.in_situ) {
                let rows = cpt_log(&body.spec, cpt, ground, &control.curve, D::N);
                dir.write_atomic(crate::rigid::cpt::LOG_FILE, |out| {
                    out.write_all(crate::rigid::cpt::log_csv(&rows).as_bytes())
                })?;
                break;
            }
        }
        // After the output, so that the peak memory covers the whole run.
        let mut summary = Summary::collect(scene, sim, wall_seconds, error);
        if let Some(r) = series {
            summary.snapshots = Some(r.written);
            summary.output_wait_seconds = Some(r.wait_seconds);
        }
        dir.write_atomic("summary.json", |out| {
            serde_json::to_writer_pretty(&mut *out, &summary).map_err(std::io::Error::other)?;
            out.write_all(b"\n")
        })?;
        let (_, skipped) = crate::output::plots::draw(dir.path())?;
        notes.0.extend(skipped);
        Ok((summary, notes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Dim2;

    fn point(name: &str, pressure: Option<f64>) -> CurvePoint {
        CurvePoint {
            name: name.into(),
            step: 7,
            time: 1.0,
            displacement: 0.25,
            force: [1.0, -2.0, 0.0],
            pressure,
        }
    }

    #[test]
    fn a_part_without_an_area_leaves_its_pressure_cell_empty() {
        let csv = curve_csv::<Dim2>(&[point("cone.tip", Some(3.0)), point("cone.shaft", None)]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "name,step,time,displacement,force_x,force_y,pressure");
        assert!(lines[1].ends_with(",3.000000000e0"), "{}", lines[1]);
        assert!(lines[2].ends_with("-2.000000000e0,"), "{}", lines[2]);
        // And summary.json leaves the key out rather than writing null.
        let json = serde_json::to_string(&point("cone.shaft", None)).unwrap();
        assert!(!json.contains("pressure"), "{json}");
    }

    #[test]
    fn a_curve_without_areas_has_no_pressure_column() {
        let csv = curve_csv::<Dim2>(&[point("wall", None)]);
        assert_eq!(
            csv.lines().next(),
            Some("name,step,time,displacement,force_x,force_y")
        );
    }
}
