//! Helpers shared by the integration tests: run a scene file with overrides, in memory.
#![allow(dead_code)]

use kdmpm::output::Summary;
use kdmpm::run::Run;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Dim2, Simulation};
use std::collections::BTreeMap;
use std::path::Path;

/// Path of a scene shipped in `scenes/`.
pub fn scene(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

/// Runs `name` with `overrides` to its stop and returns the summary (no files written).
pub fn run(name: &str, overrides: &[&str]) -> Summary {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_file(&scene(name), &overrides).expect("scene loads");
    run_loaded(loaded)
}

/// Runs the scene `text` (called `name` in messages) to its stop and returns the summary.
pub fn run_text(name: &str, text: &str) -> Summary {
    run_text_with(name, text, &[])
}

/// Runs the scene `text` (called `name` in messages) with `--set` overrides to its stop.
pub fn run_text_with(name: &str, text: &str, overrides: &[&str]) -> Summary {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_text(Path::new(name), text, &overrides).expect("scene loads");
    run_loaded(loaded)
}

/// The paper's slope (`slope.ron` and the scenes made from it) on 2 m cells with 4×4 points
/// a cell: a quarter of the shipped points, the crest point still at (29.75, 39.75).
pub const COARSE_SLOPE: [&str; 3] = [
    "grid.cell_size=2",
    "grid.cells=[90, 23]",
    "bodies[0].points_per_cell=[4, 4]",
];

/// `scenes/slope_fast.ron` run to its stop once for the whole test binary: two tests compare
/// against it (the fast preset against slope.ron, the staged slope against one stage).
pub fn slope_fast() -> &'static Summary {
    static RUN: std::sync::OnceLock<Summary> = std::sync::OnceLock::new();
    RUN.get_or_init(|| run("slope_fast.ron", &[]))
}

/// Each static state's mean pressure over `c_u` (a penetrometer's or a footing's factor
/// N), in curve order.
pub fn factors(s: &Summary, c_u: f64) -> Vec<f64> {
    s.curve.iter().map(|c| c.pressure.unwrap() / c_u).collect()
}

/// The error that building the scene `text` gives.
pub fn refusal(text: &str) -> String {
    let loaded = LoadedScene::from_text(Path::new("refused.ron"), text, &[]).expect("scene parses");
    build(&loaded).err().expect("refused").to_string()
}

/// Runs `loaded` in memory with the library's runner; a run that stops on an error gives
/// its summary (outcome `Failed`, the error in `error`).
fn run_loaded(loaded: LoadedScene) -> Summary {
    on_own_thread(|| Run::scene(loaded).quiet(true).go().expect("scene builds").summary)
}

/// Runs `f` on a rayon pool of one thread of its own. The harness runs two tests at once,
/// and on the shared global pool each run's parallel passes (broadcasts to every worker)
/// wait for the other run's worker: the two ran one after the other. A run's bits do not
/// depend on its thread count.
pub fn on_own_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread starts")
        .install(f)
}

/// Runs the `kdmpm` binary with `args` and waits for it, on one worker thread unless `args`
/// name `--threads` (the harness runs two tests at once; a run's bits do not depend on it).
pub fn kdmpm(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .env("RAYON_NUM_THREADS", "1")
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

/// Runs `kdmpm study` on the study file `study`, writing into `out`, and waits for it.
pub fn study_into(study: &Path, out: &Path) -> std::process::Output {
    kdmpm(&[
        "study",
        study.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ])
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

/// An empty scratch directory for test group `group`, case `name`, in the target
/// directory's `tmp/` (Cargo's `CARGO_TARGET_TMPDIR`): the next run of the case empties and
/// reuses it, so a run's files stay there to look at and runs do not pile up, and
/// `cargo clean` removes them.
pub fn scratch(group: &str, name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{group}-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d
}

/// The ASCII STL text of `triangles` (m): its first line `header` (`solid`, `solid name`),
/// each coordinate written by `write`.
pub fn stl(header: &str, triangles: &[[[f64; 3]; 3]], write: impl Fn(f64) -> String) -> String {
    let mut text = format!("{header}\n");
    for t in triangles {
        text += "facet normal 0 0 0\nouter loop\n";
        for c in t {
            text += &format!("vertex {} {} {}\n", write(c[0]), write(c[1]), write(c[2]));
        }
        text += "endloop\nendfacet\n";
    }
    text + "endsolid\n"
}

/// Relative difference a/b − 1.
pub fn rel(a: f64, b: f64) -> f64 {
    a / b - 1.0
}

/// The force along `axis` (N; N/m in 2D) at each static state in `s`'s curve rows named
/// `name` (a motion or a rigid body).
pub fn forces(s: &Summary, name: &str, axis: usize) -> Vec<f64> {
    s.curve
        .iter()
        .filter(|c| c.name == name)
        .map(|c| c.force[axis])
        .collect()
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
    let text = bank_on_layer_text(layer, steps, sort_every, displacements);
    let loaded = LoadedScene::from_text(Path::new("bank.ron"), &text, &[]).expect("scene loads");
    let AnySimulation::Two(sim) = build(&loaded).expect("scene builds").0 else {
        unreachable!("2D scene")
    };
    sim
}

/// The scene text of [`bank_on_layer`].
pub fn bank_on_layer_text(layer: &str, steps: u64, sort_every: u64, displacements: bool) -> String {
    BANK_ON_LAYER
        .replace("SAND", SAND)
        .replace("LAYER", layer)
        .replace("STEPS", &steps.to_string())
        .replace("SORT", &sort_every.to_string())
        .replace("KEEP", &displacements.to_string())
}

/// The test suite's own `.vtu` reader, independent of the library's (so that a fault in
/// the writer cannot hide behind the same fault in a reader). Every DataArray as f64, by name (`Points` for the positions), with its
/// component count. The XML head is parsed as XML (closed where the raw section opens);
/// each array's bytes are at `offset` after the `_` that opens the appended section, a
/// UInt64 byte count first (header_type="UInt64"), little-endian values after it.
pub fn read_vtu(path: &Path) -> BTreeMap<String, (usize, Vec<f64>)> {
    let bytes = std::fs::read(path).expect("the .vtu file is written");
    let open = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(open.len())
        .position(|w| w == open)
        .expect("raw appended data");
    let head = format!("{}</VTKFile>", std::str::from_utf8(&bytes[..at]).unwrap());
    let doc = roxmltree::Document::parse(&head).expect("the head is well-formed XML");
    let root = doc.root_element();
    assert_eq!(root.attribute("header_type"), Some("UInt64"));
    assert_eq!(root.attribute("byte_order"), Some("LittleEndian"));
    let underscore = at + open.len() + bytes[at + open.len()..].iter().position(|&b| b == b'_').unwrap();
    let data = &bytes[underscore + 1..];
    let mut out = BTreeMap::new();
    for a in doc.descendants().filter(|n| n.has_tag_name("DataArray")) {
        let name = a.attribute("Name").unwrap_or("Points").to_string();
        let comps: usize = a
            .attribute("NumberOfComponents")
            .map_or(1, |c| c.parse().unwrap());
        assert_eq!(a.attribute("format"), Some("appended"));
        let offset: usize = a.attribute("offset").unwrap().parse().unwrap();
        let len = u64::from_le_bytes(data[offset..offset + 8].try_into().unwrap()) as usize;
        let raw = &data[offset + 8..offset + 8 + len];
        let values: Vec<f64> = match a.attribute("type").unwrap() {
            "Float64" => raw
                .chunks(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect(),
            "Int64" => raw
                .chunks(8)
                .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect(),
            "UInt32" => raw
                .chunks(4)
                .map(|c| u32::from_le_bytes(c.try_into().unwrap()) as f64)
                .collect(),
            "UInt8" => raw.iter().map(|&b| b as f64).collect(),
            t => panic!("unexpected type {t}"),
        };
        out.insert(name, (comps, values));
    }
    out
}

/// summary.json in `dir` without the figures of the machine (wall time, rate, memory,
/// per-system cost, output wait, and over MPI ranks the bytes sent a step, a measure of
/// the process): what two runs of the same state must agree on.
pub fn summary_numbers(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    for key in [
        "wall_seconds",
        "particle_steps_per_second",
        "peak_memory_bytes",
        "systems",
        "output_wait_seconds",
    ] {
        v.as_object_mut().expect("an object").remove(key);
    }
    if let Some(ranks) = v.get_mut("ranks").and_then(|r| r.as_object_mut()) {
        ranks.remove("bytes_per_step");
        ranks.remove("peak_memory_bytes");
    }
    v
}

/// Copies directory `from` (and its folders) to `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("a directory");
    for e in std::fs::read_dir(from).expect("a directory").flatten() {
        if e.file_type().expect("a file type").is_dir() {
            copy_dir(&e.path(), &to.join(e.file_name()));
        } else {
            std::fs::copy(e.path(), to.join(e.file_name())).expect("copied");
        }
    }
}
