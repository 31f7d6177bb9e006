//! The example's user system runs inside the schedule, once per step, at its named place;
//! and every step runs on a thread of the rayon pool.

#[path = "../../examples/custom_system.rs"]
#[allow(dead_code)]
mod example;

#[test]
fn a_user_system_inserted_after_g2p_runs_every_step() {
    let (mut sim, record) = example::bar_with_probe();
    let names = sim.schedule.names();
    let at = names.iter().position(|n| n == "max_speed_probe").unwrap();
    assert_eq!(names[at - 1], "g2p");
    sim.run(|_| {}).unwrap();
    let speeds = record.lock().unwrap();
    assert_eq!(speeds.len() as u64, sim.ctx.state.clock.step);
    // The bar's end moves at about F/(ρcA) = 1e-3 at the first peak.
    let peak = speeds.iter().cloned().fold(0.0, f64::max);
    assert!(peak > 5e-4 && peak < 3e-3, "peak speed {peak}");
    let probe = sim
        .schedule
        .timings()
        .into_iter()
        .find(|t| t.name == "max_speed_probe")
        .unwrap();
    assert_eq!(probe.calls, sim.ctx.state.clock.step);
}

#[test]
fn run_steps_on_a_pool_thread_so_parallel_loops_do_not_wake_the_caller() {
    let (mut sim, _) = example::bar_with_probe();
    let on_pool = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let seen = on_pool.clone();
    let probe = kdmpm::FnSystem::new("where_am_i", move |_: &mut kdmpm::Context<kdmpm::Dim3>| {
        seen.lock().unwrap().push(rayon::current_thread_index().is_some());
        Ok(())
    });
    assert!(sim.schedule.insert_after("g2p", probe));
    // The test's own thread is not a pool thread.
    assert!(rayon::current_thread_index().is_none());
    sim.run(|_| {}).unwrap();
    let on_pool = on_pool.lock().unwrap();
    assert_eq!(on_pool.len() as u64, sim.ctx.state.clock.step);
    assert!(on_pool.iter().all(|&p| p), "a step ran on the caller's thread");
}

/// Under USL g2p gathers kinematics' sums in its own visit of the nodes, which is right only
/// while nothing between them changes the nodal velocity. A user system placed there (here
/// one that stops every node) makes kinematics gather again after it: no point moves.
#[test]
fn a_system_between_g2p_and_kinematics_is_seen_by_the_kinematics() {
    use kdmpm::components::{NodeVelocity, Position};
    use kdmpm::infra::columns::{col, points_with};
    let positions = |sim: &kdmpm::Simulation<kdmpm::Dim3>| -> Vec<glam::DVec3> {
        let mut x = Vec::new();
        for arch in points_with::<Position<glam::DVec3>>(&sim.ctx.world) {
            x.extend(col::<Position<glam::DVec3>>(arch).iter().map(|p| p.0));
        }
        x
    };
    let usl = || {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
        let sets = vec!["solver.scheme=Usl".to_string()];
        let loaded = kdmpm::scene::LoadedScene::from_file(&path, &sets).unwrap();
        let kdmpm::AnySimulation::Three(sim) = kdmpm::scene::build(&loaded).unwrap().0 else {
            unreachable!("bar.ron is 3D")
        };
        sim
    };
    // As scheduled, the loaded end moves in the first step.
    let mut plain = usl();
    let start = positions(&plain);
    plain.step().unwrap();
    assert_ne!(positions(&plain), start);
    let mut stopped = usl();
    let halt = kdmpm::FnSystem::new("halt_nodes", |ctx: &mut kdmpm::Context<kdmpm::Dim3>| {
        for v in ctx.world.query_mut::<&mut NodeVelocity<glam::DVec3>>() {
            v.0 = glam::DVec3::ZERO;
        }
        Ok(())
    });
    assert!(stopped.schedule.insert_after("g2p", halt));
    stopped.step().unwrap();
    assert_eq!(positions(&stopped), start);
}

/// Where the schedule has no `volume_update` the stress update updates the volumes in its
/// own pass; one added from Rust takes that over, so the volumes are updated once a step
/// either way (the same bits).
#[test]
fn a_volume_update_added_from_rust_is_the_only_one() {
    use kdmpm::components::Volume;
    use kdmpm::infra::columns::{col, points_with};
    let bar = || {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
        let loaded = kdmpm::scene::LoadedScene::from_file(&path, &[]).unwrap();
        let kdmpm::AnySimulation::Three(sim) = kdmpm::scene::build(&loaded).unwrap().0 else {
            unreachable!("bar.ron is 3D")
        };
        sim
    };
    let volumes = |sim: &kdmpm::Simulation<kdmpm::Dim3>| -> Vec<f64> {
        let mut v = Vec::new();
        for arch in points_with::<Volume>(&sim.ctx.world) {
            v.extend(col::<Volume>(arch).iter().map(|v| v.0));
        }
        v
    };
    let (mut plain, mut added) = (bar(), bar());
    assert!(plain.schedule.position("volume_update").is_none());
    assert!(added
        .schedule
        .insert_after("stress_update", kdmpm::systems::VolumeUpdate));
    let start = volumes(&plain);
    for _ in 0..20 {
        plain.step().unwrap();
        added.step().unwrap();
    }
    assert_ne!(volumes(&plain), start);
    assert_eq!(volumes(&added), volumes(&plain));
}
