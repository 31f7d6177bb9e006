//! A run over MPI ranks: each rank steps its part of the scene; rank 0 writes history.csv,
//! summary.json (the ranks' figures) and points.pvtu, every rank its own
//! `points_<rank>.vtu`.

use super::hooks::Hook;
use super::{claim, RunError, RunReport, Watch};
use crate::checkpoint;
use crate::dim::Dim;
use crate::output::recorder::write_final_points;
use crate::output::snapshots::{SnapshotWriter, Snapshots};
use crate::output::{Summary, TracedGather};
use crate::scene::LoadedScene;
use crate::simulation::Simulation;
use std::time::Instant;

/// Steps this rank's part of `sim`; rank 0 through the runner's hooks and outputs.
pub(super) fn go<D: Dim>(
    sim: &mut Simulation<D>,
    loaded: &LoadedScene,
    watch: Watch<'_>,
) -> Result<RunReport, RunError> {
    let comm = watch.comm.clone();
    let refuse = |what: String| RunError::Ranks(format!("{}: {what}", loaded.path.display()));
    if loaded.scene.solver.checkpoint_every.is_some() {
        return Err(refuse(format!(
            "a run over {} ranks does not yet write checkpoints: remove \
             solver.checkpoint_every, or run on one rank",
            comm.size()
        )));
    }
    super::distribute::decompose(sim, comm.clone());
    // Every rank gathers the traced points for rank 0's history, before it is written.
    let gather = TracedGather::new(&sim.traced);
    sim.schedule.push(gather);
    let dir = match (&watch.out, comm.is_root()) {
        (Some(out), true) => Some(claim(out)),
        _ => None,
    };
    // Whether rank 0 holds the directory: the others write into it.
    if comm.any(matches!(dir, Some(Err(_)))) {
        return Err(match dir {
            Some(Err(e)) => e,
            _ => RunError::OutputDir("rank 0 could not take the output directory".into()),
        });
    }
    if comm.is_root() {
        let dir = dir.transpose()?;
        let header = checkpoint::Header {
            scene_path: loaded.path.clone(),
            scene_text: loaded.text.clone(),
            ..checkpoint::Header::default()
        };
        return watch.drive(sim, loaded, dir.as_ref(), None, header);
    }
    // This rank's part of each snapshot (rank 0's recorder writes the rest).
    let snapshots = match (&watch.out, loaded.scene.output.snapshots) {
        (Some(out), Some(spec)) => {
            let ranks = (comm.rank(), comm.size());
            let (system, writer) = Snapshots::<D>::start(out, spec, None, ranks).map_err(|e| {
                RunError::Results(format!("rank {}: cannot start its snapshots: {e}", comm.rank()))
            })?;
            sim.schedule.push(system);
            Some(writer)
        }
        _ => None,
    };
    let start = Instant::now();
    // A strength-reduction trial's limit is every rank's decision (a collective).
    let mut limit = watch.limit;
    let result = sim.run_with(|s| match &mut limit {
        Some(l) => Hook::after_step(l, s),
        None => Ok(()),
    });
    // A state with a non-finite value comes with the run's error, reported with it.
    let unwritten = watch
        .out
        .as_deref()
        .and_then(|out| Some((out, write_final_points(sim, out).err()?)));
    let series = snapshots
        .map(SnapshotWriter::finish)
        .transpose()
        .map_err(|e| RunError::Results(format!("rank {}: cannot write its snapshots: {e}", comm.rank())));
    // The summary's figures are collectives: this rank takes part, rank 0 writes them.
    let error = result.err();
    let summary = Summary::collect(
        &loaded.path.display().to_string(),
        sim,
        start.elapsed().as_secs_f64(),
        error.as_ref().map(|e| e.to_string()),
    );
    series?;
    if let (None, Some((out, e))) = (&error, unwritten) {
        return Err(RunError::Results(format!(
            "rank {}: cannot write its points into {}: {e}",
            comm.rank(),
            out.display()
        )));
    }
    Ok(RunReport {
        summary,
        error,
        notes: Vec::new(),
        dir: watch.out,
    })
}
