//! Inserting your own system into a schedule.
//!
//! Loads the paper's elastic bar, adds a probe right after `g2p` that records the largest
//! point speed of each step, runs to convergence and prints the probe's record.
//!
//!     cargo run --release --example custom_system

use kdmpm::components::Velocity;
use kdmpm::infra::columns::{col, points_with};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Context, Dim3, FnSystem, StepError};
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Builds the bar with a max-speed probe after `g2p`; returns it with the probe's record.
pub fn bar_with_probe() -> (kdmpm::Simulation<Dim3>, Arc<Mutex<Vec<f64>>>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
    let loaded = LoadedScene::from_file(&path, &[]).expect("bar.ron loads");
    let AnySimulation::Three(mut sim) = build(&loaded).expect("bar.ron builds").0 else {
        unreachable!("bar.ron is 3D")
    };
    let record = Arc::new(Mutex::new(Vec::new()));
    let sink = Arc::clone(&record);
    let probe = FnSystem::new(
        "max_speed_probe",
        move |ctx: &mut Context<Dim3>| -> Result<(), StepError> {
            let mut max = 0.0f64;
            for arch in points_with::<Velocity<glam::DVec3>>(&ctx.world) {
                for v in col::<Velocity<glam::DVec3>>(arch).iter() {
                    max = max.max(v.0.dot(v.0).sqrt());
                }
            }
            sink.lock().expect("probe record").push(max);
            Ok(())
        },
    );
    assert!(
        sim.schedule.insert_after("g2p", probe),
        "the bar's schedule has g2p"
    );
    (sim, record)
}

fn main() {
    let (mut sim, record) = bar_with_probe();
    sim.run(|_| {}).expect("the bar runs");
    let speeds = record.lock().expect("probe record");
    let (step, peak) = speeds
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |m, (i, &v)| if v > m.1 { (i, v) } else { m });
    println!("schedule: {}", sim.schedule.names().join(" → "));
    println!(
        "{} steps recorded; fastest point {peak:.3e} at step {}",
        speeds.len(),
        step + 1
    );
    for t in sim.schedule.timings() {
        println!("{:<18} {:>6} calls {:>10.6} s", t.name, t.calls, t.seconds);
    }
}
