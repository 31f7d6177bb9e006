//! The files `kdmpm run` writes, from Rust: history.csv, the ParaView series
//! (points.pvd and snapshots/), points.vtu and summary.json.
//!
//! Loads the paper's elastic bar with a snapshot at every kinetic-damping reset and runs it
//! to convergence into a directory with the library's runner, as `kdmpm run` does.
//!
//!     cargo run --release --example write_results [OUT_DIR]

use kdmpm::run::Run;
use kdmpm::scene::LoadedScene;
use std::path::{Path, PathBuf};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out: PathBuf = std::env::args()
        .nth(1)
        .map_or("out/write_results".into(), PathBuf::from);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
    // The override goes into the scene's text, which a checkpoint keeps.
    let loaded = LoadedScene::from_file(&scene, &["output.snapshots=(at_resets: true)".into()])?;
    // The output directory is locked for this process while it writes.
    let report = Run::scene(loaded).into_dir(&out).quiet(true).go()?;
    if let Some(e) = report.error {
        return Err(e.into());
    }
    println!(
        "{:?} after {} steps; {} snapshots; files in {}",
        report.summary.outcome,
        report.summary.steps,
        report.summary.snapshots.unwrap_or(0),
        out.display()
    );
    Ok(())
}
