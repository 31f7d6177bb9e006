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
