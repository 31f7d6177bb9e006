//! Helpers shared by the integration tests: run a scene file with overrides, in memory.
#![allow(dead_code)]

use kdmpm::output::Summary;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::with_simulation;
use std::path::Path;

/// Path of a scene shipped in `scenes/`.
pub fn scene(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Runs `name` with `overrides` to its stop and returns the summary (no files written).
pub fn run(name: &str, overrides: &[&str]) -> Summary {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_file(&scene(name), &overrides).expect("scene loads");
    let (mut sim, _) = build(&loaded).expect("scene builds");
    with_simulation!(&mut sim, s => {
        let start = std::time::Instant::now();
        let result = s.run(|_| {});
        Summary::collect(name, s, start.elapsed().as_secs_f64(), result.err().map(|e| e.to_string()))
    })
}

/// Relative difference a/b − 1.
pub fn rel(a: f64, b: f64) -> f64 {
    a / b - 1.0
}
