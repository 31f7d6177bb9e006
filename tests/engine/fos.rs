//! Factor of safety by strength reduction (`kdmpm fos`).

use crate::common;

use kdmpm::fos::{reduced, strength_reduction};
use kdmpm::materials::MohrCoulombSpec;
use kdmpm::scene::{LoadedScene, MaterialSpec};

fn slope() -> LoadedScene {
    LoadedScene::from_file(&common::scene("slope_fos.ron"), &[]).expect("scene loads")
}

#[test]
fn strength_reduction_divides_cohesion_and_the_tangents_of_the_angles() {
    let l = reduced(&slope(), 1.5);
    let MaterialSpec::MohrCoulomb(MohrCoulombSpec {
        cohesion,
        friction_angle,
        dilatancy_angle,
        ..
    }) = l.scene.materials["soil"]
    else {
        panic!("Mohr-Coulomb soil")
    };
    assert!((cohesion - 10.0e3 / 1.5).abs() < 1e-9);
    let expected = (20f64.to_radians().tan() / 1.5).atan().to_degrees();
    assert!((friction_angle - expected).abs() < 1e-12, "{friction_angle}");
    assert_eq!(dilatancy_angle, 0.0);
}

/// Griffiths & Lane (1999, Géotechnique 49(3), example 1): H = 10 m, 2:1 face, firm base
/// at the toe, c′ = 10 kPa, φ′ = 20°, ψ = 0: FoS = 1.4 by finite elements (Bishop and
/// Morgenstern's charts: 1.38; Bishop's simplified method 1.378). The scene, with its
/// volumetric smoothing, is pinned to the bracket its deterministic trials give,
/// 1.375–1.390625 (1.383, +0.3 % on Bishop; README).
#[test]
fn the_griffiths_lane_slope_has_bishops_factor_of_safety() {
    let out = common::scratch("fos", "griffiths-lane");
    let r = common::on_own_thread(|| strength_reduction(&slope(), &out, |_| {}))
        .expect("the bracket holds the factor");
    assert!(r.bracket[1] - r.bracket[0] <= 0.02, "{:?}", r.bracket);
    assert_eq!(r.bracket, [1.375, 1.390625]);
    // Every standing trial lies below every failing one.
    let stands = r
        .trials
        .iter()
        .filter(|t| !t.failed)
        .map(|t| t.factor)
        .fold(0.0, f64::max);
    let fails = r
        .trials
        .iter()
        .filter(|t| t.failed)
        .map(|t| t.factor)
        .fold(f64::INFINITY, f64::min);
    assert_eq!([stands, fails], r.bracket);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["factor_of_safety"].as_f64(), Some(r.factor_of_safety));
    assert!(out.join(&r.mechanism).join("points.vtu").exists());
    assert!(out.join("fos.csv").exists() && out.join("fos.svg").exists());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_bracket_that_does_not_hold_the_factor_of_safety_is_reported() {
    let out = common::scratch("fos", "not-bracketed");
    let loaded = LoadedScene::from_file(
        &common::scene("slope_fos.ron"),
        &["strength_reduction.bracket=[1.0, 1.2]".into()],
    )
    .unwrap();
    let e = strength_reduction(&loaded, &out, |_| {})
        .expect_err("stands at 1.2")
        .to_string();
    assert!(e.contains("stands at F = 1.2") && e.contains("raise"), "{e}");
    let _ = std::fs::remove_dir_all(&out);
}
