//! Loading stages: each runs to its static stop from the state the one before left.

use crate::common;

use crate::common::{rel, run, run_text};

/// The bar (the paper's example 1, linear elastic) loaded with F = 0.001 and then, in a
/// second stage, 0.002: the second static state is the analytic one for 0.002,
/// u_A = F x/(EA) = 9.5e-3 at x = 4.75 (the first, 4.75e-3, is the paper's).
const TWO_LOADS: &str =
    r#"stages=[(name: "first"), (name: "doubled", point_loads: {"F": [0.002, 0.0, 0.0]})]"#;

#[test]
fn a_second_stage_that_doubles_the_bars_load_doubles_its_displacement() {
    let s = run("bar.ron", &[TWO_LOADS, "solver.tolerance=1e-4"]);
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.stages.len(), 2);
    assert_eq!(s.stages[0].name, "first");
    assert!(s.stages[0].step < s.stages[1].step);
    let u = s.traced[0].displacement[0];
    assert!(rel(u, 9.5e-3).abs() < 2e-3, "u_A = {u}");
    let sigma = s.traced[0].stress.xx;
    assert!(rel(sigma, 2.0e-3).abs() < 2e-3, "σ = {sigma}");
}

/// The paper's slope with the fast preset, in two stages (elastic geostatic state, then
/// the Mohr-Coulomb strength: `scenes/slope_staged.ron`) against one stage (gravity on the
/// Mohr-Coulomb soil at once: `scenes/slope_fast.ron`). A slope that fails to its repose
/// angle forgets the state it started from: both rest at Davis's angle (18.9°).
#[test]
fn the_slope_failed_from_its_geostatic_state_rests_at_the_one_stage_angle() {
    let staged = run("slope_staged.ron", &[]);
    let one = common::slope_fast();
    assert!(staged.converged && one.converged);
    assert_eq!(staged.stages.len(), 2, "geostatic, then strength");
    let angle = |s: &kdmpm::output::Summary| s.surface_angle.as_ref().unwrap().degrees;
    assert!(
        (angle(&staged) - angle(one)).abs() < 0.25,
        "{} against {}",
        angle(&staged),
        angle(one)
    );
    // The crest's run-out counted from the geostatic state, against from the start.
    let ux = |s: &kdmpm::output::Summary| s.traced[0].displacement[0];
    assert!(
        rel(ux(&staged), ux(one)).abs() < 0.03,
        "{} against {}",
        ux(&staged),
        ux(one)
    );
}

#[test]
fn a_stage_that_would_outrun_the_time_step_is_refused() {
    let path = common::scene("slope_staged.ron");
    let stiff = r#"stages[1].materials.soil.youngs_modulus=80.0e6"#;
    let o = common::kdmpm(&["check", path.to_str().unwrap(), "--set", stiff]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("stages[1].materials.soil.youngs_modulus") && e.contains("time"),
        "{e}"
    );
}

/// `scenes/soil_column.ron` (elastic self-weight between rollers) with a second stage at
/// twice the gravity, ramped over 1 s from the first stage's static state: the vertical
/// stress at mid-height doubles, −2ρg(H − y) at the cell centre.
#[test]
fn a_stage_that_doubles_gravity_doubles_the_self_weight_stress() {
    let stage =
        r#"stages=[(name: "g"), (name: "2g", gravity: (acceleration: [0.0, -19.62], ramp_time: 1.0))]"#;
    let s = run("soil_column.ron", &[stage]);
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.stages.len(), 2);
    // The ramp starts with the stage: it cannot end before a second has passed.
    assert!(s.stages[1].time >= s.stages[0].time + 1.0, "{:?}", s.stages);
    let mid = s.traced.iter().find(|t| t.name == "mid").unwrap();
    let centre = (mid.initial_position[1] / 0.5).floor() * 0.5 + 0.25;
    let sv = -1800.0 * 19.62 * (10.0 - centre);
    assert!(
        rel(mid.stress.yy, sv).abs() < 0.01,
        "σv = {} vs {sv}",
        mid.stress.yy
    );
}

/// An elastic column under its own weight between rollers (the K0 state), whose second
/// stage frees its right side and lets its base slide. Elasticity does not remember the
/// path: the state equals the one-stage run under the final conditions, σ_yy = −ρg(H − y)
/// at the cell centre (linear shape functions report a point's stress there). σ_xx, which
/// is 0 in the continuum, is 1.8 % of σ_yy in both, from the free edge's discretisation.
#[test]
fn a_stage_that_frees_a_side_ends_where_a_run_under_the_final_conditions_does() {
    let text = r#"Scene(
        dimension: 2,
        grid: (origin: [0.0, 0.0], cell_size: 0.25, cells: [8, 18]),
        shape: Linear,
        materials: { "soil": LinearElastic(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3) },
        bodies: [(material: "soil", region: Box(min: [0.0, 0.0], max: [1.0, 4.0]), points_per_cell: [2, 2])],
        boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Fixed)],
        gravity: (acceleration: [0.0, -9.81]),
        stages: [
            (name: "k0"),
            (name: "free", boundaries: [(face: XMin, condition: Roller), (face: YMin, condition: Roller)]),
        ],
        traced: [(name: "mid", position: [0.375, 1.875])],
        solver: (time_step: Courant(0.5), tolerance: 1e-5, max_time: 60.0),
    )"#;
    let staged = run_text("free.ron", text);
    let a = text.find("        stages: [").unwrap();
    let b = a + text[a..].find("        ],\n").unwrap() + "        ],\n".len();
    let direct = format!("{}{}", &text[..a], &text[b..]).replace(
        "(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Fixed)",
        "(face: XMin, condition: Roller), (face: YMin, condition: Roller)",
    );
    let direct = run_text("free.ron", &direct);
    assert!(
        staged.converged && direct.converged,
        "{:?} {:?}",
        staged.error,
        direct.error
    );
    assert_eq!(staged.stages.len(), 2);
    let (s, d) = (&staged.traced[0].stress, &direct.traced[0].stress);
    let y = staged.traced[0].initial_position[1];
    let sv = -2000.0 * 9.81 * (4.0 - ((y / 0.25).floor() * 0.25 + 0.125));
    assert!(rel(s.yy, sv).abs() < 0.01, "σ_yy {} vs {sv}", s.yy);
    assert!(
        rel(s.yy, d.yy).abs() < 1e-3,
        "σ_yy {} staged, {} direct",
        s.yy,
        d.yy
    );
    assert!(
        (s.xx - d.xx).abs() < 1e-3 * sv.abs(),
        "σ_xx {} staged, {} direct",
        s.xx,
        d.xx
    );
}
