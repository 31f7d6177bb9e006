//! The files `kdmpm run` writes, from Rust: history.csv, the ParaView series
//! (points.pvd and snapshots/), points.vtu and summary.json.
//!
//! Loads the paper's elastic bar, asks for a snapshot at every kinetic-damping reset,
//! attaches a `Recorder`, runs to convergence and finishes the recorder.
//!
//!     cargo run --release --example write_results [OUT_DIR]

use kdmpm::output::{OutputDir, Recorder, SnapshotSpec};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::with_simulation;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out: PathBuf = std::env::args()
        .nth(1)
        .map_or("out/write_results".into(), PathBuf::from);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
    let loaded = LoadedScene::from_file(&scene, &[])?;
    let (mut sim, _) = build(&loaded)?;
    // The output directory is locked for this process while it writes.
    let dir = OutputDir::claim(&out)?;
    let snapshots = SnapshotSpec {
        at_resets: true,
        ..SnapshotSpec::default()
    };
    let summary = with_simulation!(&mut sim, s => {
        let recorder = Recorder::attach(s, &dir, 10, Some(snapshots), None)?;
        let start = Instant::now();
        let result = s.run(|_| {});
        let error = result.as_ref().err().map(|e| e.to_string());
        let (summary, _notes) =
            recorder.finish(s, &dir, &scene.display().to_string(), start.elapsed().as_secs_f64(), error)?;
        result?;
        summary
    });
    println!(
        "{:?} after {} steps; {} snapshots; files in {}",
        summary.outcome,
        summary.steps,
        summary.snapshots.unwrap_or(0),
        out.display()
    );
    Ok(())
}
