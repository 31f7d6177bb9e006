//! What the runner does between steps, one small hook each: the caller's observer, progress
//! on stderr, the stop request, checkpoints, and the displacement limit of a
//! strength-reduction trial. Each sees the whole simulation after every step and may end
//! the run by setting `ctx.state.stop`.

use crate::checkpoint;
use crate::dim::Dim;
use crate::error::StepError;
use crate::interrupt::StopSignal;
use crate::measure::max_displacements;
use crate::output::dir::write_atomic;
use crate::output::{history, Progress, RowFile};
use crate::scene::CheckpointEvery;
use crate::simulation::Simulation;
use crate::state::StopReason;
use std::io::Write;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Called after every step, in the order the runner holds them.
pub(crate) trait Hook<D: Dim> {
    /// Looks at (and may stop) the simulation after a step.
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError>;

    /// The run has ended (by its stop or an error).
    fn finish(&mut self) {}
}

/// The caller's observer ([`super::Run::observe`]).
pub(crate) struct Observer<'a>(pub super::ObserveFn<'a>);

impl<D: Dim> Hook<D> for Observer<'_> {
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError> {
        (self.0)(&sim.ctx.state);
        Ok(())
    }
}

/// Progress on stderr ([`Progress`]).
pub(crate) struct ShowProgress(pub Progress);

impl<D: Dim> Hook<D> for ShowProgress {
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError> {
        self.0.update(&sim.ctx.state);
        Ok(())
    }

    fn finish(&mut self) {
        self.0.finish();
    }
}

/// Ends the run as `Interrupted` once its [`StopSignal`] is raised.
pub(crate) struct StopOnRequest(pub StopSignal);

impl<D: Dim> Hook<D> for StopOnRequest {
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError> {
        // Over several ranks every rank stops after the same step, the first after any
        // rank's signal came (a collective).
        if sim.ctx.state.stop.is_none() && sim.ctx.comm.any(self.0.requested()) {
            sim.ctx.state.stop = Some(StopReason::Interrupted);
        }
        Ok(())
    }
}

/// Writes `checkpoint.kdc` at the scene's cadence and when the run is interrupted (it runs
/// after [`StopOnRequest`]). The history is flushed first, and its committed length and
/// CRC-32 go into the header, so that a resumed run continues exactly that history. Over
/// several ranks every rank holds one, rank 0 the history's rows, and each checkpoint is
/// the ranks' parts and rank 0's manifest ([`checkpoint::parts`]), taken after the same step.
pub(crate) struct Checkpoints {
    pub dir: PathBuf,
    pub every: Option<CheckpointEvery>,
    pub header: checkpoint::Header,
    /// The history's rows (rank 0's; none on the other ranks).
    pub rows: Option<Arc<Mutex<RowFile>>>,
    /// Wall seconds of the run before this invocation (a resumed run's).
    pub before: f64,
    pub start: Instant,
    pub last: Instant,
}

impl<D: Dim> Hook<D> for Checkpoints {
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError> {
        let (st, comm) = (&sim.ctx.state, &sim.ctx.comm);
        let interrupted = st.stop == Some(StopReason::Interrupted);
        let due = st.stop.is_none()
            && match self.every {
                Some(CheckpointEvery::Steps(n)) => st.clock.step.is_multiple_of(n),
                // Each rank's clock, and any rank's decides (a collective).
                Some(CheckpointEvery::Seconds(t)) => comm.any(self.last.elapsed().as_secs_f64() >= t),
                None => false,
            };
        if !(interrupted || due) {
            return Ok(());
        }
        self.last = Instant::now();
        if let Some(rows) = &self.rows {
            let mut rows = history::lock(rows);
            rows.flush()?;
            self.header.history_bytes = rows.committed();
            self.header.history_crc = rows.committed_crc();
        }
        self.header.wall_seconds = self.before + self.start.elapsed().as_secs_f64();
        if comm.size() > 1 {
            checkpoint::parts::write(sim, &self.header, &self.dir)?;
        } else {
            let bytes = checkpoint::encode(sim, &self.header);
            write_atomic(&self.dir.join(checkpoint::FILE_NAME), |out| out.write_all(&bytes))?;
        }
        Ok(())
    }
}

/// A strength-reduction trial's failure criterion: the run stops as soon as a point has
/// moved farther than `limit` (m), looked at every `every` steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplacementLimit {
    /// Steps between looks (the scan of every point costs about a step).
    pub every: u64,
    /// The largest displacement a standing trial may show (m).
    pub limit: f64,
}

impl<D: Dim> Hook<D> for DisplacementLimit {
    fn after_step(&mut self, sim: &mut Simulation<D>) -> Result<(), StepError> {
        let st = &sim.ctx.state;
        if st.stop.is_none() && st.clock.step.is_multiple_of(self.every) {
            // Over several ranks, the largest of every rank's (each rank looks alike).
            let mut u = [max_displacements(sim).unwrap_or_default().0];
            sim.ctx.comm.max(&mut u);
            if u[0] > self.limit {
                sim.ctx.state.stop = Some(StopReason::DisplacementLimit);
            }
        }
        Ok(())
    }
}
