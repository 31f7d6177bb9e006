//! The `history` output system: one CSV row per output interval.

use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::model::Drive;
use crate::output::dir::RowFile;
use crate::schedule::System;
use crate::simulation::{traced_values, TracedPoint};
use crate::systems::convergence::ratio_cell;
use std::marker::PhantomData;
use std::path::Path;
use std::sync::{Arc, Mutex, MutexGuard};

/// Writes step, time, E_k (J), W_ext (J), K_F (max and mean norm), K_E, resets, each
/// traced point's displacement (m) and each prescribed motion's travel (m) and reaction
/// (N; N/m in 2D) every `every` steps and at the last step. A ratio whose
/// denominator is zero is an empty cell.
///
/// The file only ever holds whole rows ([`RowFile`]): a run stopped by an error, a crash or
/// a full disk leaves a valid file with every row that reached it. The row file is shared
/// ([`History::rows`]) so that a checkpoint can flush it and note its length.
pub struct History<D> {
    rows: Arc<Mutex<RowFile>>,
    every: u64,
    traced: Vec<TracedPoint>,
    _marker: PhantomData<fn() -> D>,
}

/// The column names of `history.csv` for these traced points and motions.
fn header<D: Dim>(traced: &[TracedPoint], drives: &[Drive]) -> Vec<String> {
    let mut header: Vec<String> = [
        "step",
        "time",
        "kinetic_energy",
        "external_work",
        "force_ratio_max",
        "force_ratio_mean",
        "energy_ratio",
        "resets",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for t in traced {
        for axis in ["x", "y", "z"].iter().take(D::N) {
            header.push(format!("{}_u{axis}", t.name));
        }
    }
    for d in drives {
        header.push(format!("{}_travel", d.name));
        for axis in ["x", "y", "z"].iter().take(D::N) {
            header.push(format!("{}_force_{axis}", d.name));
        }
    }
    header
}

/// One CSV line: fields quoted where they hold a comma, quote or line break.
fn line(fields: &[String]) -> Vec<u8> {
    let quoted: Vec<String> = fields
        .iter()
        .map(|f| {
            if f.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", f.replace('"', "\"\""))
            } else {
                f.clone()
            }
        })
        .collect();
    format!("{}\n", quoted.join(",")).into_bytes()
}

impl<D: Dim> History<D> {
    /// Creates `path` and writes the header.
    pub fn create(
        path: &Path,
        every: u64,
        traced: &[TracedPoint],
        drives: &[Drive],
    ) -> std::io::Result<Self> {
        let mut rows = RowFile::create(path)?;
        rows.row(&line(&header::<D>(traced, drives)))?;
        rows.flush()?;
        Ok(Self::with(rows, every, traced))
    }

    /// Continues `path` after its first `bytes` bytes (a checkpoint's length of it).
    pub fn resume(
        path: &Path,
        mark: (u64, u32),
        every: u64,
        traced: &[TracedPoint],
    ) -> std::io::Result<Self> {
        Ok(Self::with(RowFile::resume(path, mark.0, mark.1)?, every, traced))
    }

    fn with(rows: RowFile, every: u64, traced: &[TracedPoint]) -> Self {
        History {
            rows: Arc::new(Mutex::new(rows)),
            every,
            traced: traced.to_vec(),
            _marker: PhantomData,
        }
    }

    /// The row file, shared: flush it and read its length to checkpoint.
    pub fn rows(&self) -> Arc<Mutex<RowFile>> {
        self.rows.clone()
    }
}

/// Locks a row file (a panic elsewhere while holding it leaves whole rows all the same).
pub fn lock(rows: &Mutex<RowFile>) -> MutexGuard<'_, RowFile> {
    rows.lock().unwrap_or_else(|e| e.into_inner())
}

impl<D: Dim> System<D> for History<D> {
    fn name(&self) -> &str {
        "history"
    }
    /// Rank 0's alone over MPI ranks.
    fn on_every_rank(&self) -> bool {
        false
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let s = &ctx.state;
        let last = s.stop.is_some();
        if !s.clock.step.is_multiple_of(self.every) && !last {
            return Ok(());
        }
        let mut row = vec![
            s.clock.step.to_string(),
            format!("{:.9e}", s.clock.time),
            format!("{:.9e}", s.energy.current()),
            format!("{:.9e}", s.convergence.external_work),
            ratio_cell(s.convergence.force_ratio_max, 9),
            ratio_cell(s.convergence.force_ratio_mean, 9),
            ratio_cell(s.convergence.energy_ratio, 9),
            s.resets.count.to_string(),
        ];
        for (k, t) in self.traced.iter().enumerate() {
            // Over MPI the point may be on another rank: [`TracedGather`] brought it here.
            // With one rank, a handful of traced points: an entity lookup is fine here.
            let u = match ctx.state.ranks.traced_displacements.get(k) {
                Some(u) => *u,
                None => t.displacement::<D>(&ctx.world),
            };
            row.extend(u.iter().take(D::N).map(|c| format!("{c:.9e}")));
        }
        for d in &s.control.drives {
            row.push(format!("{:.9e}", d.travel));
            row.extend(d.reaction.iter().take(D::N).map(|c| format!("{c:.9e}")));
        }
        let mut rows = lock(&self.rows);
        rows.row(&line(&row))?;
        if last {
            rows.flush()?;
        }
        Ok(())
    }
}

/// Over MPI, gathers the traced points' displacements from the ranks that hold them into
/// [`crate::state::RankCounters::traced_displacements`] each step, on every rank, for
/// [`History`] to write on rank 0. Runs on every rank, before `history`.
pub struct TracedGather {
    traced: Vec<TracedPoint>,
}

impl TracedGather {
    /// Gathers these points.
    pub fn new(traced: &[TracedPoint]) -> Self {
        TracedGather {
            traced: traced.to_vec(),
        }
    }
}

impl<D: Dim> System<D> for TracedGather {
    fn name(&self) -> &str {
        "traced_gather"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let values = traced_values(ctx, &mut self.traced);
        ctx.state.ranks.traced_displacements = values.into_iter().map(|(u, _)| u).collect();
        Ok(())
    }
}

impl<D> Drop for History<D> {
    fn drop(&mut self) {
        // Rows of a run that ended without a last step (an error) still reach the file.
        let _ = lock(&self.rows).flush();
    }
}
