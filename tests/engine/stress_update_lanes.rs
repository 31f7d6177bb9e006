//! The stress update treats points four at a time in SIMD lanes; every point must still get
//! the bits it gets alone: the Jaumann rotation and the material's update of one point
//! (`jaumann_rotate`, `Material::update`) are the reference. Checked on a 3D scene whose
//! groups of four mix materials (two elastic, two Mohr-Coulomb) and whose archetypes end in
//! short groups, with strain and spin increments large enough that the soils yield.

use glam::DMat3;
use kdmpm::components::{MaterialId, Stress, VelocityGradient};
use kdmpm::infra::columns::{col, col_mut, points_with};
use kdmpm::materials::PlasticStrain;

use kdmpm::scene::{build, LoadedScene};
use kdmpm::systems::StressUpdate;
use kdmpm::tensor::Sym3;
use kdmpm::{AnySimulation, Dim, Dim3, System};
use std::path::Path;

const SCENE: &str = r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 1.0, cells: [6, 6, 6]),
    shape: Linear,
    materials: {
        "stiff": LinearElastic(density: 2000.0, youngs_modulus: 40.0e6, poisson_ratio: 0.25),
        "soft": LinearElastic(density: 1800.0, youngs_modulus: 5.0e6, poisson_ratio: 0.35),
        "sand": MohrCoulomb(density: 2000.0, youngs_modulus: 20.0e6, poisson_ratio: 0.3,
            cohesion: 0.0, friction_angle: 30.0, dilatancy_angle: 0.0),
        "clay": MohrCoulomb(density: 1900.0, youngs_modulus: 10.0e6, poisson_ratio: 0.4,
            cohesion: 20.0e3, friction_angle: 15.0, dilatancy_angle: 5.0),
    },
    // Bodies of 45, 30, 45 and 30 points (1 a cell): sorted by cell, each pair of materials
    // interleaves along x, and 75 points per archetype leave a group of three at its end.
    bodies: [
        (material: "stiff", region: Box(min: [0.0, 0.0, 0.0], max: [3.0, 5.0, 3.0]), points_per_cell: [1, 1, 1]),
        (material: "soft", region: Box(min: [3.0, 0.0, 0.0], max: [5.0, 5.0, 3.0]), points_per_cell: [1, 1, 1]),
        (material: "sand", region: Box(min: [0.0, 0.0, 3.0], max: [3.0, 5.0, 6.0]), points_per_cell: [1, 1, 1]),
        (material: "clay", region: Box(min: [3.0, 0.0, 3.0], max: [5.0, 5.0, 6.0]), points_per_cell: [1, 1, 1]),
    ],
    boundaries: [(face: ZMin, condition: Fixed)],
    gravity: (acceleration: [0.0, 0.0, -9.81]),
    solver: (damping: Kinetic, scheme: Musl, time_step: Courant(0.3), max_steps: 1, sort_every: 1),
)"#;

/// A reproducible value in [−1, 1) (a 64-bit linear congruential generator).
fn next(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    (*seed >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[test]
fn points_updated_four_at_a_time_get_the_bits_of_points_updated_one_at_a_time() {
    let loaded = LoadedScene::from_text(Path::new("lanes.ron"), SCENE, &[]).expect("scene loads");
    let AnySimulation::Three(mut sim) = build(&loaded).expect("scene builds").0 else {
        unreachable!("3D scene")
    };
    // One step sorts the points by cell, which interleaves the materials of each archetype.
    sim.step().expect("one step");
    let ctx = &mut sim.ctx;
    let dt = ctx.numerics.dt;
    let mut seed = 7;
    let mut expected = Vec::new();
    let mut mixed_groups = 0;
    for arch in points_with::<Stress<Sym3>>(&ctx.world) {
        let ids: Vec<u16> = col::<MaterialId>(arch).iter().map(|m| m.0).collect();
        mixed_groups += ids.chunks(4).filter(|g| g.iter().any(|m| *m != g[0])).count();
        let mut l = col_mut::<VelocityGradient<DMat3>>(arch);
        let mut s = col_mut::<Stress<Sym3>>(arch);
        let mut eps = arch.get::<&mut PlasticStrain>();
        for p in 0..s.len() {
            // Strain increments up to 3 %, spins up to 0.3 rad, stresses up to 500 kPa.
            l[p].0 = DMat3::from_cols_array(&std::array::from_fn(|_| 0.3 * next(&mut seed) / dt));
            let a: [f64; 6] = std::array::from_fn(|_| 5e5 * next(&mut seed));
            s[p].0 = Sym3 {
                xx: a[0],
                yy: a[1],
                zz: a[2],
                xy: a[3],
                yz: a[4],
                zx: a[5],
            };
            let (de, w) = Dim3::strain_spin(|i, j| Dim3::mat_entry(&l[p].0, i, j), dt);
            let mut alone = Dim3::jaumann_rotate(&s[p].0, w);
            let mut e = eps.as_deref_mut().map(|e| e[p]);
            let material = &ctx.materials[ids[p] as usize];
            match e.as_mut() {
                Some(e) => material.update(&mut alone, &de, e),
                None => material.update(&mut alone, &de, &mut ()),
            }
            expected.push((alone, e.map(|e| e.0)));
        }
    }
    assert!(
        mixed_groups >= 4,
        "the scene must mix materials within groups: {mixed_groups}"
    );
    StressUpdate::default().run(ctx).expect("stress update");
    let mut got = Vec::new();
    for arch in points_with::<Stress<Sym3>>(&ctx.world) {
        let s = col::<Stress<Sym3>>(arch);
        let eps = arch.get::<&PlasticStrain>();
        for p in 0..s.len() {
            got.push((s[p].0, eps.as_deref().map(|e| e[p].0)));
        }
    }
    let bits = |v: &[(Sym3, Option<f64>)]| -> Vec<u64> {
        v.iter()
            .flat_map(|(s, e)| s.to_array().into_iter().chain(*e).map(f64::to_bits))
            .collect()
    };
    let yielded = got
        .iter()
        .zip(&expected)
        .filter(|(g, _)| g.1.is_some_and(|e| e > 0.0))
        .count();
    assert!(yielded >= 20, "the soils must yield: {yielded} points did");
    assert_eq!(got.len(), 150);
    assert_eq!(bits(&got), bits(&expected));
}
