//! A hydrostatic water table: effective stress, saturated weight, and the checks.

mod common;

use common::{refusal, rel, run};

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
    assert!(rel(syy, -65984.0821288774).abs() < 1e-9, "{syy}");
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
/// base (the highest a level table may stand without open water at the toe) gives 1.398
/// (1.3906–1.4062) against the dry 1.414 (1.4062–1.4219); the dry summary has no `water`.
#[test]
fn strength_reduction_holds_the_pore_pressures_and_names_the_water() {
    let coarse = ["grid.cell_size=1.0", "grid.cells=[55, 12]"];
    let fos = |name: &str, water: Option<&str>| {
        let dir = common::scratch("water", name);
        let scene = common::scene("slope_fos.ron");
        let mut args = vec![
            "fos",
            scene.to_str().unwrap(),
            "--quiet",
            "--out",
            dir.to_str().unwrap(),
        ];
        for s in coarse.iter().copied().chain(water) {
            args.extend(["--set", s]);
        }
        let o = common::kdmpm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let dry = fos("fos-dry", None);
    let wet = fos(
        "fos-wet",
        Some(r#"water=(table: Level(0.5), saturated_density: {"soil": 2100.0})"#),
    );
    assert_eq!(dry["bracket"], serde_json::json!([1.40625, 1.421875]));
    assert_eq!(wet["bracket"], serde_json::json!([1.390625, 1.40625]));
    assert!(dry.get("water").is_none());
    assert_eq!(wet["water"]["table"], serde_json::json!({"Level": 0.5}));
    assert_eq!(wet["water"]["saturated_density"]["soil"], 2100.0);
}
