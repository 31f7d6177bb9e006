//! Parallel work is deterministic: the plastic slope gives the same bits on 1 and 2 threads,
//! spatial sorts included (every 50 steps here, eight in the run), and the same bits whether
//! the scatters share their grouping of points or group them anew.

use crate::common;
use kdmpm::components::{Position, Stress, Velocity};
use kdmpm::infra::columns::{col, points_with};
use kdmpm::materials::PlasticStrain;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::tensor::{PlanarSym3, StoredSym};
use kdmpm::{AnySimulation, Context, Dim2, FnSystem, StepError};
use std::path::Path;

/// Every position, velocity, stress and plastic strain as raw bits, plus K_F and K_E.
fn fingerprint(threads: usize) -> Vec<u64> {
    run(threads, &["solver.max_steps=400", "solver.sort_every=50"], false)
}

/// The slope after a run with `overrides`, as raw bits; with `regroup`, every scatter groups
/// the points anew instead of reusing the slabs of an earlier one.
fn run(threads: usize, overrides: &[&str], regroup: bool) -> Vec<u64> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope.ron");
        let overrides: Vec<String> = overrides.iter().map(|o| o.to_string()).collect();
        let loaded = LoadedScene::from_file(&path, &overrides).unwrap();
        let AnySimulation::Two(mut sim) = build(&loaded).unwrap().0 else {
            unreachable!()
        };
        if regroup {
            for scatter in [
                "p2g",
                "p2g_momentum",
                "p2g_force",
                "remap",
                "volumetric_smoothing",
                "cell_mean_strain",
                "cell_mean_stress",
            ] {
                let forget = |ctx: &mut Context<Dim2>| -> Result<(), StepError> {
                    ctx.slabs.invalidate();
                    Ok(())
                };
                sim.schedule
                    .insert_before(scatter, FnSystem::new(format!("forget_{scatter}"), forget));
            }
        }
        sim.run(|_| {}).unwrap();
        let mut bits = vec![
            sim.ctx.state.convergence.force_ratio_max.to_bits(),
            sim.ctx.state.convergence.energy_ratio.to_bits(),
        ];
        for arch in points_with::<Stress<PlanarSym3>>(&sim.ctx.world) {
            for x in col::<Position<glam::DVec2>>(arch).iter() {
                bits.extend(x.0.to_array().map(f64::to_bits));
            }
            for v in col::<Velocity<glam::DVec2>>(arch).iter() {
                bits.extend(v.0.to_array().map(f64::to_bits));
            }
            for s in col::<Stress<PlanarSym3>>(arch).iter() {
                bits.extend(s.0.to_sym3().to_array().map(f64::to_bits));
            }
            for e in col::<PlasticStrain>(arch).iter() {
                bits.push(e.0.to_bits());
            }
        }
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

#[test]
fn the_slope_with_cell_means_is_bitwise_identical_on_one_and_two_threads() {
    let overrides = [
        "solver.max_steps=400",
        "solver.sort_every=50",
        "solver.anti_locking=CellMean",
    ];
    let (one, two) = (run(1, &overrides, false), run(2, &overrides, false));
    let differing = one.iter().zip(&two).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} values differ", one.len());
}

#[test]
fn scatters_sharing_their_slabs_give_the_bits_of_slabs_built_for_every_scatter() {
    // MUSL (remap reuses p2g's slabs) with volumetric smoothing (p2g reuses the smoothing's)
    // or cell means (the stress's reuses the strain's), and USF (the force pass reuses the
    // momentum pass's); sorts every 25 steps. On `common::COARSE_SLOPE`'s grid (10 343
    // points, 90 × 23 cells): which slabs a scatter uses does not depend on the cell size.
    for (scheme, locking) in [
        ("Musl", "StrainSmoothing"),
        ("Usf", "StrainSmoothing"),
        ("Musl", "CellMean"),
        ("Usf", "CellMean"),
    ] {
        let (locking_set, scheme_set) = (
            format!("solver.anti_locking={locking}"),
            format!("solver.scheme={scheme}"),
        );
        let mut overrides = common::COARSE_SLOPE.to_vec();
        overrides.extend([
            "solver.max_steps=120",
            "solver.sort_every=25",
            &locking_set,
            &scheme_set,
        ]);
        let shared = run(2, &overrides, false);
        let anew = run(2, &overrides, true);
        let differing = shared.iter().zip(&anew).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing,
            0,
            "{scheme}, {locking}: {differing} of {} values differ",
            shared.len()
        );
    }
}
