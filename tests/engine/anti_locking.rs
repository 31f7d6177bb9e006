//! The volumetric treatments against locking: what `anti_locking: CellMean` keeps true at
//! every step, and what it does to a dilatant soil's limit load.

use crate::common;

use crate::common::kdmpm;
use kdmpm::components::{Position, Stress, Volume};
use kdmpm::infra::columns::{col, points_with};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::tensor::{PlanarSym3, StoredSym};
use kdmpm::AnySimulation;
use std::collections::BTreeMap;

/// The c–φ footing (φ = ψ = 30°) at the end of its first increment, plastic under
/// the footing's edge: after every step the points of a cell share one in-plane mean
/// stress, whichever of them yielded, and every point stays inside Mohr–Coulomb's envelope
/// (the cap of `cell_mean.rs` holds the mean where the shift took a point outside).
#[test]
fn cell_means_give_the_points_of_a_cell_one_mean_stress_inside_the_envelope() {
    let path = common::scene("footing_cphi.ron");
    let sets = ["solver.anti_locking=CellMean", "solver.max_steps=1500"].map(String::from);
    let loaded = LoadedScene::from_file(&path, &sets).unwrap();
    let AnySimulation::Two(mut sim) = build(&loaded).unwrap().0 else {
        unreachable!("a 2D scene")
    };
    sim.run(|_| {}).unwrap();
    let (h, c, phi) = (0.25, 10.0e3, 30f64.to_radians());
    let mut cells: BTreeMap<(i64, i64), Vec<f64>> = BTreeMap::new();
    let mut plastic = 0;
    for arch in points_with::<Volume>(&sim.ctx.world) {
        let x = col::<Position<glam::DVec2>>(arch);
        let s = col::<Stress<PlanarSym3>>(arch);
        for (x, s) in x.iter().zip(s.iter()) {
            let t = s.0.to_sym3();
            let key = ((x.0.x / h).floor() as i64, (x.0.y / h).floor() as i64);
            cells.entry(key).or_default().push(0.5 * (t.xx + t.yy));
            // Mohr–Coulomb on the in-plane circle (σ_zz lies between in plane strain here).
            let radius = (0.25 * (t.xx - t.yy).powi(2) + t.xy * t.xy).sqrt();
            let f = radius + 0.5 * (t.xx + t.yy) * phi.sin() - c * phi.cos();
            assert!(f < 1e-6 * c, "outside the envelope by {f} Pa at {:?}", x.0);
            plastic += usize::from(f > -1e-3 * c);
        }
    }
    assert!(
        plastic > 10,
        "the footing's edge yields ({plastic} points on the envelope)"
    );
    for (cell, means) in &cells {
        let spread = means.iter().fold(0.0f64, |a, m| a.max((m - means[0]).abs()));
        assert!(spread <= 1e-9 * c, "cell {cell:?}: means {means:?}");
    }
}

/// A scene written for the boolean the field replaced is refused (exit 2), at its line, with
/// the field that takes its place.
#[test]
fn the_old_volumetric_smoothing_field_is_refused_naming_anti_locking() {
    let scene = common::scene("footing.ron");
    let out = kdmpm(&[
        "check",
        scene.to_str().unwrap(),
        "--set",
        "solver.volumetric_smoothing=true",
    ]);
    let text = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{text}");
    assert!(
        text.contains("footing.ron:")
            && text.contains("`volumetric_smoothing`")
            && text.contains("`anti_locking`"),
        "{text}"
    );
}
