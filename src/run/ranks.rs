//! A run over MPI ranks: each rank steps its part of the scene; rank 0 writes history.csv,
//! summary.json (the ranks' figures) and points.pvtu, every rank its own
//! `points_<rank>.vtu` and its part of each checkpoint ([`checkpoint::parts`]).

use super::hooks::{Checkpoints, Hook, StopOnRequest};
use super::{claim, RunError, RunReport, Watch};
use crate::checkpoint;
use crate::dim::Dim;
use crate::output::recorder::write_final_points;
use crate::output::snapshots::{SnapshotWriter, Snapshots};
use crate::output::{Summary, TracedGather};
use crate::scene::LoadedScene;
use crate::simulation::Simulation;
use std::time::Instant;

/// What a rank resumes from: the manifest, its own part's bytes and file.
pub(super) struct Resume<'a> {
    pub manifest: &'a checkpoint::parts::Manifest,
    pub part: &'a [u8],
    pub file: &'a std::path::Path,
}

/// Steps this rank's part `sim` of a scene of `total` points (built from the scene for this
/// rank, or from the checkpoint's scene when `resume` is given); rank 0 through the runner's
/// hooks and outputs.
pub(super) fn go<D: Dim>(
    sim: &mut Simulation<D>,
    loaded: &LoadedScene,
    watch: Watch<'_>,
    total: usize,
    resume: Option<Resume<'_>>,
) -> Result<RunReport, RunError> {
    let comm = watch.comm.clone();
    super::distribute::join(sim, comm.clone());
    if let Some(r) = &resume {
        // This rank's points, state and split as saved; a rank that cannot stops all.
        let restored = checkpoint::restore_part(sim, r.part, r.file, total);
        if let Some((rank, e)) = comm.first_error(&restored) {
            return Err(RunError::Ranks(format!("rank {rank}: {e}")));
        }
    }
    // Every rank gathers the traced points for rank 0's history, before it is written.
    let gather = TracedGather::new(&sim.traced);
    sim.schedule.push(gather);
    let dir = match (&watch.out, comm.is_root()) {
        (Some(out), true) => Some(claim(out).and_then(|d| {
            // A fresh run's directory keeps no checkpoint of an earlier run: its parts would
            // be taken for this run's. Removed before any rank writes one.
            if resume.is_none() {
                checkpoint::parts::remove_earlier(d.path()).map_err(|e| {
                    RunError::OutputDir(format!("cannot remove the earlier run's checkpoint: {e}"))
                })?;
            }
            Ok(d)
        })),
        _ => None,
    };
    // Whether rank 0 holds the directory: the others write into it.
    if comm.any(matches!(dir, Some(Err(_)))) {
        return Err(match dir {
            Some(Err(e)) => e,
            _ => RunError::OutputDir("rank 0 could not take the output directory".into()),
        });
    }
    let header = match &resume {
        Some(r) => r.manifest.header.clone(),
        None => checkpoint::Header {
            scene_path: loaded.path.clone(),
            scene_text: loaded.text.clone(),
            meshes_crc: loaded.mesh_crc(),
            ..checkpoint::Header::default()
        },
    };
    if comm.is_root() {
        let dir = dir.transpose()?;
        let mark = resume.map(|r| (r.manifest.header.history_bytes, r.manifest.header.history_crc));
        return watch.drive(sim, loaded, dir.as_ref(), mark, header);
    }
    // This rank's part of each snapshot (rank 0's recorder writes the rest).
    let resumed = resume.is_some().then_some(sim.ctx.state.clock.time);
    let snapshots = match (&watch.out, loaded.scene.output.snapshots) {
        (Some(out), Some(spec)) => {
            let ranks = (comm.rank(), comm.size());
            let (system, writer) = Snapshots::<D>::start(out, spec, resumed, ranks).map_err(|e| {
                RunError::Results(format!("rank {}: cannot start its snapshots: {e}", comm.rank()))
            })?;
            sim.schedule.push(system);
            Some(writer)
        }
        _ => None,
    };
    // The collective hooks of rank 0's, in its order: the stop request, the checkpoints
    // (this rank's part of each), a strength-reduction trial's limit.
    let mut hooks: Vec<Box<dyn Hook<D> + Send + '_>> = vec![Box::new(StopOnRequest(watch.stop.clone()))];
    if let (true, Some(out)) = (watch.checkpoints, &watch.out) {
        hooks.push(Box::new(Checkpoints {
            dir: out.clone(),
            every: loaded.scene.solver.checkpoint_every,
            header: header.clone(),
            rows: None,
            before: header.wall_seconds,
            start: Instant::now(),
            last: Instant::now(),
        }));
    }
    if let Some(limit) = watch.limit {
        hooks.push(Box::new(limit));
    }
    let start = Instant::now();
    let result = sim.run_with(|s| hooks.iter_mut().try_for_each(|h| h.after_step(s)));
    drop(hooks);
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
