//! The discretisation error by refinement (`--refine` of `kdmpm run` and `kdmpm fos`),
//! pinned on coarse settings; the shipped-resolution figures are in docs/verification.md.

mod common;

use kdmpm::refine::{factor_of_safety, finer, limit_pressure};
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
    let f = finer(&l, 2);
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

/// `footing.ron` from h = 0.5 m: 57.15, 55.58, 52.92 kPa at h = 0.5, 0.25, 0.125 m. The
/// differences grow (1.56, then 2.66 kPa): no clean order, so nothing is extrapolated and
/// the report gives the spread instead (Prandtl: 51.42 kPa).
#[test]
fn the_coarse_footing_has_no_clean_order_and_reports_its_spread() {
    let out = common::scratch("refine", "footing");
    let l = loaded("footing.ron", &["grid.cell_size=0.5", "grid.cells=[12, 9]"]);
    let (report, r) = limit_pressure(&l, &out, 3, true, |_| {}).expect("three runs");
    let values: Vec<f64> = r.levels.iter().map(|l| l.value).collect();
    let pinned = [57145.346709844525, 55584.285930086546, 52923.729046678855];
    for (v, p) in values.iter().zip(pinned) {
        assert!(common::rel(*v, p) < 1e-9, "{values:?}");
    }
    assert_eq!(report.summary.limit_pressure, Some(values[0]));
    assert_eq!(r.extrapolated, None);
    assert!(r.note.contains("do not shrink"), "{}", r.note);
    assert!(common::rel(r.spread, pinned[0] - pinned[2]) < 1e-12);
    // The scene's own run is in `out`, the finer ones under refine/, and summary.json says
    // so without an extrapolated value (never null).
    let written = summary_refinement(&out);
    assert_eq!(written["levels"][2]["dir"], "refine/h0.125");
    assert!(written.get("extrapolated").is_none());
    assert!(out.join("refine/h0.25/curve.csv").is_file());
}

/// `slope_fos.ron` from h = 1 m with two cell sizes: 1.4609 at h = 1 m, 1.4141 at 0.5 m;
/// order 1 assumed, extrapolated 2·1.4141 − 1.4609 = 1.3672 (Bishop 1.378), so the answer
/// at h = 1 m is 0.094 above it.
#[test]
fn two_cell_sizes_of_the_slope_extrapolate_at_first_order() {
    let out = common::scratch("refine", "slope");
    let l = loaded("slope_fos.ron", &["grid.cell_size=1.0", "grid.cells=[55, 12]"]);
    let (report, r) = factor_of_safety(&l, &out, 2, |_, _| {}).expect("two analyses");
    assert_eq!(r.levels[0].value, report.factor_of_safety);
    assert_eq!(r.levels[0].value, 1.4609375);
    assert_eq!(r.levels[1].value, 1.4140625);
    assert_eq!(r.order_used, Some(1.0));
    assert!((r.extrapolated.unwrap() - 1.3671875).abs() < 1e-12);
    assert!((r.error.unwrap() - 0.09375).abs() < 1e-12);
    assert!((summary_refinement(&out)["extrapolated"].as_f64().unwrap() - 1.3671875).abs() < 1e-12);
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
