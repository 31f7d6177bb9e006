//! Bad input ends with one readable message naming the file, line:column, field and rule,
//! exit code 2, and no output directory.

use std::path::{Path, PathBuf};
use std::process::Command;

const GOOD: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 1.0, cells: [12, 2]),
    materials: {
        "rod": LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0),
        "soil": MohrCoulomb(density: 2000.0, youngs_modulus: 1000.0, poisson_ratio: 0.3, cohesion: 0.0, friction_angle: 30.0, dilatancy_angle: 0.0),
    },
    bodies: [
        (material: "rod", region: Box(min: [0.0, 0.0], max: [10.0, 1.0]), points_per_cell: [2, 2]),
    ],
    boundaries: [(face: XMin, condition: Fixed)],
    traced: [(name: "A", position: [4.75, 0.5])], point_loads: [(name: "P", position: [9.75, 0.5], force: [0.01, 0.0])],
    solver: (time_step: Fixed(0.01), tolerance: 0.01, max_steps: 10),
)
"#;

struct Case {
    dir: PathBuf,
    scene: PathBuf,
    out: PathBuf,
}

fn case(name: &str, text: &str) -> Case {
    let dir = crate::common::scratch("errors", name);
    let scene = dir.join("scene.ron");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    Case { dir, scene, out }
}

/// Runs `kdmpm run` and returns (exit code, stderr).
fn run(scene: &Path, out: &Path, extra: &[&str]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Replaces `from` by `to` in the good scene, runs it, and checks the error report.
fn rejects(name: &str, from: &str, to: &str, line: usize, expect: &[&str]) {
    assert!(GOOD.contains(from), "{name}: pattern not in the scene");
    let c = case(name, &GOOD.replacen(from, to, 1));
    let (code, err) = run(&c.scene, &c.out, &[]);
    assert_eq!(code, 2, "{name}: exit code {code}, stderr: {err}");
    let at = format!("{}:{line}:", c.scene.display());
    assert!(
        err.starts_with(&format!("error: {at}")),
        "{name}: expected `{at}` in: {err}"
    );
    for e in expect {
        assert!(err.contains(e), "{name}: expected `{e}` in: {err}");
    }
    assert_eq!(err.trim_end().lines().count(), 1, "{name}: one paragraph: {err}");
    assert!(!c.out.exists(), "{name}: output directory created");
    let _ = std::fs::remove_dir_all(&c.dir);
}

#[test]
fn the_good_scene_runs() {
    let c = case("good", GOOD);
    let (code, err) = run(&c.scene, &c.out, &[]);
    assert_eq!(code, 0, "{err}");
    assert!(c.out.join("summary.json").exists() && c.out.join("history.csv").exists());
    let _ = std::fs::remove_dir_all(&c.dir);
}

#[test]
fn malformed_ron_is_reported_where_it_breaks() {
    // The parser notices the missing `)` at the next field, which it reads as a grid field.
    rejects(
        "unclosed",
        "cells: [12, 2]),",
        "cells: [12, 2],",
        4,
        &["materials", "GridSpec"],
    );
    rejects(
        "wrong type",
        "cell_size: 1.0",
        "cell_size: \"one\"",
        3,
        &["cell_size", "float"],
    );
    rejects(
        "unknown field",
        "tolerance: 0.01,",
        "tolerence: 0.01,",
        13,
        &["tolerence"],
    );
    // A missing field is reported at the end of its struct, named by the field holding it.
    rejects(
        "missing field",
        "time_step: Fixed(0.01), ",
        "",
        13,
        &["field `solver`", "time_step"],
    );
    rejects(
        "missing material field",
        "cohesion: 0.0, ",
        "",
        6,
        &["field `soil`", "cohesion", "MohrCoulomb"],
    );
}

#[test]
fn non_physical_values_are_rejected_with_the_rule() {
    let rod = "LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0)";
    rejects(
        "E",
        rod,
        &rod.replace("youngs_modulus: 1.0", "youngs_modulus: 0.0"),
        5,
        &["materials.rod.youngs_modulus", "> 0 Pa"],
    );
    rejects(
        "nu",
        rod,
        &rod.replace("poisson_ratio: 0.0", "poisson_ratio: 0.5"),
        5,
        &["poisson_ratio", "[0, 0.5)"],
    );
    rejects(
        "rho",
        rod,
        &rod.replace("density: 1.0", "density: -2.0"),
        5,
        &["materials.rod.density", "> 0"],
    );
    rejects(
        "phi",
        "friction_angle: 30.0",
        "friction_angle: 90.0",
        6,
        &["friction_angle", "[0°, 90°)"],
    );
    rejects(
        "psi",
        "dilatancy_angle: 0.0",
        "dilatancy_angle: 31.0",
        6,
        &["dilatancy_angle", "φ = 30°"],
    );
    rejects(
        "c",
        "cohesion: 0.0",
        "cohesion: -1.0",
        6,
        &["materials.soil.cohesion", "≥ 0"],
    );
    rejects(
        "h",
        "cell_size: 1.0",
        "cell_size: 0.0",
        3,
        &["grid.cell_size", "> 0"],
    );
    rejects(
        "ppc",
        "points_per_cell: [2, 2]",
        "points_per_cell: [2, 0]",
        9,
        &["bodies[0].points_per_cell", "≥ 1"],
    );
    rejects(
        "tol",
        "tolerance: 0.01",
        "tolerance: 0.0",
        13,
        &["solver.tolerance", "> 0"],
    );
    rejects(
        "dt",
        "Fixed(0.01)",
        "Fixed(-0.01)",
        13,
        &["solver.time_step", "Δt > 0"],
    );
    rejects(
        "courant",
        "Fixed(0.01)",
        "Courant(0.0)",
        13,
        &["solver.time_step", "0 < α ≤ 1"],
    );
    rejects(
        "contact_tolerance",
        "max_steps: 10",
        "max_steps: 10, contact_tolerance: 0.01",
        13,
        &["solver.contact_tolerance", "(0, 1e-3]"],
    );
}

#[test]
fn inconsistent_scenes_are_rejected_with_the_reason() {
    rejects(
        "dt above critical",
        "Fixed(0.01)",
        "Fixed(1.5)",
        13,
        &["critical step", "by 50.0 %"],
    );
    rejects(
        "outside",
        "max: [10.0, 1.0]",
        "max: [14.0, 1.0]",
        9,
        &["bodies[0].region", "outside the grid"],
    );
    rejects(
        "no points",
        "max: [10.0, 1.0]",
        "max: [10.0, 0.1]",
        9,
        &["bodies[0].region", "no material point"],
    );
    rejects(
        "unknown material",
        "(material: \"rod\"",
        "(material: \"steel\"",
        9,
        &["bodies[0].material", "\"steel\"", "rod, soil"],
    );
    rejects(
        "untraceable",
        "position: [4.75, 0.5]",
        "position: [11.5, 1.5]",
        12,
        &["traced[0].position", "no material point"],
    );
    rejects(
        "empty",
        "        (material: \"rod\", region: Box(min: [0.0, 0.0], max: [10.0, 1.0]), points_per_cell: [2, 2]),\n",
        "",
        8,
        &["bodies", "no body"],
    );
    rejects(
        "schedule",
        "tolerance: 0.01,",
        "tolerance: 0.01, schedule: [\"grid_reset\", \"p2g_fast\"],",
        13,
        &["unknown system `p2g_fast`"],
    );
}

#[test]
fn missing_file_and_unwritable_output_are_reported() {
    let c = case("missing", GOOD);
    let (code, err) = run(&c.dir.join("nope.ron"), &c.out, &[]);
    assert_eq!(code, 2);
    assert!(
        err.contains("cannot read scene file") && err.contains("nope.ron"),
        "{err}"
    );
    // An output path below a regular file cannot be created.
    let blocker = c.dir.join("file");
    std::fs::write(&blocker, "x").unwrap();
    let (code, err) = run(&c.scene, &blocker.join("out"), &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot create output directory"), "{err}");
    let _ = std::fs::remove_dir_all(&c.dir);
}

#[test]
fn overrides_that_do_not_apply_are_rejected() {
    let c = case("override", GOOD);
    let (code, err) = run(&c.scene, &c.out, &["--set", "solver.nothing.deep=1"]);
    // The struct is written in (`--set` may fill in one the file leaves to its defaults),
    // and the scene's own parse refuses the name, pointing at the override.
    assert_eq!(code, 2);
    assert!(
        err.contains("--set `solver.nothing.deep=1`") && err.contains("Unexpected field named `nothing`"),
        "{err}"
    );
    let (code, err) = run(&c.scene, &c.out, &["--set", "solver.tolerance=-1"]);
    assert_eq!(code, 2);
    assert!(err.contains("solver.tolerance"), "{err}");
    let _ = std::fs::remove_dir_all(&c.dir);
}

#[test]
fn a_point_leaving_the_grid_stops_the_run_and_keeps_what_was_written() {
    // A block with no base condition falls out of the grid under gravity.
    let text = r#"Scene(
        dimension: 2,
        grid: (origin: [0.0, 0.0], cell_size: 1.0, cells: [4, 6]),
        materials: { "m": LinearElastic(density: 2000.0, youngs_modulus: 1e6, poisson_ratio: 0.3) },
        bodies: [(material: "m", region: Box(min: [1.0, 0.0], max: [3.0, 2.0]), points_per_cell: [2, 2])],
        gravity: (acceleration: [0.0, -9.81]),
        traced: [(name: "p", position: [1.25, 0.25])],
        solver: (damping: None, time_step: Courant(0.5), max_time: 5.0),
    )"#;
    let c = case("falls", text);
    let (code, err) = run(&c.scene, &c.out, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("system `kinematics`") && err.contains("left the grid") && err.contains("point "),
        "{err}"
    );
    let step: u64 = err
        .split("step ")
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    // history.csv holds a complete row for every step before the failure.
    let history = std::fs::read_to_string(c.out.join("history.csv")).unwrap();
    let rows: Vec<&str> = history.lines().collect();
    let width = rows[0].split(',').count();
    assert!(rows[1..]
        .iter()
        .all(|r| r.split(',').count() == width && r.split(',').all(|f| f.parse::<f64>().is_ok())));
    assert_eq!(rows.len() as u64 - 1, step - 1, "one row per completed step");
    let summary = std::fs::read_to_string(c.out.join("summary.json")).unwrap();
    assert!(
        summary.contains("\"error\": \"step ") && summary.contains("\"converged\": false"),
        "{summary}"
    );
    let _ = std::fs::remove_dir_all(&c.dir);
}
