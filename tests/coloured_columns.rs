//! Under the binary's allocator, the large columns of a scene start at different offsets in
//! a page: particle-to-grid's node momentum and force (same stride, same index) never share
//! address bits 0–11, the layout that made it up to 4× slower in some runs (`kdmpm::alloc`).

use kdmpm::alloc::{Coloured, LARGE, PAGE};
use kdmpm::columns::{col, nodes, points_with};
use kdmpm::components::{Mass, NodeForce, NodeMass, NodeMomentum, Position, Stress, Velocity, Volume};
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
    solver: (time_step: Courant(0.3), max_steps: 1),
)"#;

#[test]
fn the_large_columns_of_a_scene_start_at_different_offsets_in_a_page() {
    let loaded = LoadedScene::from_text(Path::new("coloured.ron"), SCENE, &[]).unwrap();
    let AnySimulation::Three(sim) = build(&loaded).unwrap().0 else {
        unreachable!()
    };
    let world = &sim.ctx.world;
    let n = nodes(world);
    let mut columns: Vec<(&str, usize, usize)> = vec![(
        "node mass",
        col::<NodeMass>(n).as_ptr() as usize,
        size_of_val(&*col::<NodeMass>(n)),
    )];
    let vec_column = |name, ptr: *const u8, bytes| (name, ptr as usize, bytes);
    let momentum = col::<NodeMomentum<glam::DVec3>>(n);
    let force = col::<NodeForce<glam::DVec3>>(n);
    columns.push(vec_column(
        "node momentum",
        momentum.as_ptr().cast(),
        size_of_val(&*momentum),
    ));
    columns.push(vec_column(
        "node force",
        force.as_ptr().cast(),
        size_of_val(&*force),
    ));
    let arch = points_with::<Stress<Sym3>>(world).next().unwrap();
    let (x, v, m) = (
        col::<Position<glam::DVec3>>(arch),
        col::<Velocity<glam::DVec3>>(arch),
        col::<Mass>(arch),
    );
    let (s, vol) = (col::<Stress<Sym3>>(arch), col::<Volume>(arch));
    columns.push(vec_column("position", x.as_ptr().cast(), size_of_val(&*x)));
    columns.push(vec_column("velocity", v.as_ptr().cast(), size_of_val(&*v)));
    columns.push(vec_column("mass", m.as_ptr().cast(), size_of_val(&*m)));
    columns.push(vec_column("stress", s.as_ptr().cast(), size_of_val(&*s)));
    columns.push(vec_column("volume", vol.as_ptr().cast(), size_of_val(&*vol)));
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
