//! Nothing silently wrong: one regression test per class of bad or extreme input that once
//! gave a wrong answer, a panic, a hang or a NaN. Each either gives the right answer or
//! exits 2 with a message naming the field and the rule; a run that goes wrong exits 1 and
//! writes neither NaN nor null.

use crate::common;

use kdmpm::components::NodeAcceleration;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Dim2, FnSystem, StepError};
use std::path::{Path, PathBuf};
use std::process::Command;

/// `kdmpm check` of `scene` with `sets` exits 2 with one message holding every `expect`.
fn refused(scene: &Path, sets: &[&str], expect: &[&str]) {
    let mut args = vec!["check", scene.to_str().unwrap()];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = common::kdmpm(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{sets:?}: {err}");
    assert!(err.starts_with("error: "), "{sets:?}: {err}");
    for e in expect {
        assert!(err.contains(e), "{sets:?}: expected `{e}` in: {err}");
    }
    assert_eq!(err.trim_end().lines().count(), 1, "{sets:?}: one line: {err}");
}

fn column() -> PathBuf {
    common::scene("soil_column.ron")
}

/// The column's top settles by ρgH²/(2M) = 1800·9.81·10²/(2·13.46 MPa) = 0.06559 m (the
/// oedometric answer given in scenes/soil_column.ron), ramped gravity or not; once the
/// first step's ramp factor of 0 made K_F = K_E = 0/0 count as met.
#[test]
fn a_run_is_not_converged_while_its_load_still_ramps() {
    let s = common::run("soil_column.ron", &["gravity.ramp_time=1.0"]);
    assert!(s.converged);
    assert!(s.time > 1.0, "stopped at t = {} s, inside the 1 s ramp", s.time);
    let m = 10.0e6 * 0.7 / (1.3 * 0.4);
    let analytic = 1800.0 * 9.81 * 100.0 / (2.0 * m);
    let top = s.traced[1].displacement[1];
    assert!(
        (top / -analytic - 1.0).abs() < 0.01,
        "top {top} m, analytic {analytic} m"
    );
}

#[test]
fn a_scene_without_load_is_refused_rather_than_converged() {
    refused(
        &column(),
        &["gravity.acceleration=[0.0, 0.0]"],
        &["gravity.acceleration", "no load"],
    );
}

#[test]
fn an_undefined_ratio_is_an_empty_cell_never_met_and_never_nan() {
    // With gravity ramping from 0, the first step has no external force at all.
    let dir = common::scratch("robust", "undefined");
    let out = dir.join("out");
    let sets = ["gravity.ramp_time=1.0", "output.history_every=1"];
    let o = common::run_into(&column(), &out, &sets);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    // step, time, E_k, W_ext, then K_F (max), K_F (mean) and K_E: empty at step 1.
    let first: Vec<&str> = history.lines().nth(1).unwrap().split(',').collect();
    assert_eq!(first[4..7], ["", "", ""], "{first:?}");
    assert!(!history.contains("undefined"));
    assert!(!history.to_lowercase().contains("nan") && !history.contains("inf"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_finite_or_negative_tension_cutoffs_are_refused() {
    for v in ["NaN", "-1.0", "-inf", "inf"] {
        refused(
            &column(),
            &[&format!("materials.soil.tension_cutoff={v}")],
            &[
                "materials.soil.tension_cutoff",
                "finite stress ≥ 0 Pa",
                "set by --set",
            ],
        );
    }
}

#[test]
fn a_material_named_twice_is_refused() {
    let dir = common::scratch("robust", "twice");
    let text = std::fs::read_to_string(column()).unwrap().replace(
        "\"soil\": MohrCoulomb(",
        "\"soil\": LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0),\n        \"soil\": MohrCoulomb(",
    );
    let scene = dir.join("twice.ron");
    std::fs::write(&scene, text).unwrap();
    refused(&scene, &[], &["twice.ron:12:", "\"soil\" is given twice"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn sizes_that_overflow_or_exceed_the_machine_are_refused_before_allocation() {
    let c = column();
    refused(
        &c,
        &["grid.cells=[4, 18446744073709551615]"],
        &["grid.cells", "overflows"],
    );
    refused(
        &c,
        &["bodies[0].points_per_cell=[4294967296, 4294967296]"],
        &["points_per_cell", "overflows"],
    );
    refused(
        &c,
        &["grid.cells=[4000000, 4000000]"],
        &["grid", "GB", "more than this machine"],
    );
    refused(
        &c,
        &["bodies[0].points_per_cell=[100000, 100000]"],
        &["GB", "more than this machine"],
    );
}

#[test]
fn cells_of_zero_or_infinite_volume_are_refused() {
    refused(
        &column(),
        &["grid.cell_size=1e-200"],
        &["grid.cell_size", "cell volume"],
    );
    refused(
        &column(),
        &["grid.cell_size=1e200"],
        &["grid.cell_size", "cell volume"],
    );
}

#[test]
fn time_steps_that_do_not_advance_the_clock_are_refused() {
    let c = column();
    refused(
        &c,
        &["solver.time_step=Courant(5e-324)"],
        &["solver.time_step", "too small"],
    );
    refused(&c, &["solver.time_step=Fixed(5e-324)"], &["solver.time_step"]);
    // The stiffest E allowed over a density near the smallest double: M/ρ overflows; over
    // a density of 1e-6 kg/m³ the step is 1.4e-11 s, 1.5e12 steps to max_time.
    refused(
        &c,
        &[
            "materials.soil.youngs_modulus=1e15",
            "materials.soil.density=1e-300",
        ],
        &["P-wave speed"],
    );
    refused(
        &c,
        &[
            "materials.soil.youngs_modulus=1e15",
            "materials.soil.density=1e-6",
        ],
        &["solver.max_time", "steps"],
    );
    refused(
        &c,
        &["materials.soil.youngs_modulus=1e308"],
        &["materials.soil.youngs_modulus", "at most 1e15 Pa"],
    );
}

#[test]
fn non_finite_gravity_loads_and_coordinates_are_refused() {
    let c = column();
    refused(
        &c,
        &["gravity.acceleration=[0.0, NaN]"],
        &["gravity.acceleration", "finite"],
    );
    refused(
        &c,
        &["gravity.acceleration=[inf, -9.81]"],
        &["gravity.acceleration", "finite"],
    );
    refused(&c, &["grid.origin=[0.0, -inf]"], &["grid.origin", "finite"]);
    refused(
        &c,
        &["traced[0].position=[NaN, 1.0]"],
        &["traced[0].position", "finite"],
    );
    let bar = common::scene("bar.ron");
    refused(
        &bar,
        &["point_loads[0].force=[NaN, 0.0, 0.0]"],
        &["point_loads[0].force", "finite"],
    );
}

#[test]
fn polygons_that_cross_themselves_and_bodies_that_overlap_are_refused() {
    let slope = common::scene("slope.ron");
    refused(
        &slope,
        &["bodies[0].region=Polygon(vertices: [[0.0, 0.0], [10.0, 10.0], [10.0, 0.0], [0.0, 4.0]])"],
        &["bodies[0].region.vertices", "cross"],
    );
    refused(
        &column(),
        &["bodies=[(material: \"soil\", region: Box(min: [0.0, 0.0], max: [2.0, 6.0]), points_per_cell: [2, 2]), \
           (material: \"soil\", region: Box(min: [0.0, 4.0], max: [2.0, 10.0]), points_per_cell: [2, 2])]"],
        &["bodies[1].region", "overlaps bodies[0]"],
    );
    refused(
        &column(),
        &["boundaries=[(face: YMin, condition: Fixed), (face: YMin, condition: Roller)]"],
        &["boundaries[1].face", "already has a condition"],
    );
}

#[test]
fn overrides_are_parsed_strictly_and_errors_point_into_the_file_as_written() {
    let c = column();
    refused(&c, &["solver.max_steps[oops]=7"], &["[oops]", "not an index"]);
    refused(&c, &["bodies[0]x.material=\"soil\""], &["not part of a path"]);
    // An override that adds lines before the faulty field does not move the position: the
    // tolerance stands on line 36, column 9 of the file.
    refused(
        &c,
        &["dimension=\n\n\n2", "solver.tolerance=-1.0"],
        &[
            "soil_column.ron:36:9",
            "solver.tolerance",
            "set by --set `solver.tolerance=-1.0`",
        ],
    );
    refused(
        &c,
        &["dimension=\n\n\n2", "solver.tolerance=[0"],
        &["soil_column.ron:36:", "set by --set"],
    );
}

#[test]
fn an_override_on_a_file_with_an_unterminated_string_is_an_error_not_a_panic() {
    let dir = common::scratch("robust", "unterminated");
    let scene = dir.join("s.ron");
    for text in [
        "Scene(materials: {\"soil",
        "Scene(a: \"",
        "Scene(\"",
        "Scene(é: 1, \"\\é",
        "(",
        "\"",
    ] {
        std::fs::write(&scene, text).unwrap();
        let o = common::kdmpm(&["check", scene.to_str().unwrap(), "--set", "solver.tolerance=1"]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{text}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_second_run_into_an_output_directory_in_use_is_refused() {
    let dir = common::scratch("robust", "lock");
    let out = dir.join("out");
    let slope = common::scene("slope.ron");
    let mut first = Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args([
            "run",
            slope.to_str().unwrap(),
            "--quiet",
            "--threads",
            "1",
            "--out",
        ])
        .arg(&out)
        .spawn()
        .unwrap();
    while !out.join("history.csv").exists() {
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let c = column();
    let second = || {
        common::kdmpm(&[
            "run",
            c.to_str().unwrap(),
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = second();
    let err = String::from_utf8_lossy(&o.stderr);
    first.kill().unwrap();
    first.wait().unwrap();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("in use by another run") && err.contains(&format!("process {}", first.id())),
        "{err}"
    );
    // Once the holder is gone the directory is free again, whatever it left behind.
    let o = second();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A non-finite value met while stepping stops the run at the step that met it, before any
/// point moves with it: the state stays finite and the summary holds no null or NaN.
#[test]
fn a_non_finite_value_stops_the_run_with_the_last_finite_state() {
    let loaded = LoadedScene::from_file(&column(), &[]).unwrap();
    let AnySimulation::Two(mut s) = build(&loaded).unwrap().0 else {
        unreachable!("the column is 2D")
    };
    let sim = &mut s;
    {
        let poison = FnSystem::new("poison", |ctx: &mut kdmpm::Context<Dim2>| {
            if ctx.state.clock.step == 40 {
                let n = kdmpm::infra::columns::nodes(&ctx.world);
                let mut a = kdmpm::infra::columns::col_mut::<NodeAcceleration<glam::DVec2>>(n);
                for x in a.iter_mut() {
                    x.0 *= f64::NAN;
                }
            }
            Ok(())
        });
        assert!(sim.schedule.insert_after("integrate", poison));
        let e = sim.run(|_| {}).unwrap_err();
        assert!(
            matches!(
                e,
                StepError::NonFinite {
                    step: 40,
                    system: "g2p",
                    ..
                }
            ),
            "{e}"
        );
        let text = e.to_string();
        assert!(
            text.contains("point") && text.contains("smaller time step"),
            "{text}"
        );
        // Positions, stresses and the rest stay those of step 39; the velocities do not
        // (the NaN accelerations reached them), so points.vtu is not written.
        let left = sim.first_non_finite().unwrap_or_default();
        assert!(left.starts_with("velocity of point"), "{left}");
        let summary = kdmpm::output::Summary::collect("c", sim, 1.0, Some(text));
        let json = serde_json::to_string(&summary).unwrap();
        assert!(
            !json.contains("null") && !json.to_lowercase().contains("nan"),
            "{json}"
        );
        assert_eq!(summary.outcome, kdmpm::output::Outcome::Failed);
        assert!(summary.kinetic_energy.is_finite() && summary.kinetic_energy > 0.0);
    }
}

#[test]
fn a_failed_run_writes_neither_null_nor_nan() {
    // The column without its fixed base falls through the bottom of the grid (exit 1).
    let dir = common::scratch("robust", "failed");
    let out = dir.join("out");
    let column = common::scene("soil_column.ron");
    let o = common::kdmpm(&[
        "run",
        column.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "boundaries=[(face: XMin, condition: Roller), (face: XMax, condition: Roller)]",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(
        !summary.contains("null") && summary.contains("\"outcome\": \"failed\""),
        "{summary}"
    );
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert!(!history.to_lowercase().contains("nan") && history.ends_with('\n'));
    assert!(out.join("points.vtu").exists());
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".partial"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `kdmpm check scene.ron | head -3`: the reader closes the pipe after three lines and the
/// command ends quietly, as other command-line tools do, instead of panicking on the write.
#[test]
fn a_reader_that_closes_the_pipe_ends_the_command_without_a_panic() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_kdmpm"))
        .args(["check", common::scene("tbar.ron").to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("kdmpm starts");
    // The read end closes before kdmpm writes its report.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("kdmpm ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_ne!(out.status.code(), Some(101), "{stderr}");
}
