//! A hydrostatic water table: effective stress, saturated weight, and the checks.

use crate::common;

use crate::common::{refusal, rel, run};
use kdmpm::output::Summary;

const WATER: &str = r#"water=(table: Level(8.0), saturated_density: {"soil": 2000.0})"#;

/// `soil_column.ron` (ρ = 1800 kg/m³, 10 m) with a water table 2 m below its top and a
/// saturated density of 2000 kg/m³: the effective vertical stress at depth is the dry part
/// above the table plus the buoyant weight below it,
/// σ′_v = −[1800 g · 2 + (2000 g − γ_w)(8 − y)], and σ′_h = K0 σ′_v with K0 = ν/(1 − ν).
/// The table stays where it is while the soil settles into it (3.2 cm at the traced point),
/// so the buoyancy above the point is γ_w (8 − y − δ) for its settlement δ: with that the
/// answer is exact but for the discretisation. Quadratic B-splines, h = 0.125 m: −65.98 kPa
/// at y = 4.84 m against −65.96 kPa (+0.03 %) with the settlement and −66.28 kPa (−0.44 %)
/// without, pinned.
#[test]
fn a_saturated_column_carries_its_buoyant_weight_as_effective_stress() {
    let s = run(
        "soil_column.ron",
        &[
            WATER,
            "shape=QuadraticBSpline",
            "grid.cell_size=0.125",
            "grid.cells=[16, 96]",
        ],
    );
    assert!(s.converged, "{:?}", s.error);
    let mid = s.traced.iter().find(|t| t.name == "mid").unwrap();
    let (y, settlement) = (mid.initial_position[1], -mid.displacement[1]);
    let g = 9.81;
    let weight = 1800.0 * g * 2.0 + 2000.0 * g * (8.0 - y);
    let small_strain = -(weight - 9810.0 * (8.0 - y));
    let settled = -(weight - 9810.0 * (8.0 - y + settlement));
    let syy = mid.stress.yy;
    assert!(rel(syy, -65984.08212887742).abs() < 1e-9, "{syy}");
    assert!(rel(syy, settled).abs() < 0.001, "{syy} Pa against {settled}");
    assert!(
        rel(syy, small_strain).abs() < 0.005,
        "{syy} Pa against {small_strain}"
    );
    assert!(rel(mid.stress.xx / syy, 0.3 / 0.7).abs() < 1e-6, "K0");
}

#[test]
fn water_that_cannot_be_modelled_is_refused() {
    let text = std::fs::read_to_string(common::scene("soil_column.ron")).unwrap();
    let with = |water: &str| text.replace("    gravity:", &format!("    water: {water},\n    gravity:"));
    for (water, says) in [
        (
            r#"(table: Polyline([[0.0, 8.0], [1.5, 8.0], [1.0, 7.0], [2.0, 7.0]]), saturated_density: {"soil": 2000.0})"#,
            "field `water.table`: is not a function of x",
        ),
        (
            r#"(table: Polyline([[0.0, 8.0], [1.5, 8.0]]), saturated_density: {"soil": 2000.0})"#,
            "must reach across the whole grid",
        ),
        (
            r#"(table: Heights(origin: [0.0, 0.0], spacing: [1.0, 1.0], heights: [[8.0, 8.0], [8.0, 8.0]]), saturated_density: {"soil": 2000.0})"#,
            "in 2D give a Polyline or a Level",
        ),
        (
            r#"(table: Level(8.0), material_tables: {"clay": Level(7.0)}, saturated_density: {"soil": 2000.0})"#,
            "field `water.material_tables.clay`: the scene has no material",
        ),
        (
            r#"(table: Level(8.0), saturated_density: {})"#,
            "material \"soil\" has points below the piezometric surface of `water.table`",
        ),
        (
            r#"(table: Level(8.0), saturated_density: {"soil": 1700.0})"#,
            "at least the material's dry density",
        ),
        (
            r#"(table: Level(8.0), saturated_density: {"soil": 2900.0})"#,
            "at most the dry density plus the water's, 1800 + 1000 = 2800 kg/m³",
        ),
        (
            r#"(table: Level(8.0), saturated_density: {"clay": 2000.0})"#,
            "no material \"clay\"",
        ),
        (
            r#"(table: Level(8.0), unit_weight: 0.0, saturated_density: {"soil": 2000.0})"#,
            "water.unit_weight",
        ),
    ] {
        let e = refusal(&with(water));
        assert!(e.contains(says), "{water}: {e}");
    }
    let staged = text.replace(
        "    gravity:",
        "    stages: [(name: \"dry\"), (name: \"wet\", water: (table: Level(8.0)))],\n    gravity:",
    );
    let e = refusal(&staged);
    assert!(
        e.contains("stages[1].water") && e.contains("give the scene a `water`"),
        "{e}"
    );
    let sideways = with(r#"(table: Level(8.0), saturated_density: {"soil": 2000.0})"#)
        .replace("acceleration: [0.0, -9.81]", "acceleration: [-2.0, -9.81]");
    let e = refusal(&sideways);
    assert!(
        e.contains("gravity.acceleration") && e.contains("points down one axis"),
        "{e}"
    );
}

/// With water, `points.vtu` and every snapshot hold the pore pressure and the total stress
/// beside the (effective) `stress`: u = γ_w (table − y) at each point, σ = σ′ − u I.
#[test]
fn the_pore_pressure_and_the_total_stress_are_written_for_paraview() {
    let dir = common::scratch("water", "vtu");
    let o = common::run_into(
        &common::scene("soil_column.ron"),
        &dir,
        &[WATER, "output.snapshots=(every_steps: 100)"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let snapshot = std::fs::read_dir(dir.join("snapshots"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "vtu"))
        .expect("a snapshot");
    for file in [dir.join("points.vtu"), snapshot] {
        let vtu = common::read_vtu(&file);
        let (x, s, u, t) = (
            &vtu["Points"].1,
            &vtu["stress"].1,
            &vtu["pore_pressure"].1,
            &vtu["total_stress"].1,
        );
        assert_eq!(u.len() * 3, x.len());
        let mut below = 0;
        for p in 0..u.len() {
            let want = 9810.0 * (8.0 - x[3 * p + 1]).max(0.0);
            assert!((u[p] - want).abs() <= 1e-9 * want.max(1.0), "{file:?} point {p}");
            below += usize::from(want > 0.0);
            for k in 0..6 {
                let shift = if k < 3 { u[p] } else { 0.0 };
                assert_eq!(t[6 * p + k], s[6 * p + k] - shift, "{file:?} point {p}");
            }
        }
        assert!(below > 0, "{file:?}: points below the table");
    }
    // A dry run writes neither.
    let dry = common::scratch("water", "dry");
    assert!(common::run_into(&common::scene("soil_column.ron"), &dry, &[])
        .status
        .success());
    let vtu = common::read_vtu(&dry.join("points.vtu"));
    assert!(!vtu.contains_key("pore_pressure") && !vtu.contains_key("total_stress"));
}

/// `kdmpm fos` holds the pore pressures (they are not reduced with the strength) and says
/// which water it used: Griffiths & Lane's slope at h = 1 m with a table 0.5 m above its
/// base gives 1.398 (1.3906–1.4062) against the dry 1.414 (1.4062–1.4219); the dry summary
/// has no `water`.
#[test]
fn strength_reduction_holds_the_pore_pressures_and_names_the_water() {
    let dry = fos_at_1m("fos-dry", "slope_fos.ron", &[]);
    let wet = fos_at_1m(
        "fos-wet",
        "slope_fos.ron",
        &[r#"water=(table: Level(0.5), saturated_density: {"soil": 2100.0})"#],
    );
    assert_eq!(dry["bracket"], serde_json::json!([1.40625, 1.421875]));
    assert_eq!(wet["bracket"], serde_json::json!([1.390625, 1.40625]));
    assert!(dry.get("water").is_none());
    assert_eq!(wet["water"]["table"], serde_json::json!({"Level": 0.5}));
    assert_eq!(wet["water"]["saturated_density"]["soil"], 2100.0);
}

/// The saturated column in 3D, gravity along z and the table given as a height grid over x
/// and y (level at 8 m, 1 × 1 m, between rollers): the same effective stress as in plane
/// strain. Quadratic B-splines, h = 0.25 m: −66.264 kPa at z = 4.81 m against −66.271 kPa
/// with its 3.2 cm settlement (−0.01 %), pinned.
#[test]
fn a_saturated_column_in_3d_under_a_height_grid_carries_its_buoyant_weight() {
    let s = common::run_text("column_3d.ron", COLUMN_3D);
    assert!(s.converged, "{:?}", s.error);
    let mid = &s.traced[0];
    let (z, settlement) = (mid.initial_position[2], -mid.displacement[2]);
    let g = 9.81;
    let weight = 1800.0 * g * 2.0 + 2000.0 * g * (8.0 - z);
    let settled = -(weight - 9810.0 * (8.0 - z + settlement));
    let szz = mid.stress.zz;
    assert!(rel(szz, -66263.598819919).abs() < 1e-9, "{szz}");
    assert!(rel(szz, settled).abs() < 0.001, "{szz} Pa against {settled}");
    assert!(rel(mid.stress.xx / szz, 0.3 / 0.7).abs() < 1e-6, "K0");
}

const COLUMN_3D: &str = r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 0.25, cells: [4, 4, 40]),
    shape: QuadraticBSpline,
    materials: {
        "soil": MohrCoulomb(
            density: 1800.0,
            youngs_modulus: 10.0e6,
            poisson_ratio: 0.3,
            cohesion: 0.0,
            friction_angle: 30.0,
            dilatancy_angle: 0.0,
        ),
    },
    bodies: [
        (material: "soil", region: Box(min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 10.0]), points_per_cell: [2, 2, 2]),
    ],
    boundaries: [
        (face: ZMin, condition: Fixed),
        (face: XMin, condition: Roller),
        (face: XMax, condition: Roller),
        (face: YMin, condition: Roller),
        (face: YMax, condition: Roller),
    ],
    gravity: (acceleration: [0.0, 0.0, -9.81]),
    water: (
        table: Heights(origin: [0.0, 0.0], spacing: [1.0, 1.0], heights: [[8.0, 8.0], [8.0, 8.0]]),
        saturated_density: {"soil": 2000.0},
    ),
    traced: [(name: "mid", position: [0.4375, 0.4375, 4.8125])],
    solver: (damping: Kinetic, time_step: Courant(0.5), tolerance: 1e-4, max_time: 20.0),
)
"#;

/// A stage that raises the table wets the soil it reaches: the column dry in a first stage
/// (the table below its base), then with the table 2 m below its top, comes to the
/// effective stress of the column built wet (to the tolerance of two static states, not
/// bit for bit: the paths differ).
#[test]
fn a_stage_that_raises_the_table_wets_and_buoys_the_soil_below_it() {
    let set = [
        "shape=QuadraticBSpline",
        "grid.cell_size=0.125",
        "grid.cells=[16, 96]",
    ];
    let wet = run("soil_column.ron", &[&[WATER][..], &set[..]].concat());
    let staged = run(
        "soil_column.ron",
        &[
            &[
                r#"water=(table: Level(-1.0), saturated_density: {"soil": 2000.0})"#,
                r#"stages=[(name: "dry"), (name: "wet", water: (table: Level(8.0)))]"#,
            ][..],
            &set[..],
        ]
        .concat(),
    );
    assert!(staged.converged, "{:?}", staged.error);
    let mid = |s: &Summary| s.traced.iter().find(|t| t.name == "mid").unwrap().stress.yy;
    let (a, b) = (mid(&wet), mid(&staged));
    assert!(rel(b, a).abs() < 0.002, "{b} Pa staged against {a} built wet");
}

/// Runs `kdmpm fos` on `scene` at h = 1 m with `sets`; gives its summary.json.
fn fos_at_1m(name: &str, scene: &str, sets: &[&str]) -> serde_json::Value {
    let dir = common::scratch("water", name);
    let scene = common::scene(scene);
    let mut args = vec![
        "fos",
        scene.to_str().unwrap(),
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ];
    for s in ["grid.cell_size=1.0", "grid.cells=[55, 12]"].iter().chain(sets) {
        args.extend(["--set", s]);
    }
    let o = common::kdmpm(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

const SUBMERGED: &str = r#"water=(table: Level(11.0), saturated_density: {"soil": 2038.74})"#;

/// Buoyancy, exact by effective stress: Griffiths & Lane's slope under water to above its
/// crest (γ_sat = 20 kN/m³) stands as the same slope dry with γ_sat − γ_w = 10.19 kN/m³.
/// Both 1.883 (1.875–1.8906) at h = 1 m, pinned.
#[test]
fn a_submerged_slope_stands_as_the_dry_slope_of_buoyant_weight() {
    let wet = fos_at_1m("submerged", "slope_fos.ron", &[SUBMERGED]);
    let buoyant = fos_at_1m("buoyant", "slope_fos.ron", &["materials.soil.density=1038.74"]);
    assert_eq!(wet["bracket"], serde_json::json!([1.875, 1.890625]));
    assert_eq!(buoyant["bracket"], wet["bracket"]);
}

/// A cohesionless slope (c = 0, φ = 35°) has one factor of safety dry and submerged: its
/// stresses scale with the unit weight, and so do its strengths. Both 1.367
/// (1.3594–1.375) at h = 1 m, pinned; tan φ / tan β = 1.40 for an infinite slope. The
/// failure criterion is 0.3 m here: the skin of a c = 0 slope first slides a few
/// centimetres and stops, and with 0.1 m the dry slope, whose elastic settlement is twice
/// the submerged one's, reaches the criterion sooner (1.242 dry against 1.352 submerged).
#[test]
fn a_cohesionless_slope_has_one_factor_of_safety_dry_and_submerged() {
    let c0 = [
        "materials.soil.cohesion=0.0",
        "materials.soil.friction_angle=35.0",
        "strength_reduction.failure_displacement=0.3",
    ];
    let dry = fos_at_1m("sand-dry", "slope_fos.ron", &c0);
    let wet = fos_at_1m("sand-wet", "slope_fos.ron", &[&c0[..], &[SUBMERGED][..]].concat());
    assert_eq!(dry["bracket"], serde_json::json!([1.359375, 1.375]));
    assert_eq!(wet["bracket"], dry["bracket"]);
}

/// The slope with water against an independent limit-equilibrium package: XSLOPE 1.0.5
/// (N. L. Jones, BYU; PyPI `xslope`), Bishop's simplified method with its circle search,
/// run by studies/slope_lem.sh. At h = 1 m (pinned): dry 1.414 (Bishop 1.378), water
/// table 1.227 (1.182), reservoir 5 m 1.367 (1.351), reservoir full 1.883 (1.822), drawn
/// down to 3 m in a stage 1.336 (1.302): each within 7 %, and each change from the dry
/// slope or the full reservoir in the package's direction.
#[test]
fn the_slopes_with_water_stand_beside_bishops_method() {
    // (output, scene, overrides, bracket at h = 1 m, Bishop's factor by XSLOPE)
    type Case<'a> = (&'a str, &'a str, &'a [&'a str], [f64; 2], f64);
    let cases: [Case; 5] = [
        ("lem-dry", "slope_fos.ron", &[], [1.40625, 1.421875], 1.378),
        ("lem-water", "slope_water.ron", &[], [1.21875, 1.234375], 1.182),
        (
            "lem-reservoir",
            "slope_reservoir.ron",
            &[],
            [1.359375, 1.375],
            1.351,
        ),
        (
            "lem-full",
            "slope_reservoir.ron",
            &["water.table=Level(10.0)"],
            [1.875, 1.890625],
            1.822,
        ),
        (
            "lem-drawdown",
            "slope_drawdown.ron",
            &[],
            [1.328125, 1.34375],
            1.302,
        ),
    ];
    let mut fos = Vec::new();
    for (name, scene, sets, bracket, bishop) in cases {
        let s = fos_at_1m(name, scene, sets);
        assert_eq!(s["bracket"], serde_json::json!(bracket), "{name}");
        if name == "lem-drawdown" {
            assert_eq!(s["water"]["table"], serde_json::json!({"Level": 10.0}));
            assert_eq!(
                s["stage_water"],
                serde_json::json!([["drawn down", {"table": {"Level": 3.0}, "material_tables": {}}]])
            );
        }
        let f = s["factor_of_safety"].as_f64().unwrap();
        assert!(
            rel(f, bishop).abs() < 0.07,
            "{name}: {f} against Bishop's {bishop}"
        );
        fos.push((f, bishop));
    }
    let (dry, full) = (fos[0], fos[3]);
    for (k, (f, bishop)) in fos.iter().enumerate() {
        let from = if k == 4 { full } else { dry };
        assert_eq!(f < &from.0, bishop < &from.1, "case {k}: {f} from {}", from.0);
    }
}
