//! Fuzzing the scene parser, the validator and set-up: scene texts made by mutating valid
//! scenes (numbers swapped for extreme values, characters cut or inserted, `--set`s with
//! random paths and values) must each end in `Ok` or a typed error with a place, never in a
//! panic, an abort or a hang; a scene accepted runs a few steps and its state stays finite
//! or the step reports a typed error.
//!
//! The cases are drawn from a fixed seed, so a run is reproducible; `KDMPM_FUZZ_CASES`
//! sets how many (default 40 000, about 8 s in a release build; `KDMPM_FUZZ_CASES=1000000`
//! for a deep run).

use crate::common;

use kdmpm::scene::{build, check, LoadedScene};
use kdmpm::with_simulation;
use kdmpm::SceneError;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::cell::Cell;
use std::path::Path;
use std::sync::OnceLock;

/// Small scenes of every kind the format has (2D and 3D, both materials, polygon and box,
/// loads, traced points, static check, custom schedule), then [`FEATURE_SEEDS`].
const SEEDS: &[&str] = &[
    r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [4, 12]),
    shape: Linear,
    materials: { "soil": MohrCoulomb(density: 1800.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, cohesion: 1000.0, friction_angle: 30.0, dilatancy_angle: 0.0, tension_cutoff: 100.0) },
    bodies: [(material: "soil", region: Box(min: [0.0, 0.0], max: [2.0, 5.0]), points_per_cell: [2, 2])],
    boundaries: [(face: YMin, condition: Fixed), (face: XMin, condition: Roller), (face: XMax, condition: Roller)],
    gravity: (acceleration: [0.0, -9.81], ramp_time: 0.1),
    traced: [(name: "top", position: [0.875, 4.875])],
    solver: (damping: Kinetic, time_step: Courant(0.5), tolerance: 1e-3, max_steps: 30, static_check: (window: 0.01, max_displacement: 0.01)),
    output: (history_every: 10),
)"#,
    r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 1.0, cells: [6, 2, 2]),
    shape: QuadraticBSpline,
    materials: { "rod": LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0), "rock": LinearElastic(density: 2.0, youngs_modulus: 3.0, poisson_ratio: 0.2) },
    bodies: [(material: "rod", region: Box(min: [0.0, 0.0, 0.0], max: [5.0, 1.0, 1.0]), points_per_cell: [2, 2, 2])],
    boundaries: [(face: XMin, condition: Fixed)],
    point_loads: [(name: "F", position: [4.75, 0.5, 0.5], force: [0.001, 0.0, 0.0])],
    solver: (scheme: Usl, damping: Viscous(beta: 0.1), time_step: Fixed(0.1), max_time: 3.0, flip: 0.9, sort_every: 5, checkpoint_every: Steps(10)),
)"#,
    r#"Scene(
    dimension: 2,
    grid: (origin: [-1.0, 0.0], cell_size: 1.0, cells: [12, 6]),
    shape: QuadraticBSpline,
    materials: { "sand": MohrCoulomb(density: 2000.0, youngs_modulus: 7.0e5, poisson_ratio: 0.3, cohesion: 0.0, friction_angle: 20.0) },
    bodies: [(material: "sand", region: Polygon(vertices: [[0.0, 0.0], [10.0, 0.0], [10.0, 4.0], [4.0, 4.0]]), points_per_cell: [2, 2])],
    boundaries: [(face: YMin, condition: Fixed), (face: XMin, condition: Roller)],
    gravity: (acceleration: [0.0, -9.81]),
    solver: (scheme: Usf, time_step: Courant(0.3), max_steps: 20, anti_locking: StrainSmoothing, force_norm: Mean, sort_every: 0,
             schedule: ["grid_reset", "p2g_momentum", "nodal_velocity", "velocity_gradient", "volumetric_smoothing", "stress_update", "volume_update", "p2g_force", "gravity", "boundary", "integrate", "g2p", "peak_watch", "move_points", "convergence"]),
    output: (surface_angle: true, displacements: false),
)"#,
    r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [8, 6]),
    shape: QuadraticBSpline,
    materials: { "clay": MohrCoulomb(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, cohesion: 1.0e4, friction_angle: 0.0) },
    bodies: [(material: "clay", region: Box(min: [0.0, 0.0], max: [4.0, 2.0]), points_per_cell: [2, 2])],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Fixed)],
    gravity: (acceleration: [0.0, -9.81]),
    motions: [(name: "footing", min: [0.0, 2.0], max: [1.0, 2.5], velocity: [None, Some(-0.01)], travel: 0.02, increment: 0.01, area: 1.0)],
    stages: [(name: "geostatic"), (name: "strong", materials: {"clay": MohrCoulomb(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, cohesion: 2.0e4, friction_angle: 0.0)}, reset_displacements: true)],
    strength_reduction: (bracket: [0.5, 2.0], tolerance: 0.1, failure_displacement: 0.1),
    traced: [(name: "corner", position: [0.1, 1.9])],
    solver: (time_step: Courant(0.5), max_steps: 30),
)"#,
    r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [8, 6]),
    materials: { "block": LinearElastic(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3), "soft": LinearElastic(density: 1000.0, youngs_modulus: 1.0e6, poisson_ratio: 0.3) },
    bodies: [(material: "block", region: Box(min: [0.0, 0.0], max: [4.0, 2.0]), points_per_cell: [2, 2])],
    boundaries: [(face: YMin, condition: Fixed)],
    gravity: (acceleration: [0.0, -9.81], ramp_time: 0.01),
    tractions: [(name: "strip", surface: YMax, min: [0.0, 1.5], max: [1.0, 2.0], traction: [0.0, -1.0e4], increments: 3),
                (name: "side", surface: XMax, min: [3.5, 0.0], max: [4.0, 2.0], traction: [-1.0e3, 0.0])],
    point_loads: [(name: "P", position: [2.1, 1.9], force: [0.0, -100.0])],
    stages: [(name: "one"), (name: "two", tractions: {"side": [-2.0e3, 0.0]}, point_loads: {"P": [0.0, -200.0]},
              gravity: (acceleration: [0.0, 0.0]), boundaries: [(face: YMin, condition: Fixed), (face: XMin, condition: Roller)],
              materials: {"block": LinearElastic(density: 2000.0, youngs_modulus: 5.0e6, poisson_ratio: 0.3)})],
    traced: [(name: "top", position: [0.1, 1.9]), (name: "side", position: [3.9, 1.0])],
    solver: (time_step: Courant(0.5), max_steps: 40, checkpoint_every: Steps(5)),
)"#,
];

/// Scenes with rigid bodies, meshes, water and axisymmetry: a rough footing set off by a
/// stage that lowers the water and doubles gravity; a cone on the axis with a rough tip
/// under a traction; in 3D an STL pad driven down, a sphere under a load and a cylinder
/// holding its place under a height-grid table. `{STL}` is the pad's file.
const FEATURE_SEEDS: &[&str] = &[
    r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [8, 6]),
    shape: QuadraticBSpline,
    materials: { "clay": MohrCoulomb(density: 1800.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, cohesion: 1.0e4, friction_angle: 20.0) },
    bodies: [(material: "clay", region: Box(min: [0.0, 0.0], max: [4.0, 2.0]), points_per_cell: [2, 2])],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Fixed)],
    gravity: (acceleration: [0.0, -9.81]),
    water: (table: Polyline([[0.0, 1.5], [4.0, 1.0]]), saturated_density: {"clay": 2000.0}, unit_weight: 9810.0),
    rigid_bodies: [(name: "footing", parts: [(name: "base", geometry: Polygon(vertices: [[-1.0, 2.0], [1.0, 2.0], [1.0, 2.5], [-1.0, 2.5]]))],
                    interface: Rough, motion: (velocity: [0.0, -0.01], travel: 0.02, increment: 0.01, stage: Some("push")), area: 1.0)],
    stages: [(name: "geostatic"), (name: "push", water: (table: Level(0.5)), gravity: (acceleration: [0.0, -19.62]))],
    solver: (time_step: Courant(0.5), max_steps: 30),
)"#,
    r#"Scene(
    dimension: Axisymmetric,
    grid: (origin: [0.0, 0.0], cell_size: 0.25, cells: [8, 12]),
    shape: QuadraticBSpline,
    materials: { "clay": MohrCoulomb(density: 1700.0, youngs_modulus: 3.0e6, poisson_ratio: 0.3, cohesion: 1.0e4, friction_angle: 0.0) },
    bodies: [(material: "clay", region: Box(min: [0.0, 0.0], max: [2.0, 2.0]), points_per_cell: [3, 2], initial_stress: Isotropic(1.0e4))],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Roller)],
    gravity: (acceleration: [0.0, -9.81]),
    rigid_bodies: [(name: "cone", parts: [(name: "tip", geometry: Polygon(vertices: [[0.0, 2.0], [0.25, 2.4], [0.25, 2.8], [0.0, 2.8]]), interface: Some(Rough))],
                    interface: Frictional(angle: 10.0, adhesion: 1.0e3), motion: (velocity: [0.0, -0.05], travel: 0.1, increment: 0.05), area: 0.03125)],
    tractions: [(name: "top", surface: YMax, min: [1.0, 1.5], max: [2.0, 2.0], traction: [0.0, -1.0e4])],
    solver: (time_step: Courant(0.5), max_steps: 30),
)"#,
    r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 0.5, cells: [4, 4, 4]),
    shape: Linear,
    materials: { "clay": MohrCoulomb(density: 1800.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3, cohesion: 1.0e4, friction_angle: 0.0) },
    bodies: [(material: "clay", region: Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 1.5]), points_per_cell: [2, 2, 2], initial_stress: Geostatic(k0: 0.6, surcharge: 1.0e3))],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Roller), (face: YMax, condition: Roller), (face: ZMin, condition: Fixed)],
    gravity: (acceleration: [0.0, 0.0, -9.81]),
    water: (table: Heights(origin: [0.0, 0.0], spacing: [2.0, 2.0], heights: [[1.0, 1.0], [1.0, 1.2]]), saturated_density: {"clay": 2000.0}),
    rigid_bodies: [
        (name: "pad", parts: [(name: "mesh", geometry: Mesh(file: "{STL}"))], interface: Smooth, motion: (velocity: [0.0, 0.0, -0.01], travel: 0.02), area: 0.25),
        (name: "ball", parts: [(name: "s", geometry: Sphere(centre: [1.5, 1.5, 1.9], radius: 0.1))], interface: Rough, load: (force: [0.0, 0.0, -100.0], increments: 2)),
        (name: "post", parts: [(name: "c", geometry: Cylinder(base: [0.2, 1.6, 1.5], axis: 2, length: 0.3, radius: 0.1))], interface: Frictional(angle: 20.0)),
    ],
    solver: (time_step: Courant(0.5), max_steps: 20),
)"#,
];

/// The pad of the 3D feature seed: a 0.5 × 0.5 × 0.25 m box on the clay, as ASCII STL.
fn pad_stl() -> String {
    let t = kdmpm::rigid::mesh::box_triangles([0.5, 0.5, 1.5], [1.0, 1.0, 1.75]);
    common::stl("solid pad", &t, |x| format!("{x:?}"))
}

/// Every seed scene, the feature seeds' STL written once for the process.
fn seeds() -> &'static [String] {
    static SEEDS_WITH_FEATURES: OnceLock<Vec<String>> = OnceLock::new();
    SEEDS_WITH_FEATURES.get_or_init(|| {
        let pad = common::scratch("fuzz", "seeds").join("pad.stl");
        std::fs::write(&pad, pad_stl()).unwrap();
        let file = pad.to_str().unwrap().replace('\\', "/");
        SEEDS
            .iter()
            .map(|s| s.to_string())
            .chain(FEATURE_SEEDS.iter().map(|s| s.replace("{STL}", &file)))
            .collect()
    })
}

/// Values that broke or nearly broke earlier versions.
const EXTREMES: &[&str] = &[
    "0",
    "0.0",
    "-0.0",
    "-1",
    "-1.0",
    "1e308",
    "-1e308",
    "5e-324",
    "1e-300",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551615",
    "4294967296",
    "65536",
    "1e9",
    "0.5",
    "89.999",
    "90",
    "1",
    "2",
    "3",
    "[]",
    "[0.0]",
    "[1e308, 1e308]",
    "[NaN, 0.0, 0.0]",
    "\"\"",
    "\"soil\"",
    "None",
    "Some(1.0)",
    "\"top\"",
    "[0.5]",
    "[0.0, 2.0]",
    "[2.0, 1.0]",
    "[1.0, 4294967295]",
    "4294967295",
    "(acceleration: [0.0, 0.0])",
    "Viscous(beta: 1e308)",
    "Usl",
    "Axisymmetric",
    "Rough",
    "Level(1e306)",
    "Level(-1e9)",
    "Frictional(angle: 89.0, adhesion: 1e308)",
    "Circle(centre: [3.0, -999999999.5], radius: 1.0e9)",
    "Mesh(file: \"/dev/zero\")",
    "Mesh(file: \"no.stl\")",
    "(force: [0.0, -1e160])",
    "(velocity: [1.0, 0.0], travel: 1e300)",
    "{\"clay\": 1.0}",
];

/// Paths a user may `--set`, valid or not.
const PATHS: &[&str] = &[
    "dimension",
    "grid.cell_size",
    "grid.cells",
    "grid.origin",
    "grid.cells[1]",
    "materials.soil.density",
    "materials.soil.youngs_modulus",
    "materials.soil.poisson_ratio",
    "materials.soil.tension_cutoff",
    "materials.soil.friction_angle",
    "bodies[0].points_per_cell",
    "bodies[0].region",
    "bodies[1]",
    "gravity.acceleration",
    "gravity.ramp_time",
    "solver.time_step",
    "solver.tolerance",
    "solver.max_steps",
    "solver.max_time",
    "solver.static_check",
    "solver.checkpoint_every",
    "solver.schedule",
    "traced[0].position",
    "point_loads[0].force",
    "output.history_every",
    "stages[1].materials.clay.density",
    "stages[1].materials.block.density",
    "stages[1].gravity",
    "stages[1].name",
    "stages[0].reset_displacements",
    "motions[0].min",
    "motions[0].max",
    "motions[0].increment",
    "motions[0].travel",
    "motions[1]",
    "tractions[0].increments",
    "tractions[0].min",
    "tractions[1].name",
    "strength_reduction.bracket",
    "strength_reduction.tolerance",
    "strength_reduction.failure_displacement",
    "traced[1].name",
    "rigid_bodies[0].parts[0].geometry",
    "rigid_bodies[0].parts[0].interface",
    "rigid_bodies[0].interface",
    "rigid_bodies[0].motion",
    "rigid_bodies[0].motion.velocity",
    "rigid_bodies[1].load",
    "rigid_bodies[1].load.force",
    "rigid_bodies[2].motion",
    "water.table",
    "water.saturated_density",
    "water.unit_weight",
    "water.material_tables",
    "stages[1].water",
    "stages[1].water.table",
    "stages[1].gravity.acceleration",
    "bodies[0].initial_stress",
    "tractions[0].surface",
    "solver.damping",
    "solver.scheme",
    "nothing[0]x",
    "solver..tolerance",
    "[3]",
    "a[b]c",
];

#[derive(Clone, Debug)]
enum Mutation {
    /// Replace the k-th number of the text with an extreme value.
    Number(usize, usize),
    /// Cut `len` bytes at a fraction of the text.
    Cut(f64, usize),
    /// Insert a character at a fraction of the text.
    Insert(f64, char),
    /// Apply `--set path=value`.
    Set(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (0..200usize, 0..EXTREMES.len()).prop_map(|(k, v)| Mutation::Number(k, v)),
        1 => (0.0..1.0f64, 1..8usize).prop_map(|(f, n)| Mutation::Cut(f, n)),
        1 => (0.0..1.0f64, prop::sample::select(vec!['(', ')', '[', ']', '"', ',', ':', '{', '}', 'é', '0', '/', '\\'])).prop_map(|(f, c)| Mutation::Insert(f, c)),
        2 => (0..PATHS.len(), 0..EXTREMES.len()).prop_map(|(p, v)| Mutation::Set(p, v)),
    ]
}

/// A mutation of the text alone (no `--set`): a number swapped for an extreme, a cut, or
/// one of `inserts` put in.
fn text_mutation(inserts: Vec<char>) -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (0..200usize, 0..EXTREMES.len()).prop_map(|(k, v)| Mutation::Number(k, v)),
        1 => (0.0..1.0f64, 1..8usize).prop_map(|(f, n)| Mutation::Cut(f, n)),
        1 => (0.0..1.0f64, prop::sample::select(inserts)).prop_map(|(f, c)| Mutation::Insert(f, c)),
    ]
}

/// A runner of `cases` cases drawn from the fixed seed `[seed; 32]`, so that a failure is
/// the same on every run.
fn runner(cases: u32, seed: u8) -> TestRunner {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]))
}

/// The nearest character boundary at or below `at`.
fn floor_char(text: &str, mut at: usize) -> usize {
    at = at.min(text.len());
    while !text.is_char_boundary(at) {
        at -= 1;
    }
    at
}

/// Applies the text mutations; returns the text and the overrides.
fn mutate(seed: &str, ms: &[Mutation]) -> (String, Vec<String>) {
    let mut text = seed.to_string();
    let mut sets = Vec::new();
    for m in ms {
        match *m {
            Mutation::Number(k, v) => {
                let spans: Vec<(usize, usize)> = number_spans(&text);
                if let Some(&(a, b)) = spans.get(k % spans.len().max(1)) {
                    text.replace_range(a..b, EXTREMES[v]);
                }
            }
            Mutation::Cut(f, n) => {
                let a = floor_char(&text, (f * text.len() as f64) as usize);
                let b = floor_char(&text, a + n);
                text.replace_range(a..b, "");
            }
            Mutation::Insert(f, c) => {
                let a = floor_char(&text, (f * text.len() as f64) as usize);
                text.insert(a, c);
            }
            Mutation::Set(p, v) => sets.push(format!("{}={}", PATHS[p], EXTREMES[v])),
        }
    }
    (text, sets)
}

/// Byte spans of the numeric literals of `text`.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if starts {
            let a = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || matches!(b[j], b'.' | b'e' | b'E' | b'-' | b'+')) {
                j += 1;
            }
            out.push((a, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// One case: parse, validate, build within a memory budget, and step a little. `built`
/// counts the cases that were built and stepped (a test checks that its fuzzer reaches
/// set-up; each test has its own count, as the tests run side by side).
fn exercise(text: &str, sets: &[String], built: &Cell<usize>) -> Result<(), TestCaseError> {
    let loaded = match LoadedScene::from_text(Path::new("fuzz.ron"), text, sets) {
        Ok(l) => l,
        Err(e) => return placed(&e),
    };
    let checked = match check(&loaded) {
        Ok(c) => c,
        Err(e) => return placed(&e),
    };
    // The fuzzer's own budget: scenes that fit the machine but not a test are not built.
    if checked.estimate.bytes > 64 << 20 {
        return Ok(());
    }
    let mut sim = match build(&loaded) {
        Ok((s, _)) => s,
        Err(e) => return placed(&e),
    };
    built.set(built.get() + 1);
    // Strength reduction divides the strengths of the scene and of its stages: every
    // trial's scene is checked again (a factor that breaks a material is a placed error).
    if loaded.scene.strength_reduction.is_some() {
        for factor in [0.5, 1.7] {
            if let Err(e) = check(&kdmpm::fos::reduced(&loaded, factor)) {
                placed(&e)?;
            }
        }
    }
    with_simulation!(&mut sim, s => {
        for _ in 0..20 {
            if s.ctx.state.stop.is_some() || s.step().is_err() {
                break;
            }
        }
        // A step that returned Ok never leaves a non-finite value in the state it wrote;
        // an error may (the binary then refuses to write it), but not a panic.
        let _ = s.first_non_finite();
    });
    Ok(())
}

/// A scene error must say where: a file position for the text's faults, the override for
/// a `--set` that cannot apply, the path for a file that cannot be read.
fn placed(e: &SceneError) -> Result<(), TestCaseError> {
    let text = e.to_string();
    prop_assert!(!text.is_empty());
    match e {
        SceneError::Syntax { line, .. } => prop_assert!(*line >= 1, "{text}"),
        SceneError::Invalid { field, .. } => prop_assert!(!field.is_empty(), "{text}"),
        SceneError::Override(..) | SceneError::Read { .. } => {}
    }
    Ok(())
}

#[test]
fn mutated_scenes_end_in_ok_or_a_placed_error_never_a_panic() {
    let cases = std::env::var("KDMPM_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40_000);
    let mut runner = runner(cases, 7);
    let seeds = seeds();
    let strategy = (0..seeds.len(), prop::collection::vec(mutation(), 1..4));
    // On a pool of its own: the steps of the cases that build do not wait on the other test's.
    let built = common::on_own_thread(|| {
        let built = Cell::new(0);
        runner
            .run(&strategy, |(seed, ms)| {
                let (text, sets) = mutate(&seeds[seed], &ms);
                exercise(&text, &sets, &built)
            })
            .unwrap();
        built.get()
    });
    eprintln!("{cases} cases, {built} built and stepped");
    // Most mutations break the text or a rule; about 3.5 % (1 404 of 40 000) of the cases get through to
    // set-up and steps. Far fewer would mean the mutations no longer reach the engine.
    assert!(
        built * 33 >= cases as usize,
        "only {built} of {cases} cases reached set-up"
    );
}

#[test]
fn every_seed_scene_is_valid() {
    for s in seeds() {
        let loaded = LoadedScene::from_text(Path::new("seed.ron"), s, &[]).unwrap();
        build(&loaded).unwrap_or_else(|e| panic!("{e}\n{s}"));
    }
}

/// Study files, mutated like scenes: parsing, checking and planning every run ends in a
/// study or a placed error, never a panic.
#[test]
fn mutated_study_files_end_in_ok_or_a_placed_error_never_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies");
    let seeds: Vec<String> = ["column.ron", "bar.ron"]
        .iter()
        .map(|f| std::fs::read_to_string(dir.join(f)).unwrap())
        .collect();
    let mut runner = runner(400, 11);
    let text_only = text_mutation(vec!['(', ')', '[', ']', '"', ',', ':']);
    let strategy = (0..seeds.len(), prop::collection::vec(text_only, 1..3));
    runner
        .run(&strategy, |(seed, ms)| {
            let (text, _) = mutate(&seeds[seed], &ms);
            match kdmpm::study::Study::from_text(&dir.join("fuzz.ron"), &text) {
                Ok(_) => Ok(()),
                Err(e) => placed(&e),
            }
        })
        .unwrap();
}

/// A mutation of an STL file's bytes.
#[derive(Clone, Debug)]
enum ByteMutation {
    /// XOR the byte at a fraction of the file with a value.
    Flip(f64, u8),
    /// Cut the file at a fraction of its length.
    Truncate(f64),
    /// Insert `n` zero bytes at a fraction of the file.
    Insert(f64, usize),
    /// Replace the binary triangle count (bytes 80..84).
    Count(u32),
}

/// The binary STL of the pad: 80-byte header, count, 50 bytes a triangle.
fn pad_binary() -> Vec<u8> {
    let t = kdmpm::rigid::mesh::box_triangles([0.5, 0.5, 1.5], [1.0, 1.0, 1.75]);
    let mut b = vec![b' '; 80];
    b.extend((t.len() as u32).to_le_bytes());
    for tri in &t {
        b.extend([0u8; 12]);
        for c in tri {
            for x in c {
                b.extend((*x as f32).to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn mutate_bytes(mut b: Vec<u8>, ms: &[ByteMutation]) -> Vec<u8> {
    let at = |b: &Vec<u8>, f: f64| ((f * b.len() as f64) as usize).min(b.len());
    for m in ms {
        match *m {
            ByteMutation::Flip(f, x) => {
                let i = at(&b, f).min(b.len().saturating_sub(1));
                if let Some(v) = b.get_mut(i) {
                    *v ^= x;
                }
            }
            ByteMutation::Truncate(f) => {
                let i = at(&b, f);
                b.truncate(i);
            }
            ByteMutation::Insert(f, n) => {
                let i = at(&b, f);
                b.splice(i..i, std::iter::repeat_n(0u8, n));
            }
            ByteMutation::Count(n) => {
                if b.len() >= 84 {
                    b[80..84].copy_from_slice(&n.to_le_bytes());
                }
            }
        }
    }
    b
}

/// STL files mutated as text (numbers swapped for extremes, characters cut or inserted)
/// and as bytes (a count that lies, a cut file, flipped bits): the 3D feature seed with
/// that file as its pad ends in a scene that steps or a placed error, never a panic, an
/// abort or a hang.
#[test]
fn mutated_stl_files_end_in_a_body_or_a_placed_error_never_a_panic() {
    let file = common::scratch("fuzz", "stl").join("pad.stl");
    let scene = FEATURE_SEEDS[2].replace("{STL}", &file.to_str().unwrap().replace('\\', "/"));
    let ascii = pad_stl();
    let binary = pad_binary();
    let mut runner = runner(600, 13);
    let text_only = text_mutation(vec!['\n', ' ', '-', 'e', '0', 'x']);
    let bytes = prop_oneof![
        3 => (0.0..1.0f64, 1..=255u8).prop_map(|(f, x)| ByteMutation::Flip(f, x)),
        1 => (0.0..1.0f64).prop_map(ByteMutation::Truncate),
        1 => (0.0..1.0f64, 1..60usize).prop_map(|(f, n)| ByteMutation::Insert(f, n)),
        1 => prop_oneof![Just(0u32), Just(1), Just(11), Just(13), Just(u32::MAX), any::<u32>()].prop_map(ByteMutation::Count),
    ];
    let strategy = prop_oneof![
        prop::collection::vec(text_only, 1..4).prop_map(|ms| mutate(&ascii, &ms).0.into_bytes()),
        prop::collection::vec(bytes, 1..4).prop_map(move |ms| mutate_bytes(binary.clone(), &ms)),
    ];
    runner
        .run(&strategy, |stl| {
            std::fs::write(&file, &stl).unwrap();
            exercise(&scene, &[], &Cell::new(0))
        })
        .unwrap();
}
