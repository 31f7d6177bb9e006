//! A run resumed from a checkpoint gives the bits of the run that never stopped: the same
//! point columns row by row and the same solver state in memory, and the same points.vtu,
//! history.csv and summary.json numbers on disk, for 1 and 2 threads, from any step —
//! the first, one inside the static-check window, the step before and the step of a
//! kinetic-energy reset — and after Ctrl-C.

use crate::common;

use kdmpm::checkpoint::{self, Header};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Dim, Dim2, Dim3, Simulation};
use std::path::{Path, PathBuf};
use std::process::Command;

fn load(name: &str, overrides: &[&str]) -> LoadedScene {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    LoadedScene::from_file(&common::scene(name), &overrides).expect("scene loads")
}

/// The simulation of dimension `D` that `loaded` builds.
fn sim<D: Dim>(loaded: &LoadedScene) -> Simulation<D> {
    let any: Box<dyn std::any::Any> = match build(loaded).unwrap().0 {
        AnySimulation::Two(s) => Box::new(s),
        AnySimulation::Three(s) => Box::new(s),
        AnySimulation::Axi(s) => Box::new(s),
    };
    *any.downcast().expect("the scene's dimension")
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// The whole state as checkpoint bytes (a fixed header): equal bytes, equal bits.
fn bits<D: Dim>(sim: &Simulation<D>) -> Vec<u8> {
    let header = Header {
        scene_path: PathBuf::new(),
        scene_text: String::new(),
        ..Header::default()
    };
    checkpoint::encode(sim, &header)
}

/// Steps taken, steps with a reset, steps inside a static-check window, and final bits.
struct Reference {
    steps: u64,
    resets: Vec<u64>,
    in_window: Vec<u64>,
    end: Vec<u8>,
}

fn reference<D: Dim>(sim: &mut Simulation<D>) -> Reference {
    let (mut resets, mut in_window) = (Vec::new(), Vec::new());
    sim.run(|s| {
        if s.resets.this_step {
            resets.push(s.clock.step);
        }
        if s.static_window.start.is_some() {
            in_window.push(s.clock.step);
        }
    })
    .unwrap();
    Reference {
        steps: sim.ctx.state.clock.step,
        resets,
        in_window,
        end: bits(sim),
    }
}

/// Checkpoints `loaded` after `k` steps on `before` threads, restores it into a freshly
/// built simulation and finishes it on `after` threads; returns the final bits.
fn resumed<D: Dim>(loaded: &LoadedScene, k: u64, before: usize, after: usize) -> Vec<u8> {
    let header = Header {
        scene_path: loaded.path.clone(),
        scene_text: loaded.text.clone(),
        ..Header::default()
    };
    let mut first = sim::<D>(loaded);
    let saved = pool(before).install(|| {
        for _ in 0..k {
            first.step().unwrap();
        }
        checkpoint::encode(&first, &header)
    });
    let mut second = sim::<D>(loaded);
    let read = checkpoint::restore(&mut second, &saved, Path::new("memory")).unwrap();
    assert_eq!(read, header);
    pool(after).install(|| second.run(|_| {}).unwrap());
    bits(&second)
}

/// Checks resumption of `loaded` at the first step, the step before and the step of a
/// reset, and a step inside the static-check window (when it has one), both ways round in
/// thread count.
fn resumes_bit_for_bit<D: Dim>(loaded: &LoadedScene, window: bool) {
    let mut whole = sim::<D>(loaded);
    let r = pool(2).install(|| reference(&mut whole));
    let reset = *r
        .resets
        .get(1)
        .expect("the run resets its velocities at least twice");
    let mut at = vec![1, reset - 1, reset];
    if window {
        let inside = r.in_window.get(r.in_window.len() / 2).copied();
        at.push(inside.expect("the run opens a static-check window"));
    }
    for k in at {
        assert!(k < r.steps, "checkpoint step {k} before the end {}", r.steps);
        for (before, after) in [(1, 2), (2, 1)] {
            assert!(
                resumed::<D>(loaded, k, before, after) == r.end,
                "resumed at step {k} ({before} → {after} threads) differs from the run that never stopped"
            );
        }
    }
}

#[test]
fn the_bar_resumed_at_any_step_has_the_bits_of_the_run_that_never_stopped() {
    resumes_bit_for_bit::<Dim3>(&load("bar.ron", &[]), false);
}

#[test]
fn a_run_resumed_inside_its_static_check_window_has_the_bits_of_the_run_that_never_stopped() {
    let loaded = load(
        "soil_column.ron",
        &["solver.static_check=(window: 0.3, max_displacement: 1e-4)"],
    );
    resumes_bit_for_bit::<Dim2>(&loaded, true);
}

/// A rigid footing pushed into clay (`scenes/footing_rigid.ron`, its first three
/// increments), checkpointed half way through its travel (inside an increment) and at the
/// first reset after that: the resumed run ends with the same bits, the body's place,
/// reaction and the contact's warm-start impulses included.
#[test]
fn a_body_resumed_mid_penetration_has_the_bits_of_the_run_that_never_stopped() {
    let loaded = load("footing_rigid.ron", &["rigid_bodies[0].motion.travel=0.03"]);
    let mut whole = sim::<Dim2>(&loaded);
    let r = pool(2).install(|| reference(&mut whole));
    let half = r.steps / 2;
    let reset = *r
        .resets
        .iter()
        .find(|&&k| k > half)
        .expect("a reset after half way");
    for (k, before, after) in [(half, 1, 2), (reset, 2, 1)] {
        assert!(
            resumed::<Dim2>(&loaded, k, before, after) == r.end,
            "resumed at step {k} ({before} → {after} threads) differs from the run that never stopped"
        );
    }
}

#[test]
fn a_checkpoint_of_another_scene_is_refused() {
    let mut column = sim::<Dim2>(&load("soil_column.ron", &[]));
    column.step().unwrap();
    let saved = bits(&column);
    let mut other = sim::<Dim2>(&load("slope.ron", &[]));
    let e = checkpoint::restore(&mut other, &saved, Path::new("c")).unwrap_err();
    assert!(e.to_string().contains("differs"), "{e}");
    let e = checkpoint::restore(&mut other, &saved[..saved.len() / 2], Path::new("c")).unwrap_err();
    assert!(e.to_string().contains("checksum does not match"), "{e}");
    let e = checkpoint::restore(&mut other, b"nonsense", Path::new("c")).unwrap_err();
    assert!(e.to_string().contains("not a kdmpm checkpoint"), "{e}");
}

// ---- The binary: files on disk -------------------------------------------------------

/// Every output of run directory `a` equals that of `b`, snapshot series included.
fn same_results(a: &Path, b: &Path) {
    let mut files = vec!["points.vtu".to_string(), "history.csv".to_string()];
    if a.join("curve.csv").exists() {
        files.push("curve.csv".into());
    }
    if a.join("points.pvd").exists() {
        files.push("points.pvd".into());
        for e in std::fs::read_dir(a.join("snapshots")).unwrap().flatten() {
            files.push(format!("snapshots/{}", e.file_name().to_string_lossy()));
        }
        let count = |d: &Path| std::fs::read_dir(d.join("snapshots")).unwrap().count();
        assert_eq!(count(a), count(b), "snapshot files");
    }
    for file in &files {
        let (x, y) = (
            std::fs::read(a.join(file)).unwrap(),
            std::fs::read(b.join(file)).unwrap(),
        );
        assert!(
            x == y,
            "{file} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    assert_eq!(common::summary_numbers(a), common::summary_numbers(b));
}

/// Runs `scene` to its end on 2 threads with checkpoints every `every` steps, keeps its
/// results, resumes from the last checkpoint on 1 thread and compares.
fn resume_from_last_checkpoint(scene: &str, every: u64, sets: &[&str]) {
    let dir = common::scratch("resume", scene);
    let out = dir.join("run");
    let path = common::scene(scene);
    let checkpoint = format!("solver.checkpoint_every=Steps({every})");
    let mut args = vec![
        "run",
        path.to_str().unwrap(),
        "--quiet",
        "--threads",
        "2",
        "--out",
    ];
    args.push(out.to_str().unwrap());
    for s in sets.iter().chain([&checkpoint.as_str()]) {
        args.extend(["--set", s]);
    }
    let o = common::kdmpm(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full = dir.join("full");
    common::copy_dir(&out, &full);
    let o = common::kdmpm(&["resume", out.to_str().unwrap(), "--quiet", "--threads", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_results(&out, &full);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_bar_resumed_by_the_binary_writes_the_same_files() {
    resume_from_last_checkpoint("bar.ron", 300, &[]);
}

#[test]
fn a_3d_block_resumed_by_the_binary_writes_the_same_files() {
    // It converges after 92 steps: the last checkpoint is at step 80.
    resume_from_last_checkpoint("block_10k.ron", 40, &[]);
}

/// The strip pressure under load control, checkpointed in its seventh increment.
#[test]
fn a_load_controlled_run_resumed_between_increments_writes_the_same_curve() {
    resume_from_last_checkpoint("footing_load.ron", 2_000, &[]);
}

/// The bar in two load stages, checkpointed in the second.
#[test]
fn a_staged_run_resumed_in_its_second_stage_writes_the_same_files() {
    let stages = r#"stages=[(name: "first"), (name: "doubled", point_loads: {"F": [0.002, 0.0, 0.0]})]"#;
    resume_from_last_checkpoint("bar.ron", 2_000, &[stages]);
}

/// The drained drawdown (scenes/slope_drawdown.ron), checkpointed in its second stage (step
/// 2 000 of 2 756): the lowered table comes back with the stage, the points' weights with
/// the points.
#[test]
fn a_drawdown_resumed_below_its_lowered_table_writes_the_same_files() {
    resume_from_last_checkpoint("slope_drawdown.ron", 2_000, &[]);
}

/// The footing, checkpointed in its sixth increment (step 5 000 of 7 753): the motion's
/// travel, its hold and the curve so far come back with the points.
#[test]
fn the_footing_resumed_in_the_middle_of_an_increment_writes_the_same_curve() {
    resume_from_last_checkpoint("footing.ron", 5_000, &[]);
}

/// The rigid footing, checkpointed mid-penetration (step 5 000 of 8 344): the body's place,
/// travel, hold and forces come back with the points, and its surface is sampled again.
#[test]
fn a_rigid_body_resumed_mid_penetration_writes_the_same_curve() {
    resume_from_last_checkpoint("footing_rigid.ron", 5_000, &[]);
}

/// The circular footing (axisymmetric), checkpointed in its sixth increment.
#[test]
fn an_axisymmetric_footing_resumed_in_an_increment_writes_the_same_curve() {
    resume_from_last_checkpoint("footing_circular.ron", 5_000, &[]);
}

/// The paper's slope (the fast preset, whose static check window the run ends in),
/// on `common::COARSE_SLOPE`'s grid, checkpointed in the middle of its run (step 1 500 of
/// 2 500).
#[test]
fn the_slope_resumed_from_the_middle_of_its_run_writes_the_same_files() {
    resume_from_last_checkpoint("slope_fast.ron", 1_500, &common::COARSE_SLOPE);
}

#[test]
fn ctrl_c_checkpoints_and_a_resumed_run_writes_the_files_of_one_never_interrupted() {
    let dir = common::scratch("resume", "ctrl-c");
    let path = common::scene("slope.ron");
    let scene = path.to_str().unwrap();
    let (whole, cut) = (dir.join("whole"), dir.join("cut"));
    let mut sets = vec!["--set", "solver.max_steps=2000"];
    for s in &common::COARSE_SLOPE {
        sets.extend(["--set", s]);
    }
    let mut args = vec!["run", scene, "--quiet", "--out", whole.to_str().unwrap()];
    args.extend(&sets);
    let o = common::kdmpm(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let child = Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args(["run", scene, "--quiet", "--threads", "1"])
        .args(&sets)
        .arg("--out")
        .arg(&cut)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupt once the run is under way (its history has rows beyond the header).
    common::interrupt(child, &cut, "INT");
    let summary = common::summary_numbers(&cut);
    assert_eq!(summary["outcome"], "interrupted");
    assert!(summary["steps"].as_u64().unwrap() < 2000);
    assert!(cut.join("checkpoint.kdc").exists());
    let o = common::kdmpm(&["resume", cut.to_str().unwrap(), "--quiet", "--threads", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_results(&cut, &whole);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_new_run_into_a_directory_drops_the_checkpoint_of_the_run_before() {
    let dir = common::scratch("resume", "stale");
    let out = dir.join("out");
    let (bar, column) = (common::scene("bar.ron"), common::scene("soil_column.ron"));
    let run = |scene: &Path, sets: &[&str]| {
        let o = common::run_into(scene, &out, sets);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&bar, &["solver.checkpoint_every=Steps(300)"]);
    assert!(out.join("checkpoint.kdc").exists());
    run(&column, &[]);
    assert!(
        !out.join("checkpoint.kdc").exists(),
        "the bar's checkpoint outlived its run"
    );
    let o = common::kdmpm(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The rigid footing under load control, checkpointed in its ninth increment (step 1 500
/// of 2 151): the body's load, velocity and settlement come back with the points.
#[test]
fn a_rigid_body_under_load_control_resumed_mid_increment_writes_the_same_curve() {
    resume_from_last_checkpoint("footing_rigid_load.ron", 1_500, &[]);
}
