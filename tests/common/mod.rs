//! Helpers shared by the integration tests: run a scene file with overrides, in memory.
#![allow(dead_code)]

use kdmpm::output::Summary;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{with_simulation, AnySimulation, Dim2, Simulation};
use std::path::Path;

/// Path of a scene shipped in `scenes/`.
pub fn scene(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Runs `name` with `overrides` to its stop and returns the summary (no files written).
pub fn run(name: &str, overrides: &[&str]) -> Summary {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_file(&scene(name), &overrides).expect("scene loads");
    run_loaded(name, &loaded)
}

/// Runs the scene `text` (called `name` in messages) to its stop and returns the summary.
pub fn run_text(name: &str, text: &str) -> Summary {
    let loaded = LoadedScene::from_text(Path::new(name), text, &[]).expect("scene loads");
    run_loaded(name, &loaded)
}

/// The error that building the scene `text` gives.
pub fn refusal(text: &str) -> String {
    let loaded = LoadedScene::from_text(Path::new("refused.ron"), text, &[]).expect("scene parses");
    build(&loaded).err().expect("refused").to_string()
}

fn run_loaded(name: &str, loaded: &LoadedScene) -> Summary {
    let (mut sim, _) = build(loaded).expect("scene builds");
    with_simulation!(&mut sim, s => {
        let start = std::time::Instant::now();
        let result = s.run(|_| {});
        Summary::collect(name, s, start.elapsed().as_secs_f64(), result.err().map(|e| e.to_string()))
    })
}

/// Runs the `kdmpm` binary with `args` and waits for it.
pub fn kdmpm(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args(args)
        .output()
        .expect("kdmpm starts")
}

/// Runs `kdmpm run SCENE --quiet --out OUT --set ...` and waits for it.
pub fn run_into(scene: &Path, out: &Path, sets: &[&str]) -> std::process::Output {
    let mut args = vec![
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    for s in sets {
        args.extend(["--set", s]);
    }
    kdmpm(&args)
}

/// Waits until the run writing into `dir` has written rows beyond the header of its
/// history: the run is under way.
pub fn wait_until_running(dir: &Path) {
    let history = dir.join("history.csv");
    while std::fs::read_to_string(&history).map_or(0, |t| t.lines().count()) < 3 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// Sends `signal` (`INT`, `TERM`) to the process `pid`.
pub fn signal(pid: u32, signal: &str) {
    let sent = std::process::Command::new("kill")
        .args([&format!("-{signal}"), &pid.to_string()])
        .status()
        .unwrap();
    assert!(sent.success(), "kill -{signal} {pid}");
}

/// Waits until `child`, a run writing into `dir`, is under way, sends it `signal` and
/// waits for it: it must stop as interrupted (exit 130). Returns its output.
pub fn interrupt(child: std::process::Child, dir: &Path, signal_name: &str) -> std::process::Output {
    wait_until_running(dir);
    signal(child.id(), signal_name);
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// An empty scratch directory for test group `group`, case `name`, unique to this process.
pub fn scratch(group: &str, name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("kdmpm-{group}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d
}

/// Relative difference a/b − 1.
pub fn rel(a: f64, b: f64) -> f64 {
    a / b - 1.0
}

/// The bank's material: cohesionless Mohr-Coulomb sand.
pub const SAND: &str = "MohrCoulomb(density: 1900.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, \
                        cohesion: 0.0, friction_angle: 25.0, dilatancy_angle: 0.0)";

/// A linear elastic rock.
pub const ROCK: &str = "LinearElastic(density: 2400.0, youngs_modulus: 5.0e8, poisson_ratio: 0.25)";

/// A cohesionless (plastic) bank of [`SAND`] on a layer of material `LAYER`, spawned after
/// it, with a load on its crest and two traced points. Set-up sorts the points; as the bank
/// fails, points cross cells and fall out of order.
const BANK_ON_LAYER: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [40, 16]),
    shape: QuadraticBSpline,
    materials: { "sand": SAND, "layer": LAYER },
    bodies: [
        (material: "sand", region: Polygon(vertices: [[0.0, 3.0], [8.0, 3.0], [4.0, 6.0], [0.0, 6.0]]), points_per_cell: [2, 2]),
        (material: "layer", region: Box(min: [0.0, 0.0], max: [20.0, 3.0]), points_per_cell: [2, 2]),
    ],
    boundaries: [(face: YMin, condition: Fixed), (face: XMin, condition: Roller), (face: XMax, condition: Roller)],
    gravity: (acceleration: [0.0, -9.81]),
    point_loads: [(name: "crest", position: [2.1, 5.9], force: [2.0e3, -1.0e4])],
    traced: [(name: "edge", position: [3.9, 5.9]), (name: "heap", position: [15.1, 2.9])],
    solver: (time_step: Courant(0.3), max_steps: STEPS, sort_every: SORT),
    output: (displacements: KEEP),
)"#;

/// The bank of [`BANK_ON_LAYER`] on a layer of `layer` ([`SAND`] or [`ROCK`]), built, not
/// run: `steps` steps, a sort every `sort_every` (0: none), per-point displacements kept or
/// not.
pub fn bank_on_layer(layer: &str, steps: u64, sort_every: u64, displacements: bool) -> Simulation<Dim2> {
    let text = BANK_ON_LAYER
        .replace("SAND", SAND)
        .replace("LAYER", layer)
        .replace("STEPS", &steps.to_string())
        .replace("SORT", &sort_every.to_string())
        .replace("KEEP", &displacements.to_string());
    let loaded = LoadedScene::from_text(Path::new("bank.ron"), &text, &[]).expect("scene loads");
    let AnySimulation::Two(sim) = build(&loaded).expect("scene builds").0 else {
        unreachable!("2D scene")
    };
    sim
}
