//! `Friction(δ)` faces: Coulomb friction between the soil and a grid face.

use crate::common;

use crate::common::{refusal, rel, run};

/// `scenes/sliding_block.ron`: once the block slides, the push that moves it is the base's
/// friction, tan δ · W = tan 20° · 39.24 kN/m = 14.28 kN/m. At rest at the end of each
/// increment the block keeps the compression friction holds in it: the last static state
/// gives 14.07 kN/m (−1.5 %), pinned.
#[test]
fn a_block_pushed_along_a_friction_base_needs_its_weight_times_tan_delta() {
    let s = run("sliding_block.ron", &[]);
    assert!(s.converged, "{:?}", s.error);
    let weight = 2000.0 * 9.81 * 2.0;
    let friction = 20f64.to_radians().tan() * weight;
    let last = s.curve.last().expect("ten increments");
    assert_eq!(s.curve.len(), 10);
    assert!(rel(last.force[0], 14074.0).abs() < 1e-4, "{} N/m", last.force[0]);
    assert!(
        rel(last.force[0], friction).abs() < 0.03,
        "{} N/m against {friction}",
        last.force[0]
    );
    // From the second increment on it slides: every row within 4 % of tan δ · W.
    for row in &s.curve[1..] {
        assert!(rel(row.force[0], friction).abs() < 0.04, "{row:?}");
    }
}

/// A friction angle of 0 is a roller, bit for bit: the block slides for free (a push within
/// what the stopping tolerance, K_F ≤ 0.001 of the weight, leaves), and a steeper base needs
/// more.
#[test]
fn friction_grows_with_the_angle_and_vanishes_at_zero() {
    let force = |condition: &str| {
        let s = run(
            "sliding_block.ron",
            &[&format!("boundaries[0].condition={condition}")],
        );
        assert!(s.converged, "{:?}", s.error);
        s.curve.last().unwrap().force[0]
    };
    let (roller, zero, steep) = (force("Roller"), force("Friction(0.0)"), force("Friction(30.0)"));
    assert_eq!(zero, roller);
    let weight = 2000.0 * 9.81 * 2.0;
    assert!(roller.abs() < 1e-3 * weight, "{roller} N/m");
    assert!(
        rel(steep, 30f64.to_radians().tan() * weight).abs() < 0.03,
        "{steep} N/m"
    );
}

#[test]
fn a_friction_angle_out_of_range_or_in_a_stage_is_refused() {
    let text = std::fs::read_to_string(common::scene("sliding_block.ron")).unwrap();
    for angle in ["90.0", "-1.0", "NaN"] {
        let e = refusal(&text.replace("Friction(20.0)", &format!("Friction({angle})")));
        assert!(
            e.contains("boundaries[0].condition") && e.contains("0 ≤ δ < 90"),
            "{e}"
        );
    }
    let staged = text.replace(
        "    solver: (",
        "    stages: [(name: \"a\"), (name: \"b\", boundaries: [(face: YMin, condition: Friction(10.0))])],\n    solver: (",
    );
    let e = refusal(&staged);
    assert!(
        e.contains("stages[1].boundaries[0].condition") && e.contains("Friction"),
        "{e}"
    );
}
