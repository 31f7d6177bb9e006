//! Throughput: particle-steps per second of whole explicit steps.
//!
//! The 3D elastic block of `scenes/block_*.ron` (as the Taichi peer's presets) at about 10k,
//! 100k and 1M points on 1 and 2 threads, and the 2D slope. Prints a table and the
//! per-system split. Each rate is the best of three rounds, the thread counts (and the
//! variants of the 100k block) alternating.
//! `cargo bench -p kdmpm-bench --bench throughput` (add `-- 10k` to run one size).
//!
//! The 100k block is also run in a grid with ten times as many nodes (50 × 50 × 54 cells
//! instead of 23 × 23 × 25): only the nodes the points reach should cost time, so the
//! per-step cost should stay within 1.2×.
//!
//! And the 100k block with its points stored in random order (as after a flow has mixed
//! them), left so (`sort_every = 0`) and after one spatial sort: what cell order is worth.

use kdmpm::components::Position;
use kdmpm::infra::columns::{col_mut, points_with};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::systems::SpatialSort;
use kdmpm::{with_simulation, Dim, Simulation, System};
use std::path::Path;
use std::time::Instant;

/// As the `kdmpm` binary: large blocks coloured (see `kdmpm::infra::alloc`).
#[global_allocator]
static ALLOCATOR: kdmpm::infra::alloc::Coloured = kdmpm::infra::alloc::Coloured;

/// How the points are stored when the timing starts.
#[derive(Clone, Copy, PartialEq)]
enum Order {
    /// As set-up left them: cell order, body by body.
    AsBuilt,
    /// Shuffled, and never sorted.
    Mixed,
    /// Shuffled, then sorted once.
    MixedThenSorted,
}

/// Stores the points in a random order. The blocks' points differ only in position at the
/// start (same mass, volume, material, zero velocity and stress), so shuffling the
/// positions alone relabels them without changing the problem.
fn shuffle<D: Dim>(sim: &mut Simulation<D>) {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for arch in points_with::<Position<D::Vec>>(&sim.ctx.world) {
        let mut x = col_mut::<Position<D::Vec>>(arch);
        for i in (1..x.len()).rev() {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            x.swap(i, (state >> 33) as usize % (i + 1));
        }
    }
}

/// Times steps until `min_seconds` have passed; returns particle-steps per second.
fn measure<D: Dim>(sim: &mut Simulation<D>, min_seconds: f64) -> f64 {
    let start = Instant::now();
    let mut steps = 0;
    while start.elapsed().as_secs_f64() < min_seconds || steps < 3 {
        sim.step().expect("step");
        steps += 1;
    }
    sim.point_count() as f64 * steps as f64 / start.elapsed().as_secs_f64()
}

/// Timed rounds per case. The 1- and 2-thread runs alternate round by round and each keeps
/// its best round: on a shared machine a slow round is disturbance, not the code, and
/// alternating exposes both thread counts to the same spells of it.
const ROUNDS: usize = 3;

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

/// One scene as timed: its file, its label, overrides and the order of its points.
struct Variant {
    file: &'static str,
    label: &'static str,
    overrides: &'static [&'static str],
    order: Order,
}

/// Builds `variant` for a pool of `threads` threads, shuffled or sorted as asked, and warms
/// it up with three steps.
fn prepare(variant: &Variant, threads: usize) -> (rayon::ThreadPool, kdmpm::AnySimulation) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    // This package is benches/ in the kdmpm checkout: scenes are one level up.
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenes")
        .join(variant.file);
    let mut o = vec!["solver.max_steps=1000000000".to_string()];
    o.extend(variant.overrides.iter().map(|s| s.to_string()));
    let loaded = LoadedScene::from_file(&path, &o).unwrap();
    let (mut any, _) = build(&loaded).unwrap();
    let order = variant.order;
    pool.install(|| {
        with_simulation!(&mut any, sim => {
            if order != Order::AsBuilt {
                shuffle(sim);
            }
            if order == Order::MixedThenSorted {
                SpatialSort::new(1).run(&mut sim.ctx).expect("sort");
            }
            for _ in 0..3 {
                sim.step().expect("warm-up step");
            }
        })
    });
    (pool, any)
}

fn main() {
    let per_call = timing_cost();
    println!("timing one system call costs {:.1} ns", per_call * 1e9);
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let variant = |file, label, overrides, order| Variant {
        file,
        label,
        overrides,
        order,
    };
    let unsorted: &[&str] = &["solver.sort_every=0"];
    // Variants of one group are timed in the same rounds, so the later ones' cost relative
    // to the first is measured through the same spells of disturbance.
    let groups: Vec<(f64, Vec<Variant>)> = vec![
        (
            2.0,
            vec![variant("block_10k.ron", "3D block 10k", &[], Order::AsBuilt)],
        ),
        (
            3.0,
            vec![
                variant("block_100k.ron", "3D block 100k", &[], Order::AsBuilt),
                variant(
                    "block_100k.ron",
                    "  in 10× grid",
                    &["grid.cells=[50, 50, 54]"],
                    Order::AsBuilt,
                ),
                variant("block_100k.ron", "  mixed", unsorted, Order::Mixed),
                variant(
                    "block_100k.ron",
                    "  mixed, sorted",
                    unsorted,
                    Order::MixedThenSorted,
                ),
            ],
        ),
        (
            6.0,
            vec![variant("block_1m.ron", "3D block 1M", &[], Order::AsBuilt)],
        ),
        (3.0, vec![variant("slope.ron", "2D slope", &[], Order::AsBuilt)]),
    ];
    println!(
        "{:<16} {:>9} {:>8} {:>14} {:>9}",
        "case", "points", "threads", "M pt-steps/s", "speed-up"
    );
    for (seconds, variants) in groups {
        if filter
            .as_ref()
            .is_some_and(|f| !variants[0].file.contains(f.as_str()))
        {
            continue;
        }
        // (variant, threads, pool, simulation, best rate), 1 and 2 threads side by side.
        let mut runs: Vec<_> = variants
            .iter()
            .enumerate()
            .flat_map(|(v, variant)| {
                [1, 2].map(|threads| {
                    let (pool, any) = prepare(variant, threads);
                    (v, threads, pool, any, 0.0f64)
                })
            })
            .collect();
        for _ in 0..ROUNDS {
            for (_, _, pool, any, best) in runs.iter_mut() {
                let rate = pool
                    .install(|| with_simulation!(&mut *any, sim => measure(sim, seconds / ROUNDS as f64)));
                *best = best.max(rate);
            }
        }
        // The first variant's rates on 1 and 2 threads, to compare the others with.
        let reference = [runs[0].4, runs[1].4];
        for pair in runs.chunks(2) {
            let single = pair[0].4;
            for (v, threads, _, any, rate) in pair {
                let (v, threads, rate) = (*v, *threads, *rate);
                let label = variants[v].label;
                let (points, split) =
                    with_simulation!(any, sim => (sim.point_count(), sim.schedule.timings()));
                println!(
                    "{label:<16} {points:>9} {threads:>8} {:>14.2} {:>8.2}×",
                    rate / 1e6,
                    rate / single
                );
                if v > 0 {
                    println!(
                        "{:<16} per-step cost: {:.2}× the {}'s on {threads} thread{}, same rounds",
                        "",
                        reference[threads - 1] / rate,
                        variants[0].label.trim(),
                        if threads == 1 { "" } else { "s" }
                    );
                }
                if threads == 1 {
                    continue;
                }
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
