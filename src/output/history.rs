//! The `history` output system: one CSV row per output interval.

use crate::dim::Dim;
use crate::error::StepError;
use crate::schedule::System;
use crate::simulation::{Context, TracedPoint};
use std::fs::File;
use std::io::BufWriter;
use std::marker::PhantomData;
use std::path::Path;

/// Writes step, time, E_k (J), W_ext (J), K_F (max and mean norm), K_E, resets and each
/// traced point's displacement (m) every `every` steps and at the last step.
/// Rows reach the disk whenever the buffer fills and at the end, so a run stopped by an
/// error leaves a valid file with every row before the error.
pub struct History<D> {
    writer: csv::Writer<BufWriter<File>>,
    every: u64,
    traced: Vec<TracedPoint>,
    _marker: PhantomData<fn() -> D>,
}

impl<D: Dim> History<D> {
    /// Creates `path` and writes the header.
    pub fn create(path: &Path, every: u64, traced: &[TracedPoint]) -> std::io::Result<Self> {
        let mut writer = csv::Writer::from_writer(BufWriter::new(File::create(path)?));
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
        writer.write_record(&header).map_err(std::io::Error::other)?;
        Ok(History {
            writer,
            every,
            traced: traced.to_vec(),
            _marker: PhantomData,
        })
    }
}

impl<D: Dim> System<D> for History<D> {
    fn name(&self) -> &str {
        "history"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let s = &ctx.state;
        let last = s.stop.is_some();
        if s.step % self.every != 0 && !last {
            return Ok(());
        }
        let mut row = vec![
            s.step.to_string(),
            format!("{:.9e}", s.time),
            format!("{:.9e}", s.kinetic_energy),
            format!("{:.9e}", s.external_work),
            format!("{:.9e}", s.force_ratio_max),
            format!("{:.9e}", s.force_ratio_mean),
            format!("{:.9e}", s.energy_ratio),
            s.resets.to_string(),
        ];
        for t in &self.traced {
            // A handful of traced points: an entity lookup is fine here.
            let u = t.displacement::<D>(&ctx.world);
            row.extend(u.iter().take(D::N).map(|c| format!("{c:.9e}")));
        }
        self.writer.write_record(&row).map_err(std::io::Error::other)?;
        if last {
            self.writer.flush()?;
        }
        Ok(())
    }
}
