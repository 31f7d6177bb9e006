//! Tractions: a distributed load on a body's surface, carried by its outermost points.

use crate::common;

use crate::common::{refusal, rel, run_text};

/// An elastic column between rollers under a uniform pressure p = 10 kPa on its top:
/// uniaxial strain, σ_yy = −p throughout and a settlement of p y/M at height y, with
/// M = E(1 − ν)/((1 + ν)(1 − 2ν)).
const COLUMN_2D: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.25, cells: [4, 18]),
    shape: Linear,
    materials: { "soil": LinearElastic(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3) },
    bodies: [(material: "soil", region: Box(min: [0.0, 0.0], max: [1.0, 4.0]), points_per_cell: [2, 2])],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller), (face: YMin, condition: Fixed)],
    tractions: [(name: "p", surface: YMax, min: [0.0, 3.5], max: [1.0, 4.0], traction: [0.0, -10.0e3])],
    traced: [(name: "mid", position: [0.375, 1.875]), (name: "top", position: [0.375, 3.9375])],
    solver: (time_step: Courant(0.5), tolerance: 1e-5, max_time: 60.0),
)"#;

fn m(e: f64, nu: f64) -> f64 {
    e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
}

/// The plane strain column's traced point `mid` under a top pressure `p` (Pa): σ_yy = −p
/// and a settlement of p y/M, each within 1 %.
fn assert_mid_under(s: &kdmpm::Summary, p: f64) {
    assert!(s.converged, "{:?}", s.error);
    let mid = &s.traced[0];
    assert!(rel(mid.stress.yy, -p).abs() < 0.01, "σ_yy {}", mid.stress.yy);
    let expected = -p * mid.initial_position[1] / m(1.0e7, 0.3);
    assert!(
        rel(mid.displacement[1], expected).abs() < 0.01,
        "u_y {:?}",
        mid.displacement
    );
}

#[test]
fn a_pressure_on_a_plane_strain_column_gives_its_stress_and_settlement() {
    let s = run_text("traction.ron", COLUMN_2D);
    assert!(s.converged, "{:?}", s.error);
    let (p, m) = (10.0e3, m(1.0e7, 0.3));
    // Inside the column; the loaded points themselves carry only part of the load in
    // their own stress (it reaches the nodes below them through their weights).
    let mid = &s.traced[0];
    assert!(rel(mid.stress.yy, -p).abs() < 0.01, "σ_yy {}", mid.stress.yy);
    // The settlement: within 1 % inside; at the surface within 2 %, the top half-cell being
    // strained less for the same reason (−1.2 % at h = 0.25 m).
    for (t, tolerance) in s.traced.iter().zip([0.01, 0.02]) {
        let expected = -p * t.initial_position[1] / m;
        assert!(
            rel(t.displacement[1], expected).abs() < tolerance,
            "{}: u_y {:?}",
            t.name,
            t.displacement
        );
    }
}

#[test]
fn a_traction_or_a_pressure_on_a_3d_column_gives_its_stress() {
    let text = r#"Scene(
        dimension: 3,
        grid: (origin: [0.0, 0.0, 0.0], cell_size: 0.25, cells: [4, 4, 18]),
        shape: Linear,
        materials: { "soil": LinearElastic(density: 2000.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3) },
        bodies: [(material: "soil", region: Box(min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 4.0]), points_per_cell: [2, 2, 2])],
        boundaries: [
            (face: XMin, condition: Roller), (face: XMax, condition: Roller),
            (face: YMin, condition: Roller), (face: YMax, condition: Roller),
            (face: ZMin, condition: Fixed),
        ],
        tractions: [(name: "p", surface: ZMax, min: [0.0, 0.0, 3.5], max: [1.0, 1.0, 4.0], traction: [0.0, 0.0, -10.0e3])],
        traced: [(name: "mid", position: [0.375, 0.375, 1.875])],
        solver: (time_step: Courant(0.5), tolerance: 1e-5, max_time: 60.0),
    )"#;
    // The same as a pressure that follows the top (flat here): the same answer.
    for text in [
        text.to_string(),
        text.replace("traction: [0.0, 0.0, -10.0e3]", "pressure: 10.0e3"),
    ] {
        let s = run_text("traction.ron", &text);
        assert!(s.converged, "{:?}", s.error);
        let t = &s.traced[0];
        assert!(rel(t.stress.zz, -10.0e3).abs() < 0.01, "σ_zz {}", t.stress.zz);
        let expected = -10.0e3 * t.initial_position[2] / m(1.0e7, 0.3);
        assert!(
            rel(t.displacement[2], expected).abs() < 0.01,
            "u_z {:?}",
            t.displacement
        );
    }
}

#[test]
fn a_traction_whose_box_holds_no_point_is_refused() {
    let bad = COLUMN_2D.replace(
        "min: [0.0, 3.5], max: [1.0, 4.0]",
        "min: [2.0, 3.5], max: [3.0, 4.0]",
    );
    let e = refusal(&bad);
    assert!(e.contains("tractions[0].min") && e.contains("no point"), "{e}");
}

/// `scenes/footing_load.ron`: a uniform strip pressure on weightless Tresca clay
/// (c = 10 kPa) raised by 5 kPa increments. Prandtl's (2 + π) c = 51.42 kPa: the settlement
/// stays elastic-plastic (centimetres) below it and jumps by well over an order of
/// magnitude past it (the rigid footing reaches 55.6 kPa at this cell size).
#[test]
fn a_strip_pressure_under_load_control_settles_by_centimetres_below_prandtls_limit_and_collapses_above() {
    let s = common::run("footing_load.ron", &[]);
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.curve.len(), 12, "twelve increments, twelve static states");
    let u: Vec<f64> = s.curve.iter().map(|c| c.displacement).collect();
    let p: Vec<f64> = s.curve.iter().map(|c| c.pressure.unwrap()).collect();
    assert_eq!(p[9], 50.0e3);
    // Elastic at first: the first four increments settle in proportion to the load.
    for k in 1..4 {
        assert!(rel(u[k] / u[0], (k + 1) as f64).abs() < 0.02, "{u:?}");
    }
    assert!(u[9] < 0.03, "50 kPa settles by centimetres: {u:?}");
    assert!(u[11] > 20.0 * u[9], "60 kPa collapses: {u:?}");
    // Load control gives no limit pressure of its own: a collapse may end at rest.
    assert!(s.limit_pressure.is_none());
}

#[test]
fn a_stage_that_doubles_the_pressure_doubles_the_stress_and_settlement() {
    let staged = COLUMN_2D.replace(
        "    traced:",
        r#"    stages: [(name: "first"), (name: "doubled", tractions: {"p": [0.0, -20.0e3]})],
    traced:"#,
    );
    let s = run_text("traction.ron", &staged);
    assert_eq!(s.stages.len(), 2);
    assert_mid_under(&s, 20.0e3);
}

/// A `pressure` on the column's flat top is the traction −p n, at the start and as the
/// column settles (it stays flat, its width held by the rollers): the same stress and
/// settlement, and a stage that gives it a new value [p] doubles them.
#[test]
fn a_pressure_on_a_flat_top_loads_it_as_the_traction_does_and_a_stage_doubles_it() {
    let pressed = COLUMN_2D.replace("traction: [0.0, -10.0e3]", "pressure: 10.0e3");
    assert_mid_under(&run_text("pressure.ron", &pressed), 10.0e3);
    let staged = pressed.replace(
        "    traced:",
        r#"    stages: [(name: "first"), (name: "doubled", tractions: {"p": [20.0e3]})],
    traced:"#,
    );
    assert_mid_under(&run_text("pressure.ron", &staged), 20.0e3);
}

#[test]
fn a_pressure_is_given_alone_on_points_of_its_own() {
    let both = COLUMN_2D.replace(
        "traction: [0.0, -10.0e3]",
        "traction: [0.0, -10.0e3], pressure: 10.0e3",
    );
    let e = refusal(&both);
    assert!(
        e.contains("tractions[0].pressure") && e.contains("not both"),
        "{e}"
    );
    let neither = COLUMN_2D.replace(", traction: [0.0, -10.0e3]", "");
    let e = refusal(&neither);
    assert!(
        e.contains("tractions[0].traction") && e.contains("or a pressure"),
        "{e}"
    );
    // A side traction whose box reaches the top row shares its corner point with the
    // pressure on the top.
    let shared = COLUMN_2D.replace(
        r#"traction: [0.0, -10.0e3])],"#,
        r#"pressure: 10.0e3), (name: "side", surface: XMax, min: [0.5, 3.0], max: [1.0, 4.0], traction: [-1.0e3, 0.0])],"#,
    );
    let e = refusal(&shared);
    assert!(
        e.contains("tractions[1].min") && e.contains("shares the point") && e.contains("\"p\""),
        "{e}"
    );
    let vector_stage = COLUMN_2D
        .replace("traction: [0.0, -10.0e3]", "pressure: 10.0e3")
        .replace(
            "    traced:",
            r#"    stages: [(name: "first"), (name: "doubled", tractions: {"p": [0.0, -20.0e3]})],
    traced:"#,
        );
    let e = refusal(&vector_stage);
    assert!(
        e.contains("stages[1].tractions.p") && e.contains("one entry [p]"),
        "{e}"
    );
}
