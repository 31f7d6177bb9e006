//! The discretisation error by refinement (`--refine` of `kdmpm run` and `kdmpm fos`),
//! pinned on coarse settings; the shipped-resolution figures are in docs/verification.md.

use crate::common;

use kdmpm::refine::{factor_of_safety, finer, limit_pressure, pressure, RunQuantity};
use kdmpm::scene::{LoadedScene, TimeStep};

fn loaded(name: &str, sets: &[&str]) -> LoadedScene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    LoadedScene::from_file(&common::scene(name), &sets).expect("scene loads")
}

fn summary_refinement(out: &std::path::Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let summary: serde_json::Value = serde_json::from_str(&text).expect("json");
    summary["refinement"].clone()
}

#[test]
fn a_finer_scene_halves_the_cells_and_counts_steps_twice() {
    let l = loaded(
        "bar.ron",
        &["solver.max_steps=Some(1000)", "output.history_every=3"],
    );
    let f = finer(&l, 2).expect("the overrides apply");
    let (a, b) = (&l.scene, &f.scene);
    assert_eq!(b.grid.cell_size, a.grid.cell_size / 2.0);
    assert_eq!(
        b.grid.cells,
        a.grid.cells.iter().map(|c| 2 * c).collect::<Vec<_>>()
    );
    assert_eq!(b.grid.origin, a.grid.origin);
    assert_eq!(b.solver.time_step, TimeStep::Fixed(0.005));
    assert_eq!(b.solver.max_steps, Some(2000));
    assert_eq!(b.output.history_every, 6);
    assert_eq!(b.bodies[0].points_per_cell, a.bodies[0].points_per_cell);
}

/// The finer scene is written into the scene's text, which a checkpoint keeps: read back
/// from that text alone it is the same scene, so a finer run resumes at its own cell size.
/// `soil_column.ron` with its `output` block removed: the refinement writes one.
#[test]
fn a_finer_scene_read_back_from_its_text_is_the_same_scene() {
    let path = common::scene("soil_column.ron");
    let text = std::fs::read_to_string(&path).expect("scene");
    let at = text.find("output:").expect("an output block");
    let end = at + text[at..].find("),").expect("its end") + 2;
    let text = format!("{}{}", &text[..at], &text[end..]);
    let l = LoadedScene::from_text(&path, &text, &["solver.max_steps=500".into()]).expect("scene");
    assert_eq!(l.scene.output.history_every, 1);
    let f = finer(&l, 4).expect("the overrides apply");
    assert_eq!(f.scene.output.history_every, 4);
    assert_eq!(f.scene.solver.max_steps, Some(2000));
    let back = LoadedScene::from_text(&path, &f.text, &[]).expect("the finer text parses");
    assert_eq!(back.scene, f.scene);
}

/// `footing.ron` (volumetric smoothing) from h = 0.5 m: 50.44 and 50.33 kPa at h = 0.5 and
/// 0.25 m. The difference (0.11 kPa) is below what each answer resolves (K_F ≤ 0.01 of
/// 50 kPa): no trend, so nothing is extrapolated and the report gives the spread instead
/// (Prandtl: 51.42 kPa). A third level, h = 0.125 m, gives 50.11 kPa, 0.22 kPa lower: still
/// no clean order (`kdmpm run scenes/footing.ron --set grid.cell_size=0.5 --set
/// "grid.cells=[12, 9]" --refine`; src/refine.rs tests the three-level rules).
#[test]
fn a_footing_whose_answers_differ_by_less_than_they_resolve_reports_its_spread() {
    let out = common::scratch("refine", "footing");
    let l = loaded("footing.ron", &["grid.cell_size=0.5", "grid.cells=[12, 9]"]);
    let (report, r) = limit_pressure(&l, &out, 2, true, |_| {}).expect("two runs");
    let values: Vec<f64> = r.levels.iter().map(|l| l.value).collect();
    let pinned = [50438.413886499286, 50328.638082202015];
    for (v, p) in values.iter().zip(pinned) {
        assert!(common::rel(*v, p).abs() < 1e-9, "{values:?}");
    }
    assert_eq!(values.len(), 2);
    assert_eq!(report.summary.limit_pressure, Some(values[0]));
    assert_eq!(r.extrapolated, None);
    assert!(r.note.contains("less than they resolve"), "{}", r.note);
    assert!(common::rel(r.spread, pinned[0] - pinned[1]).abs() < 1e-12);
    // The scene's own run is in `out`, the finer one under refine/, and summary.json says
    // so without an extrapolated value (never null).
    let written = summary_refinement(&out);
    assert_eq!(written["levels"][1]["dir"], "refine/h0.25");
    assert!(written.get("extrapolated").is_none());
    assert!(out.join("refine/h0.25/curve.csv").is_file());
}

/// A penetrometer's answer is its steady resistance, the mean of its static states over a
/// window of travel, not the largest: `--mean-from ROW=FROM` refines that. `footing.ron`
/// at h = 0.5 and 0.25 m, the mean pressure of its states from 5 cm on, is each level's
/// mean of those rows of `curve.csv`, known to the stopping tolerance or to the standard
/// error of the mean, whichever is larger.
#[test]
fn a_mean_pressure_over_a_window_of_travel_is_refined_as_a_limit_pressure_is() {
    let out = common::scratch("refine", "mean");
    let l = loaded("footing.ron", &["grid.cell_size=0.5", "grid.cells=[12, 9]"]);
    let what = RunQuantity::MeanPressure {
        row: "footing".into(),
        from: 0.05,
    };
    let (_, r) = pressure(&l, &out, 2, true, &what, |_| {}).expect("two runs");
    assert_eq!(r.quantity, "mean_pressure");
    for (level, dir) in r.levels.iter().zip([out.clone(), out.join("refine/h0.25")]) {
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
        let states: Vec<f64> = summary["curve"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["name"] == "footing" && c["displacement"].as_f64().unwrap() >= 0.05)
            .map(|c| c["pressure"].as_f64().unwrap())
            .collect();
        assert_eq!(states.len(), 6, "{dir:?}");
        let mean = states.iter().sum::<f64>() / 6.0;
        assert!(
            (level.value / mean - 1.0).abs() < 1e-12,
            "{} against {mean}",
            level.value
        );
        assert!(level.resolution >= 0.01 * mean, "{}", level.resolution);
    }
    assert_eq!([r.levels[0].value, r.levels[1].value], PINNED_MEANS);
}

/// The means `a_mean_pressure_over_a_window_…` pins (Pa).
const PINNED_MEANS: [f64; 2] = [48213.085038001176, 49660.135411108095];

/// A row that has no pressure, a window that is not a displacement, or `--mean-from`
/// without `--refine`: refused with the reason (exit 2) before anything runs.
#[test]
fn a_mean_pressure_of_a_row_without_an_area_or_without_refine_is_refused() {
    let out = common::scratch("refine", "mean-refused");
    let footing = common::scene("footing.ron");
    let f = footing.to_str().unwrap();
    let o = out.to_str().unwrap();
    for (args, says) in [
        (
            vec!["run", f, "--out", o, "--refine", "2", "--mean-from", "pile=0.1"],
            "no curve row `pile`",
        ),
        (
            vec!["run", f, "--out", o, "--refine", "2", "--mean-from", "footing=-1"],
            "must be ≥ 0 m",
        ),
        (
            vec!["run", f, "--out", o, "--refine", "2", "--mean-from", "footing"],
            "give ROW=FROM",
        ),
        (
            vec!["run", f, "--out", o, "--mean-from", "footing=0.1"],
            "--refine",
        ),
    ] {
        let r = common::kdmpm(&args);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    assert!(!out.join("summary.json").exists(), "nothing is run");
}

/// `slope_fos.ron` from h = 2.5 m with two cell sizes: 1.4453 at h = 2.5 m, 1.4141 at 1.25 m;
/// order 1 assumed, extrapolated 2·1.4141 − 1.4453 = 1.3828 (Bishop 1.378), so the answer
/// at h = 2.5 m is 0.0625 above it. (From the shipped h = 0.5 m: 1.3828 at 0.5 m, 1.3516
/// extrapolated from h = 1 m and 0.5 m, docs/verification.md.)
#[test]
fn two_cell_sizes_of_the_slope_extrapolate_at_first_order() {
    let out = common::scratch("refine", "slope");
    let l = loaded("slope_fos.ron", &COARSE_SLOPE);
    let (report, r) = factor_of_safety(&l, &out, 2, |_, _| {}).expect("two analyses");
    assert_eq!(r.levels[0].value, report.factor_of_safety);
    assert_eq!(r.levels[0].value, 1.4453125);
    assert_eq!(r.levels[1].value, 1.4140625);
    assert_eq!(r.order_used, Some(1.0));
    assert!((r.extrapolated.unwrap() - 1.3828125).abs() < 1e-12);
    assert!((r.error.unwrap() - 0.0625).abs() < 1e-12);
    assert!((summary_refinement(&out)["extrapolated"].as_f64().unwrap() - 1.3828125).abs() < 1e-12);
}

/// `slope_fos.ron` on 2.5 m cells, whose grid ends at the body's back at x = 55 m as the
/// shipped one does (h and h/2 of the refinement tests of the factor of safety).
const COARSE_SLOPE: [&str; 2] = ["grid.cell_size=2.5", "grid.cells=[22, 5]"];

/// The same slope at a tolerance too coarse to tell h from h/2 (0.1: the two answers are
/// 1.46875 and 1.40625, a bracket's width apart): `--refine` bisects each on, a trial at a
/// time, until they are resolved, and gives the estimate the scene's tolerance gives
/// (1.4453125, 1.4140625 as above). Once it said only that the answers differ by less than
/// they resolve.
#[test]
fn answers_closer_than_their_brackets_are_bisected_on_until_resolved() {
    let out = common::scratch("refine", "narrowed");
    let mut sets = COARSE_SLOPE.to_vec();
    sets.push("strength_reduction.tolerance=0.1");
    let l = loaded("slope_fos.ron", &sets);
    let (report, r) = factor_of_safety(&l, &out, 2, |_, _| {}).expect("two analyses");
    assert_eq!(r.levels[0].value, 1.4453125);
    assert_eq!(r.levels[1].value, 1.4140625);
    assert_eq!(r.levels[0].resolution, 1.0 / 128.0);
    assert_eq!(report.factor_of_safety, 1.4453125);
    assert_eq!(report.tolerance, 0.025);
    assert!((r.extrapolated.unwrap() - 1.3828125).abs() < 1e-12, "{}", r.note);
    // The narrowing trials are the analysis's own: in its table and its folders.
    let table = std::fs::read_to_string(out.join("fos.csv")).unwrap();
    assert_eq!(table.lines().count(), 1 + report.trials.len());
    assert!(out.join("trials/F1.453125").is_dir());
    let fine: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("refine/h1.25/summary.json")).unwrap())
            .unwrap();
    assert_eq!(fine["factor_of_safety"], 1.4140625);
}

#[test]
fn a_refinement_without_a_limit_pressure_or_with_four_levels_is_bad_input() {
    let out = common::scratch("refine", "refused");
    let bar = common::scene("bar.ron");
    let o = common::kdmpm(&[
        "run",
        bar.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--refine",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no motion with a loaded `area`"), "{err}");
    let footing = common::scene("footing.ron");
    let o = common::kdmpm(&[
        "run",
        footing.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--refine",
        "4",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--refine takes 2 or 3 cell sizes"), "{err}");
    assert!(!out.join("summary.json").exists(), "nothing is run");
}

/// `kdmpm study` with a `Refine` axis runs the scenes `--refine` runs (one list of what a
/// refinement changes), and a `FactorOfSafety` quantity makes each run a `kdmpm fos`: the
/// slope from h = 2.5 m gives 1.4453 and 1.4141, as `two_cell_sizes_of_the_slope_…` pins.
#[test]
fn a_study_of_the_factor_of_safety_refines_as_refine_does() {
    let dir = common::scratch("refine", "study-fos");
    let scenes = common::scene("");
    let study = dir.join("s.ron");
    let text = format!(
        r#"Study(
    scene: "{}/slope_fos.ron",
    set: ["grid.cell_size=2.5", "grid.cells=[22, 5]"],
    axes: [Refine([1, 2])],
    quantities: [(name: "F", of: FactorOfSafety, compare: Analytic(1.378))],
)"#,
        scenes.display()
    );
    std::fs::write(&study, text).unwrap();
    let out = dir.join("out");
    let o = common::study_into(&study, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = table.lines().skip(1).map(|l| l.split(',').collect()).collect();
    for (row, pinned) in rows.iter().zip([1.4453125, 1.4140625]) {
        assert_eq!(row[at("outcome")], "bracketed", "{table}");
        assert!(
            common::rel(row[at("F")].parse().unwrap(), pinned).abs() < 1e-6,
            "{table}"
        );
    }
    assert!(
        out.join("run-002/trials").is_dir(),
        "each run is a strength reduction"
    );
}

/// A factor of safety is a whole analysis's answer: a study of it measures nothing else,
/// and needs a scene with `strength_reduction`.
#[test]
fn a_study_of_the_factor_of_safety_is_refused_beside_another_quantity_or_without_one() {
    let dir = common::scratch("refine", "study-fos-refused");
    let scenes = common::scene("");
    for (scene, quantities, says) in [
        (
            "slope_fos.ron",
            r#"(name: "F", of: FactorOfSafety, compare: Analytic(1.378)), (name: "u", of: MaxDisplacement, compare: Analytic(1.0))"#,
            "measures nothing else",
        ),
        (
            "footing.ron",
            r#"(name: "F", of: FactorOfSafety, compare: Analytic(1.378))"#,
            "no `strength_reduction`",
        ),
    ] {
        let study = dir.join("s.ron");
        let text = format!(
            r#"Study(scene: "{}/{scene}", axes: [Refine([1])], quantities: [{quantities}])"#,
            scenes.display()
        );
        std::fs::write(&study, text).unwrap();
        let o = common::study_into(&study, &dir.join("out"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("quantities[") && err.contains(says), "{err}");
    }
}
