//! Nothing silently wrong in the features added last (stages, motions, load steps, factors
//! of safety, checkpoints, studies, plots, signals): one regression test per class of bad
//! or extreme input that gave a wrong answer, a hang, a panic or a stale file. Each gives
//! the right answer or exits 2 (bad input) or 1 (a run that went wrong) naming the field and
//! the rule.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// `kdmpm ARGS` with `--set`s, waited for at most `limit`: a hang fails the test.
fn kdmpm_within(args: &[&str], sets: &[&str], limit: Duration) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_kdmpm"));
    // One worker: the harness runs two tests at once.
    cmd.env("RAYON_NUM_THREADS", "1").args(args);
    for s in sets {
        cmd.args(["--set", s]);
    }
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("kdmpm {args:?} {sets:?} did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// `kdmpm run SCENE --quiet --out OUT --set ...`, waited for at most `limit`.
fn run_within(scene: &Path, out: &Path, sets: &[&str], limit: Duration) -> Output {
    let args = [
        "run",
        scene.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    kdmpm_within(&args, sets, limit)
}

/// `kdmpm fos SCENE --quiet --out OUT`, waited for at most `limit`.
fn fos_within(scene: &Path, out: &Path, limit: Duration) -> Output {
    let args = [
        "fos",
        scene.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    kdmpm_within(&args, &[], limit)
}

/// `kdmpm check SCENE --set ...` exits 2 with one line holding every `expect`.
fn refused(scene: &str, sets: &[&str], expect: &[&str]) {
    let path = common::scene(scene);
    let o = kdmpm_within(&["check", path.to_str().unwrap()], sets, Duration::from_secs(60));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{sets:?}: {err}");
    for e in expect {
        assert!(err.contains(e), "{sets:?}: expected `{e}` in: {err}");
    }
    assert_eq!(err.trim_end().lines().count(), 1, "{sets:?}: one line: {err}");
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

const COLUMN_SOIL: &str = "MohrCoulomb(density: DENSITY, youngs_modulus: 10.0e6, poisson_ratio: 0.3, \
                           cohesion: 0.0, friction_angle: 30.0, dilatancy_angle: 0.0)";

// ---- Stages -------------------------------------------------------------------------

/// soil_column.ron with `stages` (the text of the list).
fn staged_column(stages: &str) -> String {
    let text = std::fs::read_to_string(common::scene("soil_column.ron")).unwrap();
    text.replace("    solver: (", &format!("    stages: {stages},\n    solver: ("))
}

/// Runs soil_column.ron whose stage `heavy` (after the stages `before`) doubles the density
/// to 3600 kg/m³: the mass doubles, and the top settles by ρgH²/(2M) (0.06559 m at
/// 1800 kg/m³, twice that at 3600) to the column's own discretisation error at
/// 1800 kg/m³ (tests/robustness.rs): under 1 %.
fn doubled_density_column(before: &str) {
    let heavy = COLUMN_SOIL.replace("DENSITY", "3600.0");
    let s = common::run_text(
        "heavy.ron",
        &staged_column(&format!(
            r#"[{before}(name: "heavy", materials: {{"soil": {heavy}}})]"#
        )),
    );
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.total_mass, 3600.0 * 2.0 * 10.0);
    let m = 10.0e6 * 0.7 / (1.3 * 0.4);
    let analytic = 3600.0 * 9.81 * 100.0 / (2.0 * m);
    let top = -s.traced[1].displacement[1];
    assert!(
        (top / analytic - 1.0).abs() < 0.01,
        "top {top} m, analytic {analytic} m"
    );
}

/// A second stage that doubles the density doubles the mass and the settlement. Once the
/// stage's density was ignored and the run converged at the first stage's settlement.
#[test]
fn a_stage_that_doubles_the_density_doubles_the_mass_and_the_settlement() {
    doubled_density_column(r#"(name: "a"), "#);
}

/// The first stage's changes apply before step 1: a column whose only stage doubles the
/// density weighs twice as much from the start. Once the first stage's density was
/// ignored (36 000 kg, 0.066 m).
#[test]
fn a_first_stage_that_doubles_the_density_weighs_the_column_from_the_first_step() {
    doubled_density_column("");
}

/// A stage that takes every load away (gravity 0) relaxes the column back towards its
/// unloaded shape and stops: K_F is measured against the load it took away. Once K_F was
/// 0/0 in such a stage and the run went on to max_steps with the body at rest.
#[test]
fn a_stage_that_removes_every_load_stops_at_its_static_state() {
    let elastic = "LinearElastic(density: 1800.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3)";
    let text =
        staged_column(r#"[(name: "loaded"), (name: "unloaded", gravity: (acceleration: [0.0, 0.0]))]"#);
    let text = text.replace(
        "MohrCoulomb(\n            density: 1800.0,\n            youngs_modulus: 10.0e6,\n            poisson_ratio: 0.3,\n            cohesion: 0.0,\n            friction_angle: 30.0,\n            dilatancy_angle: 0.0,\n        )",
        elastic,
    );
    assert!(text.contains("LinearElastic"), "the column's soil was replaced");
    let s = common::run_text("unload.ron", &text);
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.stages.len(), 2);
    assert!(s.steps < 2 * s.stages[0].step + 2000, "{} steps", s.steps);
    // Elastic: the top comes back to where it started, to the tolerance's share of the
    // 0.0656 m it settled.
    let top = s.traced[1].displacement[1];
    assert!(top.abs() < 0.01 * 0.0656, "top still displaced {top} m");
}

// ---- Motions ------------------------------------------------------------------------

#[test]
fn a_motion_box_that_drives_no_node_of_the_body_is_refused() {
    // Outside the grid (18 cells of 0.25 m: the top is 4.5 m).
    refused(
        "footing.ron",
        &["motions[0].min=[0.0, 5.0]", "motions[0].max=[1.0, 5.5]"],
        &["motions[0].min", "holds no grid node"],
    );
    // Between grid nodes.
    refused(
        "footing.ron",
        &["motions[0].min=[0.1, 4.01]", "motions[0].max=[0.2, 4.2]"],
        &["motions[0].min", "holds no grid node"],
    );
    // Nodes the body does not reach: grid nodes do not move, so it would push nothing.
    refused(
        "footing.ron",
        &[
            "grid.cells=[24, 24]",
            "motions[0].min=[0.0, 5.5]",
            "motions[0].max=[1.0, 6.0]",
        ],
        &["motions[0].min", "touches the body"],
    );
}

#[test]
fn a_motion_box_corner_that_is_not_a_finite_number_is_refused() {
    refused(
        "footing.ron",
        &["motions[0].max=[1.0, inf]"],
        &["motions[0].max", "finite"],
    );
    refused(
        "footing.ron",
        &["motions[0].min=[NaN, 4.0]"],
        &["motions[0].min", "finite"],
    );
}

#[test]
fn two_motions_over_one_node_are_refused() {
    let two = concat!(
        r#"motions=[(name: "a", min: [0.0, 4.0], max: [1.0, 4.5], velocity: [None, Some(-0.01)], travel: 0.1), "#,
        r#"(name: "b", min: [0.5, 4.0], max: [1.5, 4.5], velocity: [None, Some(-0.01)], travel: 0.1)]"#
    );
    refused(
        "footing.ron",
        &[two],
        &["motions[1].min", "motions[0]", "one motion"],
    );
}

// ---- Load steps ---------------------------------------------------------------------

/// Increments that balance at once used to clear the stop each step and run past
/// max_steps for ever.
#[test]
fn a_load_in_billions_of_increments_stops_at_max_steps() {
    let dir = common::scratch("features", "increments");
    let scene = common::scene("footing_load.ron");
    let o = run_within(
        &scene,
        &dir,
        &["tractions[0].increments=4294967295", "solver.max_steps=3000"],
        Duration::from_secs(120),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&dir);
    assert_eq!(s["outcome"], "max_steps");
    assert_eq!(s["steps"], 3000);
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- Factor of safety ---------------------------------------------------------------

/// slope_fos.ron on 1 m cells with an elastic soil whose strength comes from a stage (a
/// geostatic elastic stage, then Mohr-Coulomb with the displacements zeroed).
fn slope_with_strength_in_a_stage() -> PathBuf {
    let shipped = std::fs::read_to_string(common::scene("slope_fos.ron")).unwrap();
    let text = shipped.replace(
        "cell_size: 0.5, cells: [110, 24]",
        "cell_size: 1.0, cells: [55, 12]",
    );
    assert_ne!(text, shipped, "the grid line of slope_fos.ron");
    let soil = "MohrCoulomb(density: 2038.74, youngs_modulus: 100.0e6, poisson_ratio: 0.3, \
                cohesion: 10.0e3, friction_angle: 20.0, dilatancy_angle: 0.0)";
    let start = text.find("\"soil\": MohrCoulomb(").unwrap() + "\"soil\": ".len();
    let end = start + text[start..].find(')').unwrap() + 1;
    let mut text = text.replace(
        &text[start..end],
        "LinearElastic(density: 2038.74, youngs_modulus: 100.0e6, poisson_ratio: 0.3)",
    );
    text = text.replace(
        "    solver: (",
        &format!(
            "    stages: [(name: \"geostatic\"), (name: \"strength\", materials: {{\"soil\": {soil}}}, \
             reset_displacements: true)],\n    solver: ("
        ),
    );
    let path = common::scratch("features", "fos-staged").join("slope_staged_strength.ron");
    std::fs::write(&path, text).unwrap();
    path
}

/// Strength reduction divides the strength a stage gives, as it does the scene's: the
/// factor is Griffiths & Lane's slope's, the bracket of the one-stage scene on the same
/// 1 m cells (1.40625–1.421875: `kdmpm fos scenes/slope_fos.ron --set grid.cell_size=1.0
/// --set "grid.cells=[55, 12]"`). Once the stage's strength was left whole ("above 2"),
/// and an elastic scene with a Mohr-Coulomb stage was refused.
#[test]
fn fos_reduces_the_strength_that_a_stage_gives() {
    let scene = slope_with_strength_in_a_stage();
    let out = scene.parent().unwrap().join("out");
    let o = fos_within(&scene, &out, Duration::from_secs(300));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["bracket"], serde_json::json!([1.40625, 1.421875]));
    // The mechanism is the smallest failing trial's folder.
    let trials = s["trials"].as_array().unwrap();
    let mechanism = trials.iter().find(|t| t["dir"] == s["mechanism"]).unwrap();
    assert_eq!(mechanism["failed"], true);
    assert_eq!(mechanism["factor"], 1.421875);
    let _ = std::fs::remove_dir_all(scene.parent().unwrap());
}

#[test]
fn a_bracket_without_two_ordered_factors_is_refused_by_its_own_field() {
    let scene = common::scene("slope_fos.ron");
    for bracket in ["[1.0]", "[NaN, 2.0]", "[-1.0, 2.0]", "[0.0, 2.0]", "[2.0, 1.0]"] {
        let set = format!("strength_reduction.bracket={bracket}");
        let o = kdmpm_within(
            &["fos", scene.to_str().unwrap(), "--quiet"],
            &[&set],
            Duration::from_secs(60),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{bracket}: {err}");
        assert!(
            err.contains("field `strength_reduction.bracket`"),
            "{bracket}: {err}"
        );
    }
}

#[test]
fn a_bisection_finer_than_a_trial_resolves_is_refused() {
    refused(
        "slope_fos.ron",
        &["strength_reduction.tolerance=1e-300"],
        &["strength_reduction.tolerance", "at least 1e-7"],
    );
}

#[test]
fn fos_into_a_path_that_cannot_be_a_directory_is_bad_input() {
    let dir = common::scratch("features", "fos-out");
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let scene = common::scene("slope_fos.ron");
    let o = fos_within(&scene, &file, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- Other scene rules --------------------------------------------------------------

#[test]
fn a_musl_schedule_without_the_remap_is_refused() {
    let names = "solver.schedule=[\"grid_reset\", \"spatial_sort\", \"p2g\", \"gravity\", \"boundary\", \
                 \"integrate\", \"g2p\", \"peak_watch\", \"kinematics\", \"stress_update\", \
                 \"volume_update\", \"convergence\"]";
    refused("soil_column.ron", &[names], &["solver.schedule", "remap"]);
}

#[test]
fn a_z_extent_on_a_2d_polygon_is_refused() {
    refused(
        "slope_fos.ron",
        &["bodies[0].region=Polygon(vertices: [[15.0, 0.0], [55.0, 0.0], [55.0, 10.0], [35.0, 10.0]], z: [0.0, 1.0])"],
        &["bodies[0].region.z", "2D"],
    );
}

#[test]
fn two_traced_points_of_one_name_are_refused() {
    refused(
        "soil_column.ron",
        &["traced=[(name: \"top\", position: [0.875, 9.875]), (name: \"top\", position: [0.875, 4.875])]"],
        &["traced[1].name", "traced[0]"],
    );
}

#[test]
fn masses_weights_and_damping_that_overflow_are_refused() {
    refused(
        "soil_column.ron",
        &["materials.soil.density=1e308"],
        &["materials.soil.density", "not a finite"],
    );
    refused(
        "soil_column.ron",
        &["gravity.acceleration=[0.0, -1e308]"],
        &["gravity.acceleration", "not a finite"],
    );
    refused(
        "soil_column.ron",
        &["solver.damping=Viscous(beta: 1e308)"],
        &["solver.damping", "βΔt = 1"],
    );
}

/// The memory bound holds against an address-space limit, as on a shared cluster node,
/// not only against the machine's memory: refused at once instead of an abort.
#[test]
fn a_scene_over_the_address_space_limit_is_refused_quickly() {
    let scene = common::scene("block_1m.ron");
    let start = Instant::now();
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 4000000 && exec {} check {} --set 'bodies[0].points_per_cell=[8, 8, 8]'",
            env!("CARGO_BIN_EXE_kdmpm"),
            scene.display()
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("address-space limit"), "{err}");
    assert!(start.elapsed() < Duration::from_secs(10));
}

// ---- Output -------------------------------------------------------------------------

/// A tolerance near the largest float once made convergence.svg's axis infinite, and
/// drawing it never returned.
#[test]
fn a_huge_tolerance_draws_its_plots_and_plot_returns() {
    let dir = common::scratch("features", "huge-tolerance");
    let scene = common::scene("bar.ron");
    let o = run_within(&scene, &dir, &["solver.tolerance=5e307"], Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = kdmpm_within(&["plot", dir.to_str().unwrap()], &[], Duration::from_secs(60));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("convergence.svg").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Starts the failing slope (a run of some seconds) into `dir`, its stderr piped.
fn start_slope(dir: &Path) -> std::process::Child {
    let scene = common::scene("slope.ron");
    Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--quiet",
            "--set",
            "output.snapshots=None",
            "--out",
        ])
        .arg(dir)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// A new run into a directory removes what the run before left as results and what a
/// killed process left half-written, before it writes anything: a crash of the new run
/// leaves nothing old looking current.
#[test]
fn a_new_run_leaves_no_earlier_result_or_partial_file_beside_its_history() {
    let dir = common::scratch("features", "stale-results");
    for f in [
        "summary.json",
        "points.vtu",
        "curve.csv",
        "stages.csv",
        "curve.svg",
        "points.pvd",
    ] {
        std::fs::write(dir.join(f), "from an earlier run").unwrap();
    }
    std::fs::write(dir.join("summary.json.partial-999999"), "half").unwrap();
    let mut child = start_slope(&dir);
    common::wait_until_running(&dir);
    child.kill().unwrap();
    child.wait().unwrap();
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n != "history.csv" && n != ".kdmpm.lock")
        .collect();
    assert!(left.is_empty(), "left beside the new history: {left:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM, what a batch scheduler sends before its limit, is handled as Ctrl-C: the run
/// checkpoints and exits 130, and resumes.
#[test]
fn sigterm_checkpoints_like_ctrl_c() {
    let dir = common::scratch("features", "sigterm");
    let child = start_slope(&dir);
    common::interrupt(child, &dir, "TERM");
    assert_eq!(summary(&dir)["outcome"], "interrupted");
    assert!(dir.join("checkpoint.kdc").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

// ---- Studies ------------------------------------------------------------------------

fn study_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text.replace("SCENES", common::scene("").to_str().unwrap())).unwrap();
    path
}

/// Runs `kdmpm study` on `study` into `out`, which must refuse it as bad input (exit 2),
/// and returns its message.
fn study_refusal(study: &Path, out: &Path) -> String {
    let o = common::study_into(study, out);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    err
}

/// A reference that ended at max_steps once gave every run an error against a state that
/// is not static (52 %, all on the Pareto front); the study now stops and says so.
#[test]
fn a_study_refuses_a_reference_run_that_did_not_converge() {
    let dir = common::scratch("features", "study-reference");
    let study = study_file(
        &dir,
        "s.ron",
        r#"Study(
    scene: "SCENES/soil_column.ron",
    reference: ["solver.max_steps=20"],
    axes: [Set(path: "solver.tolerance", values: ["1e-3"])],
    quantities: [(name: "u top", of: Displacement(point: "top", component: 1), compare: Reference)],
)"#,
    );
    let out = dir.join("out");
    let o = kdmpm_within(
        &[
            "study",
            study.to_str().unwrap(),
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
        Duration::from_secs(120),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("did not converge") && err.contains("max_steps"),
        "{err}"
    );
    assert!(!out.join("study.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `LimitPressure` reads a run's `limit_pressure` (the footing at h = 0.25 m: 50.33 kPa,
/// −2.1 % on Prandtl's 51.42 kPa), and is refused on a scene without a loaded motion;
/// `MeanPressure` reads the mean of a curve row's pressures, and is refused for a row the
/// scene does not have.
#[test]
fn a_study_measures_a_limit_and_a_mean_pressure_and_refuses_what_the_scene_lacks() {
    let dir = common::scratch("features", "study-limit-pressure");
    let quantity = r#"quantities: [(name: "p", of: LimitPressure, compare: Analytic(51415.93))]"#;
    let steady =
        r#"(name: "mean", of: MeanPressure(name: "footing", from: 0.05), compare: Analytic(51415.93))"#;
    let study = study_file(
        &dir,
        "footing.ron",
        &format!(
            r#"Study(scene: "SCENES/footing.ron", axes: [Set(path: "solver.tolerance", values: ["0.01"])], {})"#,
            quantity.replace(")]", &format!("), {steady}]"))
        ),
    );
    let out = dir.join("out");
    let args = [
        "study",
        study.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = kdmpm_within(&args, &[], Duration::from_secs(120));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let row: Vec<&str> = table.lines().nth(1).unwrap().split(',').collect();
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let col = |name: &str| {
        row[header.iter().position(|h| *h == name).unwrap()]
            .parse::<f64>()
            .unwrap()
    };
    // study.csv holds seven significant digits.
    assert!(common::rel(col("p"), 50328.64).abs() < 1e-6, "{table}");
    assert!(
        common::rel(col("error p"), 50328.638082202015 / 51415.93 - 1.0).abs() < 1e-6,
        "{table}"
    );
    // `MeanPressure`: the mean of the static pressures from 5 cm on (the six of
    // docs/verification.md's table, 48.71 to 50.33 kPa).
    assert!(
        common::rel(col("mean"), 49660.135411108095).abs() < 1e-6,
        "{table}"
    );
    let unknown = study_file(
        &dir,
        "unknown.ron",
        &format!(
            r#"Study(scene: "SCENES/footing.ron", axes: [Set(path: "solver.tolerance", values: ["0.01"])], quantities: [{}])"#,
            steady.replace("\"footing\"", "\"cone\"")
        ),
    );
    let err = study_refusal(&unknown, &dir.join("out3"));
    assert!(
        err.contains("no curve row `cone`") && err.contains("are footing"),
        "{err}"
    );
    let column = study_file(
        &dir,
        "column.ron",
        &format!(
            r#"Study(scene: "SCENES/soil_column.ron", axes: [Set(path: "solver.tolerance", values: ["1e-3"])], {quantity})"#
        ),
    );
    let err = study_refusal(&column, &dir.join("out2"));
    assert!(err.contains("no motion with a loaded `area`"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// SIGTERM to a study reaches the run under way, which is waited for: no run is left
/// holding its directory, and the study exits 130.
#[test]
fn sigterm_to_a_study_stops_its_run_and_waits_for_it() {
    let dir = common::scratch("features", "study-sigterm");
    let study = study_file(
        &dir,
        "s.ron",
        r#"Study(
    scene: "SCENES/slope.ron",
    set: ["output.snapshots=None"],
    axes: [Set(path: "solver.tolerance", values: ["1e-2", "1e-3"])],
    quantities: [(name: "angle", of: SurfaceAngle, compare: Analytic(20.0))],
)"#,
    );
    let out = dir.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args(["study", study.to_str().unwrap(), "--quiet", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_until_running(&out.join("run-001"));
    common::signal(child.id(), "TERM");
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    // The run was stopped as by Ctrl-C (its summary says so) and released its directory.
    assert_eq!(summary(&out.join("run-001"))["outcome"], "interrupted");
    assert!(kdmpm::output::OutputDir::claim(&out.join("run-001")).is_ok());
    assert!(!out.join("run-001").join(kdmpm::study::RECORD).exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Volumetric smoothing on a dilatant soil (the c–φ footing of docs/verification.md) once
/// ran until "kinetic energy exceeds 10× the external work"; it is refused with the reason.
#[test]
fn volumetric_smoothing_on_a_dilatant_soil_is_refused() {
    refused(
        "footing.ron",
        &[
            "solver.anti_locking=StrainSmoothing",
            "materials.clay=MohrCoulomb(density: 2000.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3, \
             cohesion: 10.0e3, friction_angle: 30.0, dilatancy_angle: 30.0)",
        ],
        &["solver.anti_locking", "\"clay\" dilates", "ψ = 0"],
    );
}

/// `kdmpm triaxial` writes triaxial.csv only for a test that ran to its end: one that
/// stops (the oedometer's clay from 2 MPa runs out of voids at increment 1 252, exit 1)
/// removes the csv an earlier test left in the same directory, so that it is not read as
/// this test's. A test refused at its input (exit 2) writes nothing.
#[test]
fn a_triaxial_test_that_stops_leaves_no_earlier_csv_behind() {
    let scene = common::scene("clay_oedometer.ron");
    let out = common::scratch("robustness", "triaxial-stale");
    let test = |p0: &str| {
        let args = [
            "triaxial",
            scene.to_str().unwrap(),
            "--material",
            "clay",
            "--cell-pressure",
            p0,
            "--steps",
            "1500",
            "--out",
            out.to_str().unwrap(),
        ];
        kdmpm_within(&args, &[], Duration::from_secs(60))
    };
    let csv = out.join("triaxial.csv");
    assert_eq!(test("1e5").status.code(), Some(0));
    assert!(csv.exists());
    let o = test("2e6");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("no voids left"), "{err}");
    assert!(!csv.exists());
    assert_eq!(test("5e6").status.code(), Some(2));
    assert!(!csv.exists());
}
