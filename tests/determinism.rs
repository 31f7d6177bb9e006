//! Parallel work is deterministic: the plastic slope gives the same bits on 1 and 2 threads,
//! spatial sorts included (every 50 steps here, eight in the run).

use kdmpm::columns::{col, points_with};
use kdmpm::components::{PlasticStrain, Position, Stress, Velocity};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Dim2};
use std::path::Path;

/// Every position, velocity, stress and plastic strain as raw bits, plus K_F and K_E.
fn fingerprint(threads: usize) -> Vec<u64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope.ron");
        let loaded = LoadedScene::from_file(
            &path,
            &["solver.max_steps=400".into(), "solver.sort_every=50".into()],
        )
        .unwrap();
        let AnySimulation::Two(mut sim) = build(&loaded).unwrap().0 else {
            unreachable!()
        };
        sim.run(|_| {}).unwrap();
        let mut bits = vec![
            sim.ctx.state.force_ratio_max.to_bits(),
            sim.ctx.state.energy_ratio.to_bits(),
        ];
        for arch in points_with::<Stress>(&sim.ctx.world) {
            for x in col::<Position<glam::DVec2>>(arch).iter() {
                bits.extend(x.0.to_array().map(f64::to_bits));
            }
            for v in col::<Velocity<glam::DVec2>>(arch).iter() {
                bits.extend(v.0.to_array().map(f64::to_bits));
            }
            for s in col::<Stress>(arch).iter() {
                bits.extend(s.0.to_array().map(f64::to_bits));
            }
            for e in col::<PlasticStrain>(arch).iter() {
                bits.push(e.0.to_bits());
            }
        }
        let _: &kdmpm::Simulation<Dim2> = &sim;
        bits
    })
}

#[test]
fn plastic_slope_is_bitwise_identical_on_one_and_two_threads() {
    let one = fingerprint(1);
    let two = fingerprint(2);
    assert_eq!(one.len(), two.len());
    let differing = one.iter().zip(&two).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} values differ", one.len());
    // And from run to run.
    assert_eq!(fingerprint(2), two);
}
