//! Throughput: particle-steps per second of whole explicit steps.
//!
//! The 3D elastic block of `scenes/block_*.ron` (as the Taichi peer's presets) at about 10k,
//! 100k and 1M points on 1 and 2 threads, and the 2D slope. Prints a table and the
//! per-system split. `cargo bench --bench throughput` (add `-- 10k` to run one size).
//!
//! The 100k block is also run in a grid with ten times as many nodes (50 × 50 × 54 cells
//! instead of 23 × 23 × 25): only the nodes the points reach should cost time, so the
//! per-step cost should stay within 1.2× (issue #5).

use kdmpm::scene::{build, LoadedScene};
use kdmpm::{with_simulation, Dim, Simulation};
use std::path::Path;
use std::time::Instant;

/// Times steps until `min_seconds` have passed (after a short warm-up).
fn measure<D: Dim>(sim: &mut Simulation<D>, min_seconds: f64) -> (f64, u64) {
    for _ in 0..3 {
        sim.step().expect("warm-up step");
    }
    let start = Instant::now();
    let mut steps = 0;
    while start.elapsed().as_secs_f64() < min_seconds || steps < 3 {
        sim.step().expect("step");
        steps += 1;
    }
    let wall = start.elapsed().as_secs_f64();
    (sim.point_count() as f64 * steps as f64 / wall, steps)
}

/// Cost of timing one system call: two clock reads and the bookkeeping (s).
fn timing_cost() -> f64 {
    let n = 1_000_000;
    let mut total = std::time::Duration::ZERO;
    let start = Instant::now();
    for _ in 0..n {
        let t = Instant::now();
        total += std::hint::black_box(t).elapsed();
    }
    std::hint::black_box(total);
    start.elapsed().as_secs_f64() / n as f64
}

fn main() {
    let per_call = timing_cost();
    println!("timing one system call costs {:.1} ns", per_call * 1e9);
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let big_grid: &[&str] = &["grid.cells=[50, 50, 54]"];
    let cases: [(&str, &str, f64, &[&str]); 5] = [
        ("block_10k.ron", "3D block 10k", 2.0, &[]),
        ("block_100k.ron", "3D block 100k", 3.0, &[]),
        ("block_100k.ron", "  in 10× grid", 3.0, big_grid),
        ("block_1m.ron", "3D block 1M", 6.0, &[]),
        ("slope.ron", "2D slope", 3.0, &[]),
    ];
    // 2-thread rate of the 100k block in its own grid, to compare the 10× grid with.
    let mut block_100k = None;
    println!(
        "{:<16} {:>9} {:>8} {:>14} {:>9}",
        "case", "points", "threads", "M pt-steps/s", "speed-up"
    );
    for (file, label, seconds, overrides) in cases {
        if filter.as_ref().is_some_and(|f| !file.contains(f.as_str())) {
            continue;
        }
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(file);
        let mut single = 0.0;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut o = vec!["solver.max_steps=1000000000".to_string()];
            o.extend(overrides.iter().map(|s| s.to_string()));
            let loaded = LoadedScene::from_file(&path, &o).unwrap();
            let (mut any, _) = build(&loaded).unwrap();
            let (rate, points, split) = pool.install(|| {
                with_simulation!(&mut any, sim => {
                    let (rate, _) = measure(sim, seconds);
                    (rate, sim.point_count(), sim.schedule.timings())
                })
            });
            if threads == 1 {
                single = rate;
            }
            println!(
                "{label:<16} {points:>9} {threads:>8} {:>14.2} {:>8.2}×",
                rate / 1e6,
                rate / single
            );
            if threads == 2 && file == "block_100k.ron" {
                match block_100k {
                    None => block_100k = Some(rate),
                    Some(own) => println!(
                        "{:<16} per-step cost in the 10× grid: {:.2}× its own grid's",
                        "",
                        own / rate
                    ),
                }
            }
            if threads == 2 {
                let total: f64 = split.iter().map(|t| t.seconds).sum();
                let calls: u64 = split.iter().map(|t| t.calls).sum();
                println!(
                    "{:<16} timing overhead: {:.3}% of the step",
                    "",
                    100.0 * per_call * calls as f64 / total
                );
                let parts: Vec<String> = split
                    .iter()
                    .filter(|t| t.seconds / total > 0.01)
                    .map(|t| format!("{} {:.0}%", t.name, 100.0 * t.seconds / total))
                    .collect();
                println!("{:<16} split: {}", "", parts.join(", "));
            }
        }
    }
}
