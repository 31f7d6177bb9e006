//! Per-system micro-benchmarks on the 2D slope after 200 steps of failure: particle-to-grid,
//! grid-to-particle, the Mohr-Coulomb stress update and the convergence monitor; and what
//! water costs a step of the slope with a water table (particle-to-grid with and without
//! its water, on the same points, and a whole step).

use criterion::{criterion_group, criterion_main, Criterion};
use kdmpm::infra::lanes::LANES;
use kdmpm::materials::{Material, MohrCoulomb, PlasticStrain};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::shape::QuadraticBSpline;
use kdmpm::systems::{Convergence, G2p, GridReset, P2g, P2gPart};
use kdmpm::tensor::{Sym3, Sym3x4};
use kdmpm::{AnySimulation, Dim2, Simulation, System};
use std::path::Path;

/// As the `kdmpm` binary: large blocks coloured (see `kdmpm::infra::alloc`).
#[global_allocator]
static ALLOCATOR: kdmpm::infra::alloc::Coloured = kdmpm::infra::alloc::Coloured;

fn slope() -> Simulation<Dim2> {
    after_200_steps("scenes/slope.ron")
}

fn after_200_steps(scene: &str) -> Simulation<Dim2> {
    // This package is benches/ in the kdmpm checkout: scenes are one level up.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(scene);
    let loaded = LoadedScene::from_file(&path, &[]).unwrap();
    let AnySimulation::Two(mut sim) = build(&loaded).unwrap().0 else {
        unreachable!()
    };
    for _ in 0..200 {
        sim.step().unwrap();
    }
    sim
}

fn kernels(c: &mut Criterion) {
    let mut sim = slope();
    let mut p2g = P2g::<Dim2, QuadraticBSpline>::new(P2gPart::All);
    c.bench_function("p2g (2D slope, B-spline, 23k points)", |b| {
        b.iter(|| {
            GridReset::default().run(&mut sim.ctx).unwrap();
            p2g.run(&mut sim.ctx).unwrap();
        })
    });
    let mut g2p = G2p::<Dim2, QuadraticBSpline>::default();
    c.bench_function("g2p (2D slope, B-spline, 23k points)", |b| {
        b.iter(|| g2p.run(&mut sim.ctx).unwrap())
    });
    let mut conv = Convergence;
    c.bench_function("convergence (2D slope grid)", |b| {
        b.iter(|| conv.run(&mut sim.ctx).unwrap())
    });
    let mc = MohrCoulomb::new(2000.0, 20e6, 0.4, 0.0, 20.0, 0.0, None);
    let start = Sym3 {
        xx: -1.0e5,
        yy: -2.5e5,
        zz: -1.4e5,
        xy: 3.0e4,
        ..Sym3::ZERO
    };
    let de = Sym3 {
        xx: 2e-5,
        yy: -3e-5,
        xy: 1e-5,
        ..Sym3::ZERO
    };
    c.bench_function("Mohr-Coulomb update (plastic, plane strain)", |b| {
        b.iter(|| {
            let mut s = std::hint::black_box(start);
            let mut eps = PlasticStrain(0.0);
            mc.update(&mut s, &de, &mut eps);
            (s, eps)
        })
    });
    // Four points at rest (K0 = ν/(1 − ν) = 0.667) under a small increment: the state of
    // most of a slope once it has failed. One by one, and in lanes as the stress update
    // calls it.
    let at_rest: [Sym3; LANES] = std::array::from_fn(|q| {
        let v = -1.0e5 * (1.0 + 0.1 * q as f64);
        Sym3::diagonal(0.667 * v, v, 0.667 * v)
    });
    c.bench_function("Mohr-Coulomb update (4 elastic points, one by one)", |b| {
        b.iter(|| {
            let mut s = std::hint::black_box(at_rest);
            let mut eps = [PlasticStrain(0.0); LANES];
            for (s, eps) in s.iter_mut().zip(&mut eps) {
                mc.update(s, &de, eps);
            }
            (s, eps)
        })
    });
    let (at_rest4, de4) = (Sym3x4::gather(|q| at_rest[q]), Sym3x4::gather(|_| de));
    c.bench_function("Mohr-Coulomb update (4 elastic points, in lanes)", |b| {
        b.iter(|| {
            let mut s = std::hint::black_box(at_rest4);
            let mut eps = [PlasticStrain(0.0); LANES];
            mc.update4(&mut s, &de4, eps.each_mut());
            (s, eps)
        })
    });
}

/// The pore water's load rides on p2g: its cost is p2g with the water less p2g without it,
/// on the same points in the same run; beside it, a whole step of the wet slope.
fn water(c: &mut Criterion) {
    let mut sim = after_200_steps("scenes/slope_water.ron");
    let mut p2g = P2g::<Dim2, QuadraticBSpline>::new(P2gPart::All);
    let water = sim.ctx.model.water.clone();
    c.bench_function("p2g (slope_water, with its water)", |b| {
        b.iter(|| {
            GridReset::default().run(&mut sim.ctx).unwrap();
            p2g.run(&mut sim.ctx).unwrap();
        })
    });
    sim.ctx.model.water = None;
    c.bench_function("p2g (slope_water, the same points dry)", |b| {
        b.iter(|| {
            GridReset::default().run(&mut sim.ctx).unwrap();
            p2g.run(&mut sim.ctx).unwrap();
        })
    });
    sim.ctx.model.water = water;
    c.bench_function("step (slope_water)", |b| b.iter(|| sim.step().unwrap()));
}

criterion_group!(benches, kernels, water);
criterion_main!(benches);
