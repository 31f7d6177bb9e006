//! A body started at its geostatic state (`initial_stress: Geostatic(k0: …)`): the weight of
//! the ground above each point, its water taken off, K0 across.

use crate::common::{refusal, run_text};
use kdmpm::components::{Position, Stress};
use kdmpm::infra::columns::{col, points_with};
use kdmpm::output::Outcome;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::tensor::{PlanarSym3, StoredSym};
use kdmpm::AnySimulation;
use std::path::Path;

/// A 10 m column of sand (dry 1 800, saturated 2 000 kg/m³) with its water table 6 m up,
/// started at K0 = ν/(1 − ν), the plane-strain elastic ratio under its own weight.
const COLUMN: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.5, cells: [4, 24]),
    shape: Linear,
    materials: {
        "soil": MohrCoulomb(density: 1800.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3,
                            cohesion: 0.0, friction_angle: 30.0, dilatancy_angle: 0.0),
    },
    bodies: [
        (material: "soil", region: Box(min: [0.0, 0.0], max: [2.0, 10.0]), points_per_cell: [2, 2],
         initial_stress: Geostatic(k0: 0.42857142857142855)),
    ],
    boundaries: [
        (face: YMin, condition: Fixed),
        (face: XMin, condition: Roller),
        (face: XMax, condition: Roller),
    ],
    gravity: (acceleration: [0.0, -9.81]),
    water: (table: Level(6.0), saturated_density: {"soil": 2000.0}),
    traced: [(name: "mid", position: [0.875, 4.875])],
    solver: (damping: Kinetic, time_step: Courant(0.5), tolerance: 1e-4, max_time: 20.0),
)"#;

/// The same column in Modified Cam Clay, normally consolidated, under water to its top.
const CLAY: &str = r#""soil": ModifiedCamClay(density: 1700.0, lambda: 0.25, kappa: 0.05,
            critical_state_ratio: 0.9, poisson_ratio: 0.25, ncl_volume: 3.0,
            preconsolidation: Ratio(1.0), max_mean_stress: 1.0e6),"#;

#[test]
fn a_geostatic_start_carries_the_ground_above_and_takes_its_water_off() {
    let loaded = LoadedScene::from_text(Path::new("column.ron"), COLUMN, &[]).unwrap();
    let AnySimulation::Two(sim) = build(&loaded).unwrap().0 else {
        unreachable!("a 2D scene")
    };
    let (g, gw, k0) = (9.81, 9810.0, 0.3 / 0.7);
    let mut seen = 0;
    for arch in points_with::<Stress<PlanarSym3>>(&sim.ctx.world) {
        let (x, s) = (
            col::<Position<glam::DVec2>>(arch),
            col::<Stress<PlanarSym3>>(arch),
        );
        for (x, s) in x.iter().zip(s.iter()) {
            let (y, s) = (x.0.y, s.0.to_sym3());
            // Dry above the table, saturated below it; the water's pressure below it.
            let total = g * (1800.0 * (10.0 - y.max(6.0)) + 2000.0 * (6.0 - y).max(0.0));
            let v = total - gw * (6.0 - y).max(0.0);
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
            assert!(close(s.yy, -v), "y = {y}: σ′_yy {} against {}", s.yy, -v);
            assert!(close(s.xx, -k0 * v) && close(s.zz, -k0 * v), "y = {y}: {s:?}");
            assert_eq!(s.xy, 0.0);
            seen += 1;
        }
    }
    assert_eq!(seen, 320);
}

#[test]
fn level_ground_started_at_its_geostatic_state_is_static_at_the_first_step() {
    // In Mohr–Coulomb at the elastic K0, and in a normally consolidated Cam Clay (on its
    // yield surface from the start) drained and undrained, the start balances gravity and
    // the water, below the ground and standing on it: the first step's K_F is round-off
    // and nothing moves. Started from no
    // stress, the same sand settles 38.3 mm at mid-height over 199 steps.
    let clay = COLUMN
        .replace(
            r#""soil": MohrCoulomb(density: 1800.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3,
                            cohesion: 0.0, friction_angle: 30.0, dilatancy_angle: 0.0),"#,
            CLAY,
        )
        .replace("0.42857142857142855", "0.64");
    let undrained = clay.replace(
        "max_mean_stress: 1.0e6)",
        "max_mean_stress: 1.0e6, drainage: Undrained(bulk_modulus: 1.0e8))",
    );
    for (name, text) in [
        ("sand", COLUMN.to_string()),
        ("clay", clay),
        ("undrained", undrained),
    ] {
        let s = run_text(name, &text);
        assert_eq!(s.outcome, Outcome::Converged, "{name}");
        assert_eq!(s.steps, 1, "{name}");
        let u = s.traced[0].displacement;
        assert!(u[0].abs() < 1e-15 && u[1].abs() < 1e-15, "{name}: {u:?}");
    }
    // Under 2 m of open water (table at 12 m, the grid 14 m tall) the sand carries its
    // buoyant weight only: σ′_yy at mid-height (4.875 m) is (ρ_sat g − γ_w)(10 − 4.875).
    let open = COLUMN
        .replace("Level(6.0)", "Level(12.0)")
        .replace("cells: [4, 24]", "cells: [4, 28]");
    let s = run_text("open water", &open);
    assert_eq!(s.steps, 1);
    let buoyant = (2000.0 * 9.81 - 9810.0) * (10.0 - 4.875);
    assert!((s.traced[0].stress.yy + buoyant).abs() < 1e-9 * buoyant);
    // Two layers (clay under the sand, each its own saturated density), the column turned
    // about its axis, and the column in 3D with gravity along z: static at the first step.
    let two = COLUMN
        .replace(
            "Box(min: [0.0, 0.0], max: [2.0, 10.0]), points_per_cell: [2, 2],",
            "Box(min: [0.0, 4.0], max: [2.0, 10.0]), points_per_cell: [2, 2],",
        )
        .replace(
            "    ],\n    boundaries",
            "        (material: \"clay\", region: Box(min: [0.0, 0.0], max: [2.0, 4.0]), points_per_cell: [2, 2],\n         \
             initial_stress: Geostatic(k0: 0.5)),\n    ],\n    boundaries",
        )
        .replace(
            "    },\n    bodies",
            "        \"clay\": MohrCoulomb(density: 1600.0, youngs_modulus: 5.0e6, poisson_ratio: 0.3, \
             cohesion: 20.0e3, friction_angle: 0.0),\n    },\n    bodies",
        )
        .replace("{\"soil\": 2000.0}", "{\"soil\": 2000.0, \"clay\": 1900.0}");
    assert!(two.matches("Geostatic").count() == 2 && two.contains("\"clay\": 1900.0"));
    let turned = COLUMN.replace("dimension: 2,", "dimension: Axisymmetric,");
    let solid = COLUMN
        .replace("dimension: 2,", "dimension: 3,")
        .replace("origin: [0.0, 0.0], cell_size: 0.5, cells: [4, 24]", "origin: [0.0, 0.0, 0.0], cell_size: 0.5, cells: [4, 4, 24]")
        .replace(
            "Box(min: [0.0, 0.0], max: [2.0, 10.0]), points_per_cell: [2, 2]",
            "Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 10.0]), points_per_cell: [2, 2, 2]",
        )
        .replace("[0.0, -9.81]", "[0.0, 0.0, -9.81]")
        .replace(
            "(face: YMin, condition: Fixed)",
            "(face: ZMin, condition: Fixed), (face: YMin, condition: Roller), (face: YMax, condition: Roller)",
        )
        .replace("position: [0.875, 4.875]", "position: [0.875, 0.875, 4.875]");
    for (name, text) in [("layers", two), ("axisymmetric", turned), ("3D", solid)] {
        assert_ne!(text, COLUMN, "{name}");
        let s = run_text(name, &text);
        assert_eq!((s.outcome, s.steps), (Outcome::Converged, 1), "{name}");
    }
    let settled = run_text(
        "from rest",
        &COLUMN.replace(
            ",\n         initial_stress: Geostatic(k0: 0.42857142857142855)",
            "",
        ),
    );
    assert_eq!(settled.steps, 199);
    assert!((settled.traced[0].displacement[1] + 0.03826260235305362).abs() < 1e-12);
}

#[test]
fn a_geostatic_start_without_full_gravity_down_one_axis_is_refused() {
    let no_gravity = COLUMN
        .replace("gravity: (acceleration: [0.0, -9.81]),", "")
        .replace(
            "water: (table: Level(6.0), saturated_density: {\"soil\": 2000.0}),",
            "",
        );
    let ramped = COLUMN.replace("[0.0, -9.81])", "[0.0, -9.81], ramp_time: 1.0)");
    let slanted = COLUMN.replace("[0.0, -9.81])", "[1.0, -9.81])");
    let k0 = COLUMN.replace("k0: 0.42857142857142855", "k0: -0.5");
    // Each scene, the field its refusal names and words of its rule.
    for (text, field, rule) in [
        (no_gravity, "bodies[0].initial_stress", "needs gravity"),
        (ramped, "gravity.ramp_time", "from the first step"),
        (slanted, "gravity.acceleration", "down one axis"),
        (k0, "bodies[0].initial_stress.k0", "found -0.5"),
    ] {
        let e = refusal(&text);
        assert!(e.contains(field) && e.contains(rule), "{e}");
    }
}
