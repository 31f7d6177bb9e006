//! Under the binary's allocator, the large columns of a scene start at different offsets in
//! a page: particle-to-grid's node momentum and force (same stride, same index) never share
//! address bits 0–11, the layout that made it up to 4× slower in some runs (`kdmpm::infra::alloc`).

use glam::DVec3;
use kdmpm::components::{Mass, NodeForce, NodeMass, NodeMomentum, Position, Stress, Velocity, Volume};
use kdmpm::infra::alloc::{Coloured, LARGE, PAGE};
use kdmpm::infra::columns::{col, nodes, points_with};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::tensor::Sym3;
use kdmpm::AnySimulation;
use std::path::Path;

#[global_allocator]
static ALLOCATOR: Coloured = Coloured;

/// A block of 4 × 4 × 4 points a cell in a grid of 41 × 41 × 41 nodes: every node column and
/// every point column holds at least `LARGE` bytes.
const SCENE: &str = r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 1.0, cells: [40, 40, 40]),
    materials: { "soil": LinearElastic(density: 2000.0, youngs_modulus: 2e7, poisson_ratio: 0.3) },
    bodies: [(material: "soil", region: Box(min: [0.0, 0.0, 0.0], max: [8.0, 8.0, 8.0]), points_per_cell: [4, 4, 4])],
    gravity: (acceleration: [0.0, 0.0, -9.81]),
    solver: (time_step: Courant(0.3), max_steps: 1),
)"#;

/// A column's name, start address and length in bytes.
fn span<'a, T>(name: &'a str, column: &[T]) -> (&'a str, usize, usize) {
    (name, column.as_ptr() as usize, size_of_val(column))
}

#[test]
fn the_large_columns_of_a_scene_start_at_different_offsets_in_a_page() {
    let loaded = LoadedScene::from_text(Path::new("coloured.ron"), SCENE, &[]).unwrap();
    let AnySimulation::Three(sim) = build(&loaded).unwrap().0 else {
        unreachable!()
    };
    let world = &sim.ctx.world;
    let n = nodes(world);
    let arch = points_with::<Stress<Sym3>>(world).next().unwrap();
    let columns = [
        span("node mass", &col::<NodeMass>(n)),
        span("node momentum", &col::<NodeMomentum<DVec3>>(n)),
        span("node force", &col::<NodeForce<DVec3>>(n)),
        span("position", &col::<Position<DVec3>>(arch)),
        span("velocity", &col::<Velocity<DVec3>>(arch)),
        span("mass", &col::<Mass>(arch)),
        span("stress", &col::<Stress<Sym3>>(arch)),
        span("volume", &col::<Volume>(arch)),
    ];
    for &(name, _, bytes) in &columns {
        assert!(bytes >= LARGE, "{name}: {bytes} bytes, too small to be coloured");
    }
    for (k, a) in columns.iter().enumerate() {
        for b in &columns[k + 1..] {
            assert_ne!(
                a.1 % PAGE,
                b.1 % PAGE,
                "{} and {} share an offset in a page",
                a.0,
                b.0
            );
        }
    }
}
