//! The profile's byte budget (docs/performance.md, "The byte budget"): every system of a
//! plain step counts the bytes of point and node columns it moves, and the counts are the
//! columns' sizes over the points and the box of nodes the step reached.

use kdmpm::scene::{build, LoadedScene};
use kdmpm::AnySimulation;
use std::path::Path;

fn block(scheme: &str) -> kdmpm::Simulation<kdmpm::Dim3> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/block_10k.ron");
    let sets = vec![format!("solver.scheme={scheme}")];
    let AnySimulation::Three(sim) = build(&LoadedScene::from_file(&path, &sets).unwrap()).unwrap().0 else {
        panic!("the block is 3D")
    };
    sim
}

/// The bytes system `name` counted over the calls so far.
fn bytes_of(sim: &kdmpm::Simulation<kdmpm::Dim3>, name: &str) -> kdmpm::infra::traffic::Traffic {
    let t = sim
        .schedule
        .timings()
        .into_iter()
        .find(|t| t.name == name)
        .unwrap();
    t.bytes.unwrap()
}

#[test]
fn every_system_of_a_plain_step_counts_its_bytes() {
    for scheme in ["Musl", "Usl", "Usf"] {
        let mut sim = block(scheme);
        sim.step().unwrap();
        for t in sim.schedule.timings() {
            // The sort moves every column when it reorders and nothing otherwise; the
            // history writes a file.
            let counts = !matches!(t.name.as_str(), "spatial_sort" | "history");
            assert_eq!(t.bytes.is_some(), counts, "{scheme}: {}", t.name);
        }
    }
}

#[test]
fn the_block_moves_its_columns_bytes_a_musl_step() {
    let mut sim = block("Musl");
    sim.step().unwrap();
    let (points, nodes) = (sim.point_count() as u64, sim.ctx.state.active_nodes.len() as u64);
    assert_eq!((points, nodes), (10_648, 12 * 12 * 12));
    let bytes = |name: &str| bytes_of(&sim, name);
    // Particle-to-grid reads the scatter's order (4 B), position (24), mass (8), velocity
    // (24), stress (48) and volume (8) of each point, and adds into each node's mass (8),
    // momentum (24) and force (24).
    let p2g = bytes("p2g");
    assert_eq!(p2g.read, points * (4 + 24 + 8 + 24 + 48 + 8) + nodes * 56);
    assert_eq!(p2g.written, nodes * 56);
    // The velocity gradient (72 B) written by the kinematics is read once, by the stress
    // update, which updates the volumes in the same pass; the stress (48) and the volume (8)
    // are read and written.
    assert_eq!(bytes("kinematics").written, points * (72 + 24));
    let stress = bytes("stress_update");
    assert_eq!(
        (stress.read, stress.written),
        (points * (72 + 2 + 48 + 8), points * (48 + 8))
    );
    assert!(sim.schedule.timings().iter().all(|t| t.name != "volume_update"));
}

/// USL: g2p gathers the velocity gradient and the points' nodal velocity beside their
/// accelerations, and kinematics only moves the points by what it left.
#[test]
fn a_usl_step_gathers_the_velocity_gradient_in_g2p() {
    let mut sim = block("Usl");
    sim.step().unwrap();
    let (points, nodes) = (sim.point_count() as u64, sim.ctx.state.active_nodes.len() as u64);
    let bytes = |name: &str| bytes_of(&sim, name);
    // Position (24), mass (8) and velocity (24) of each point, each node's acceleration and
    // velocity (24 each); the velocity, the velocity gradient (72) and the nodal velocity at
    // the point (24) written.
    let g2p = bytes("g2p");
    assert_eq!(g2p.read, points * (24 + 8 + 24) + nodes * 48);
    assert_eq!(g2p.written, points * (24 + 72 + 24));
    // The nodal velocity at the point read, the position read and written.
    let kinematics = bytes("kinematics");
    assert_eq!((kinematics.read, kinematics.written), (points * 48, points * 24));
}

/// USF: g2p gathers the points' nodal velocity beside their accelerations, and
/// `move_points` only moves them by what it left.
#[test]
fn a_usf_step_moves_the_points_by_the_nodal_velocity_g2p_gathered() {
    let mut sim = block("Usf");
    sim.step().unwrap();
    let (points, nodes) = (sim.point_count() as u64, sim.ctx.state.active_nodes.len() as u64);
    let bytes = |name: &str| bytes_of(&sim, name);
    // Position, mass and velocity read, each node's acceleration and velocity; the velocity
    // and the nodal velocity at the point (24) written.
    let g2p = bytes("g2p");
    assert_eq!(g2p.read, points * (24 + 8 + 24) + nodes * 48);
    assert_eq!(g2p.written, points * (24 + 24));
    let moved = bytes("move_points");
    assert_eq!((moved.read, moved.written), (points * 48, points * 24));
}
