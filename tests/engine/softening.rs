//! Mohr-Coulomb with strain softening (`MohrCoulombSoftening`) in whole runs.

use crate::common;

use kdmpm::fos::strength_reduction;
use kdmpm::scene::LoadedScene;

/// The Griffiths–Lane soil (ρ, E, ν of scenes/slope_fos.ron) with peak c = 10 kPa,
/// φ = 20° and the given residual strength, reached at κ = `kappa_r`.
fn softening(c_r: f64, phi_r: f64, kappa_r: f64) -> String {
    format!(
        "materials.soil=MohrCoulombSoftening(density: 2038.74, youngs_modulus: 100.0e6, \
         poisson_ratio: 0.3, cohesion: 10.0e3, friction_angle: 20.0, residual_cohesion: {c_r:?}, \
         residual_friction_angle: {phi_r:?}, softening_strain: {kappa_r:?})"
    )
}

fn slope(overrides: &[String]) -> LoadedScene {
    LoadedScene::from_file(&common::scene("slope_fos.ron"), overrides).expect("scene loads")
}

#[test]
fn a_softening_soil_whose_residual_is_its_peak_runs_as_mohr_coulomb_bit_for_bit() {
    let scene = common::scene("slope_fos.ron");
    let (plain, soft) = (
        common::scratch("softening", "plain"),
        common::scratch("softening", "soft"),
    );
    let same = softening(10.0e3, 20.0, 0.01);
    for (out, extra) in [(&plain, None), (&soft, Some(same.as_str()))] {
        let o = common::run_into(&scene, out, extra.as_slice());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // The state column, its sort and its output (`plastic_strain`) included.
    for file in ["history.csv", "points.vtu"] {
        let (a, b) = (std::fs::read(plain.join(file)), std::fs::read(soft.join(file)));
        assert!(a.expect(file) == b.expect(file), "{file} differs");
    }
}

/// Softening lowers the factor of safety of the Griffiths–Lane slope below the one of its
/// peak strength, and not as far as the one of its residual strength alone: failure
/// progresses from the points that yield first, while the others keep their peak. On 1 m
/// cells: `kdmpm fos scenes/slope_fos.ron --set grid.cell_size=1.0 --set "grid.cells=[55,
/// 12]"` gives 1.414 for the peak strength (1.40625–1.421875, the bracket
/// tests/engine/robustness_features.rs pins for the same strength given by a stage); with
/// `--set "strength_reduction.bracket=[0.5, 2.0]" --set materials.soil=…` 0.764 for the
/// residual strength alone and 1.314 for softening from peak to residual at κ = 0.01 (on the
/// shipped 0.5 m cells: 1.383 for the peak).
#[test]
fn softening_puts_the_factor_of_safety_between_the_residual_and_the_peak() {
    let coarse = [
        "grid.cell_size=1.0",
        "grid.cells=[55, 12]",
        "strength_reduction.bracket=[0.5, 2.0]",
    ];
    let fos = |name: &str, material: String| {
        let out = common::scratch("softening", name);
        let mut overrides: Vec<String> = coarse.iter().map(|s| s.to_string()).collect();
        overrides.push(material);
        common::on_own_thread(|| strength_reduction(&slope(&overrides), &out, |_| {}))
            .expect("the bracket holds the factor")
            .factor_of_safety
    };
    // The peak strength's factor on these cells (above), not run again here.
    let peak = 1.4140625;
    let residual_only = "materials.soil=MohrCoulomb(density: 2038.74, youngs_modulus: 100.0e6, \
                         poisson_ratio: 0.3, cohesion: 2.0e3, friction_angle: 16.0)"
        .to_string();
    let residual = fos("fos-residual", residual_only);
    let soft = fos("fos-soft", softening(2.0e3, 16.0, 0.01));
    // Pinned: each is the middle of its last bracket (0.7578–0.7695, 1.3086–1.3203).
    assert_eq!([residual, soft], [0.763671875, 1.314453125]);
    assert!(
        residual + 0.1 < soft && soft < peak - 0.05,
        "residual {residual}, softening {soft}, peak {peak}"
    );
}

#[test]
fn a_stage_may_not_give_a_material_a_model_with_another_state() {
    let text = std::fs::read_to_string(common::scene("slope_fos.ron")).expect("scene");
    let stage = "stages: [(name: \"soft\", materials: {\"soil\": MohrCoulombSoftening(density: 2038.74, \
                 youngs_modulus: 100.0e6, poisson_ratio: 0.3, cohesion: 10.0e3, friction_angle: 20.0, \
                 residual_cohesion: 2.0e3, residual_friction_angle: 16.0, softening_strain: 0.01)})],";
    let bad = text.replacen("    solver: (", &format!("    {stage}\n    solver: ("), 1);
    let e = common::refusal(&bad);
    assert!(e.contains("stages[0].materials.soil"), "{e}");
    assert!(
        e.contains("MohrCoulombSoftening has another internal state than MohrCoulomb"),
        "{e}"
    );
}
