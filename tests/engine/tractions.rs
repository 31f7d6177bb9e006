//! Tractions: a distributed load on a body's surface, carried by its outermost points.

use crate::common;

use crate::common::{refusal, rel, run_text, run_text_with};

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

/// The same column on quadratic B-splines under each volumetric treatment. The loaded
/// points pass the pressure to the grid as point forces inside the top cells, so the
/// stress jumps across them; the cell means leave them out (`systems/shared.rs`), and the
/// top settles as with no treatment, 0.7 % over p y/M (the B-spline's top half-cell);
/// averaged with the rest, they let it settle 5.7 % over. The smoothing still averages
/// them: 3.8 % over (docs/verification.md, "A pressed surface under the volumetric
/// treatments").
#[test]
fn a_pressed_column_settles_as_much_under_the_cell_means_as_without() {
    let m = m(1.0e7, 0.3);
    let pinned = [
        ("Off", -2.9447166555e-3, 0.012),
        ("CellMean", -2.9452119391e-3, 0.012),
        ("StrainSmoothing", -3.0372797109e-3, 0.04),
    ];
    for (anti_locking, pinned, within) in pinned {
        let treatment = format!("solver.anti_locking={anti_locking}");
        let s = run_text_with("traction.ron", COLUMN_2D, &["shape=QuadraticBSpline", &treatment]);
        assert_mid_under(&s, 10.0e3);
        let top = &s.traced[1];
        let expected = -10.0e3 * top.initial_position[1] / m;
        assert!(
            rel(top.displacement[1], expected).abs() < within,
            "{anti_locking}: u_y {} against {expected}",
            top.displacement[1]
        );
        assert!(
            (top.displacement[1] - pinned).abs() < 1e-13,
            "{anti_locking}: u_y {}",
            top.displacement[1]
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

/// A traction acts on a body's face: a box that ends inside the body, whose outermost
/// points have soil beyond them, is refused rather than loading the soil within.
#[test]
fn a_traction_whose_box_ends_inside_the_body_is_refused() {
    let bad = COLUMN_2D.replace(
        "min: [0.0, 3.5], max: [1.0, 4.0]",
        "min: [0.0, 2.0], max: [1.0, 2.5]",
    );
    let e = refusal(&bad);
    assert!(
        e.contains("tractions[0].max")
            && e.contains("ends inside the body")
            && e.contains("[0.0625, 2.4375] m"),
        "{e}"
    );
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

/// A quarter of a thick elastic sphere (axisymmetric, a0 = 1 m to b = 3 m, h = 0.1 m) at
/// rest under 100 kPa on both its faces, given as `Arc`s, and then 110 kPa in its cavity.
/// The polygon of its section has sides of 1°.
fn thick_sphere(stages: &str) -> String {
    let arc = |r: f64, from: f64, to: f64| -> Vec<[f64; 2]> {
        (0..=90)
            .map(|k| {
                let phi = (from + (to - from) * k as f64 / 90.0).to_radians();
                [r * phi.cos(), r * phi.sin()]
            })
            .collect()
    };
    let mut vertices = vec![[1.0, 0.0]];
    vertices.extend(arc(3.0, 0.0, 90.0));
    vertices.extend(arc(1.0, 90.0, 0.0).into_iter().take(90));
    let polygon: Vec<String> = vertices
        .iter()
        .map(|v| format!("[{:.9}, {:.9}]", v[0].max(0.0), v[1].max(0.0)))
        .collect();
    format!(
        r#"Scene(
    dimension: Axisymmetric,
    grid: (origin: [0.0, 0.0], cell_size: 0.1, cells: [32, 32]),
    shape: QuadraticBSpline,
    materials: {{ "soil": LinearElastic(density: 1700.0, youngs_modulus: 1.0e7, poisson_ratio: 0.3) }},
    bodies: [(material: "soil", region: Polygon(vertices: [{}]), points_per_cell: [2, 2],
              initial_stress: Isotropic(100.0e3))],
    boundaries: [(face: XMin, condition: Roller), (face: YMin, condition: Roller)],
    tractions: [
        (name: "cavity", surface: Arc(centre: [0.0, 0.0], radius: 1.0), min: [0.0, 0.0], max: [1.5, 1.5], pressure: 100.0e3),
        (name: "far field", surface: Arc(centre: [0.0, 0.0], radius: 3.0), min: [0.0, 0.0], max: [3.5, 3.5], pressure: 100.0e3),
    ],
    traced: [(name: "wall9", position: [1.025, 0.175]), (name: "wall27", position: [0.925, 0.475]),
             (name: "wall45", position: [0.725, 0.725]), (name: "wall63", position: [0.475, 0.925]),
             (name: "wall81", position: [0.175, 1.025])],
    stages: [{stages}],
    solver: (time_step: Courant(0.5), tolerance: 1e-4, max_time: 200.0),
)"#,
        polygon.join(", ")
    )
}

/// The thick sphere's cavity pressure raised by Δp = 10 kPa: Lamé's solution (Timoshenko &
/// Goodier 1970, §141) moves a point at r by u = Δp a³/(b³ − a³) (r/(3K) + b³/(4G r²)).
/// The wall's five traced points, each standing for an 18° zone of the sphere (weight
/// cos φ dφ), give the cavity's growth of volume, Σ w ρ0² u_r: −1.6 % on Lamé's, pinned
/// (the points one by one −4.4 % at 45° to +2.3 % at 81°: the wall is a staircase of
/// sub-cells round the circle, its loaded points up to a sub-cell from it).
#[test]
fn a_pressure_on_an_arc_opens_a_thick_sphere_as_lames_solution() {
    let s = run_text(
        "thick_sphere.ron",
        &thick_sphere(
            r#"(name: "in situ"), (name: "110 kPa", reset_displacements: true, tractions: {"cavity": [110.0e3]})"#,
        ),
    );
    assert!(s.converged, "{:?}", s.error);
    let (e, nu, a, b, dp): (f64, f64, f64, f64, f64) = (1.0e7, 0.3, 1.0, 3.0, 10.0e3);
    let (k, g) = (e / (3.0 * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
    let lame =
        |r: f64| dp * a.powi(3) / (b.powi(3) - a.powi(3)) * (r / (3.0 * k) + b.powi(3) / (4.0 * g * r * r));
    let (mut grown, mut expected) = (0.0, 0.0);
    for t in &s.traced {
        let phi: f64 = t.name[4..].parse::<f64>().unwrap().to_radians();
        let w = (phi + 9f64.to_radians()).sin() - (phi - 9f64.to_radians()).sin();
        let x0 = t.initial_position;
        let rho0 = x0[0].hypot(x0[1]);
        let ur = (t.displacement[0] * x0[0] + t.displacement[1] * x0[1]) / rho0;
        assert!(
            rel(ur, lame(rho0)).abs() < 0.05,
            "{}: u_r {ur} against {}",
            t.name,
            lame(rho0)
        );
        grown += w * rho0 * rho0 * ur;
        expected += w * rho0 * rho0 * lame(rho0);
    }
    assert!(rel(grown, expected).abs() < 0.02, "{grown} against {expected}");
    assert_eq!(grown, 0.000680910837248523, "pinned");
}

#[test]
fn an_arc_is_loaded_by_a_pressure_in_stages_in_a_2d_scene() {
    let sphere = thick_sphere(r#"(name: "in situ")"#);
    let e = refusal(&sphere.replace(
        "pressure: 100.0e3),\n        (name: \"far",
        "traction: [1.0, 0.0]),\n        (name: \"far",
    ));
    assert!(
        e.contains("tractions[0].traction") && e.contains("pressure"),
        "{e}"
    );
    let e = refusal(&sphere.replacen("pressure: 100.0e3)", "pressure: 100.0e3, increments: 4)", 1));
    assert!(
        e.contains("tractions[0].increments") && e.contains("stages"),
        "{e}"
    );
    // An arc through the soil, not along its face.
    let e = refusal(&sphere.replacen(
        "radius: 1.0), min: [0.0, 0.0], max: [1.5, 1.5]",
        "radius: 2.0), min: [0.0, 0.0], max: [2.5, 2.5]",
        1,
    ));
    assert!(
        e.contains("tractions[0].surface") && e.contains("runs through the soil"),
        "{e}"
    );
    let e = refusal(&sphere.replacen("radius: 1.0)", "radius: 0.0)", 1));
    assert!(e.contains("tractions[0].surface.radius"), "{e}");
    let e = refusal(&sphere.replacen("max: [1.5, 1.5]", "max: [0.5, 0.5]", 1));
    assert!(
        e.contains("tractions[0].min") && e.contains("no part of the circle"),
        "{e}"
    );
    let e = refusal(&sphere.replacen(
        "min: [0.0, 0.0], max: [1.5, 1.5]",
        "min: [-1.5, 0.3], max: [1.5, 0.7]",
        1,
    ));
    assert!(
        e.contains("tractions[0].min") && e.contains("2 separate arcs"),
        "{e}"
    );
}
