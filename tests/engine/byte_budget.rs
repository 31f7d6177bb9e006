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

/// USL and USF: g2p gathers the points' nodal velocity (and under USL their velocity
/// gradient) beside their accelerations, and the system that moves the points after it
/// only moves them by what it left.
#[test]
fn usl_and_usf_steps_gather_the_motion_in_g2p() {
    // The scheme, the system that moves the points, and what g2p writes a point besides
    // the velocity (24 B) and the nodal velocity at the point (24): USL's velocity
    // gradient (72).
    for (scheme, mover, gradient) in [("Usl", "kinematics", 72), ("Usf", "move_points", 0)] {
        let mut sim = block(scheme);
        sim.step().unwrap();
        let (points, nodes) = (sim.point_count() as u64, sim.ctx.state.active_nodes.len() as u64);
        // Position (24), mass (8) and velocity (24) of each point, each node's acceleration
        // and velocity (24 each).
        let g2p = bytes_of(&sim, "g2p");
        assert_eq!(g2p.read, points * (24 + 8 + 24) + nodes * 48, "{scheme}");
        assert_eq!(g2p.written, points * (24 + gradient + 24), "{scheme}");
        // The nodal velocity at the point read, the position read and written.
        let moved = bytes_of(&sim, mover);
        assert_eq!(
            (moved.read, moved.written),
            (points * 48, points * 24),
            "{scheme}"
        );
    }
}
