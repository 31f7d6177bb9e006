//! A hydrostatic water table: effective stress, saturated weight, and the checks.

mod common;

use common::{refusal, rel, run};

const WATER: &str = r#"water=(table: 8.0, saturated_density: {"soil": 2000.0})"#;

/// `soil_column.ron` (ρ = 1800 kg/m³, 10 m) with a water table 2 m below its top and a
/// saturated density of 2000 kg/m³: the effective vertical stress at depth is the dry part
/// above the table plus the buoyant weight below it,
/// σ′_v = −[1800 g · 2 + (2000 g − γ_w)(8 − y)], and σ′_h = K0 σ′_v with K0 = ν/(1 − ν).
/// Quadratic B-splines, h = 0.125 m: −65.99 kPa at y = 4.84 m against −66.28 kPa (−0.43 %),
/// pinned.
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
    let y = mid.initial_position[1];
    let g = 9.81;
    let analytic = -(1800.0 * g * 2.0 + (2000.0 * g - 9810.0) * (8.0 - y));
    let syy = mid.stress.yy;
    assert!(rel(syy, -65994.68307350186).abs() < 1e-9, "{syy}");
    assert!(rel(syy, analytic).abs() < 0.005, "{syy} Pa against {analytic}");
    assert!(rel(mid.stress.xx / syy, 0.3 / 0.7).abs() < 1e-6, "K0");
}

#[test]
fn water_that_cannot_be_modelled_is_refused() {
    let text = std::fs::read_to_string(common::scene("soil_column.ron")).unwrap();
    let with = |water: &str| text.replace("    gravity:", &format!("    water: {water},\n    gravity:"));
    for (water, says) in [
        (
            r#"(table: 11.0, saturated_density: {"soil": 2000.0})"#,
            "stands above the ground",
        ),
        (
            r#"(table: 8.0, saturated_density: {})"#,
            "give its material \"soil\" a saturated density",
        ),
        (
            r#"(table: 8.0, saturated_density: {"soil": 1700.0})"#,
            "at least the material's dry density",
        ),
        (
            r#"(table: 8.0, saturated_density: {"clay": 2000.0})"#,
            "no material \"clay\"",
        ),
        (
            r#"(table: 8.0, unit_weight: 0.0, saturated_density: {"soil": 2000.0})"#,
            "water.unit_weight",
        ),
    ] {
        let e = refusal(&with(water));
        assert!(e.contains(says), "{water}: {e}");
    }
    let sideways = with(r#"(table: 8.0, saturated_density: {"soil": 2000.0})"#)
        .replace("acceleration: [0.0, -9.81]", "acceleration: [-2.0, -9.81]");
    let e = refusal(&sideways);
    assert!(
        e.contains("gravity.acceleration") && e.contains("points down one axis"),
        "{e}"
    );
}
