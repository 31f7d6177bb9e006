//! The paper's Example 2: a 40 m cohesionless slope (φ = 20°, 30° face) that fails and comes
//! to rest, and its stable companion (φ = 35°).
//!
//! Paper: the run stops at t = 24.28 s and the final surface stands at about φ = 20°.
//! Expected angle here: Davis's effective friction angle for non-associated flow in plane
//! strain, tan φ* = sin φ cos ψ / (1 − sin φ sin ψ) = sin 20° → φ* = 18.9°.

use crate::common;

use kdmpm::components::Mass;
use kdmpm::infra::columns::{col, points_with};
use kdmpm::measure::{all_positions_finite, max_displacements, max_movement, positions, surface_angle};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::state::StopReason;
use kdmpm::{with_simulation, Dim, Simulation};
use std::path::Path;

fn scene(name: &str, overrides: &[&str]) -> kdmpm::AnySimulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    build(&LoadedScene::from_file(&path, &o).unwrap()).unwrap().0
}

/// Sum of point masses, compared bit for bit.
fn mass_bits<D: Dim>(sim: &Simulation<D>) -> u64 {
    points_with::<Mass>(&sim.ctx.world)
        .map(|a| col::<Mass>(a).iter().map(|m| m.0).sum::<f64>())
        .sum::<f64>()
        .to_bits()
}

/// Where a slope came to rest.
struct Rest {
    /// Simulated time at the stop (s).
    time: f64,
    /// Steps to the stop.
    steps: u64,
    /// Surface angle (degrees).
    angle: f64,
    /// Largest |u_x| of any point (m).
    max_ux: f64,
    /// The traced crest point's u_x (m).
    crest_ux: f64,
    /// Largest movement in 10 s more (m).
    moved: f64,
}

/// Checks a deterministic figure against the value the run gives (2 threads or 1): within
/// `rel` of it, a band that a change of summation order survives and a regression does not.
fn pinned(what: &str, value: f64, reference: f64, rel: f64) {
    assert!(
        (value / reference - 1.0).abs() <= rel,
        "{what} {value}, pinned at {reference} (within {:.2} %)",
        100.0 * rel
    );
}

/// Runs to the stop, then 10 s more.
fn run_and_continue<D: Dim>(sim: &mut Simulation<D>) -> Rest {
    let mass0 = mass_bits(sim);
    sim.run(|_| {})
        .expect("no point leaves the grid, nothing becomes NaN");
    let s = &sim.ctx.state;
    assert_eq!(
        s.stop,
        Some(StopReason::Converged),
        "t = {}, K_F = {}, K_E = {}",
        s.clock.time,
        s.convergence.force_ratio_max,
        s.convergence.energy_ratio
    );
    let (t_stop, steps, norm) = (s.clock.time, s.clock.step, sim.ctx.numerics.force_norm);
    assert!(s.convergence.force_ratio(norm) <= 0.01 && s.convergence.energy_ratio <= 0.01);
    let angle = surface_angle(sim).expect("a surface").degrees;
    let (_, max_ux) = max_displacements(sim).expect("the slope scenes keep displacements");
    let crest = sim
        .traced_results()
        .into_iter()
        .find(|t| t.name == "crest")
        .unwrap();
    assert_eq!(mass_bits(sim), mass0, "total mass changed");
    assert!(all_positions_finite(sim));
    // Static: ten more seconds move nothing by more than 1 cm.
    let (mut before, mut after) = (Vec::new(), Vec::new());
    positions::<D>(&sim.ctx.world, &mut before);
    let more = (10.0 / sim.ctx.numerics.dt).ceil() as u64;
    for _ in 0..more {
        sim.step().expect("continuing stays stable");
    }
    positions::<D>(&sim.ctx.world, &mut after);
    let moved = max_movement(&before, &after);
    println!(
        "stop t = {t_stop:.2} s, angle {angle:.2}°, max u_x {max_ux:.3} m, moved {moved:.4} m in 10 s more"
    );
    Rest {
        time: t_stop,
        steps,
        angle,
        max_ux,
        crest_ux: crest.displacement[0],
        moved,
    }
}

/// The paper's settings (MUSL, Courant 0.2, the 10 s static check) on 2 m cells with 4×4
/// points a cell, a quarter of the shipped scene's points and half its steps a second (the
/// shipped 1 m cells: 28 131 steps, 18.994°, docs/verification.md). The run is
/// deterministic, pinned to what it gives: `kdmpm run scenes/slope.ron --set
/// grid.cell_size=2 --set "grid.cells=[90, 23]" --set "bodies[0].points_per_cell=[4, 4]"`:
/// 18 308 steps to t = 50.027 s, surface angle 18.90254° (about φ = 20° in the paper,
/// φ* = 18.9° by Davis for ψ = 0), crest u_x 20.5082 m, max u_x 34.469 m.
#[test]
fn failing_slope_comes_to_rest_at_its_repose_angle() {
    common::on_own_thread(|| {
        let mut sim = scene("slope.ron", &common::COARSE_SLOPE);
        let r = with_simulation!(&mut sim, s => run_and_continue(s));
        pinned("steps", r.steps as f64, 18308.0, 0.01);
        pinned("stop time (s)", r.time, 50.027, 0.01);
        // 0.005° of 19°: a change of 0.5° fails by a hundred times.
        pinned("angle (°)", r.angle, 18.90254, 0.005 / 19.0);
        pinned("crest u_x (m)", r.crest_ux, 20.5082, 5e-4);
        pinned("max u_x (m)", r.max_ux, 34.469, 5e-4);
        assert!(r.moved <= 0.01, "not static: {} m in 10 s", r.moved);
    })
}

/// φ = 35° under a 30° face: it stands, settling 0.17 m at most (on the coarse grid above,
/// `common::COARSE_SLOPE`:
/// `kdmpm run scenes/slope_stable.ron --set …` 4 330 steps, angle 29.7720°, crest u_x
/// 0.05530 m; the shipped 1 m cells: 8 937 steps, 29.7668°, 0.05444 m).
#[test]
fn slope_steeper_friction_than_its_face_stands() {
    common::on_own_thread(|| {
        let mut sim = scene("slope_stable.ron", &common::COARSE_SLOPE);
        let r = with_simulation!(&mut sim, s => run_and_continue(s));
        pinned("steps", r.steps as f64, 4330.0, 0.01);
        pinned("angle (°)", r.angle, 29.77204, 0.005 / 30.0);
        pinned("crest u_x (m)", r.crest_ux, 0.05530, 0.005);
        pinned("max u_x (m)", r.max_ux, 0.1654, 0.005);
        assert!(r.moved <= 0.01, "not static: {} m in 10 s", r.moved);
    })
}

/// The shipped slope.ron's resting state (2 threads or 1: the run is deterministic):
/// `kdmpm run scenes/slope.ron` gives surface angle 18.99398° and crest u_x 22.5158 m.
const REFERENCE_ANGLE: f64 = 18.99398;
const REFERENCE_CREST_UX: f64 = 22.5158;

#[test]
fn the_fast_preset_comes_to_rest_where_the_paper_settings_do() {
    // scenes/slope_fast.ron (USF, Courant 0.8, a 2 s static check): within 0.25° of the surface
    // angle and 3 % of the crest's run-out of slope.ron, the target of the fast preset.
    let s = common::slope_fast();
    assert_eq!(s.outcome, kdmpm::output::Outcome::Converged);
    let angle = s.surface_angle.as_ref().expect("a surface").degrees;
    let crest = s.traced.iter().find(|t| t.name == "crest").unwrap();
    println!(
        "fast preset: {} steps, angle {angle:.3}°, crest u_x {:.3} m",
        s.steps, crest.displacement[0]
    );
    assert!((angle - REFERENCE_ANGLE).abs() <= 0.25, "angle {angle}");
    assert!(
        (crest.displacement[0] / REFERENCE_CREST_UX - 1.0).abs() <= 0.03,
        "crest u_x {}",
        crest.displacement[0]
    );
    // And pinned to what the preset gives: 3 767 steps, 18.93675°, crest u_x 22.5185 m.
    pinned("steps", s.steps as f64, 3767.0, 0.01);
    pinned("angle (°)", angle, 18.93675, 0.005 / 19.0);
    pinned("crest u_x (m)", crest.displacement[0], 22.5185, 5e-4);
}

#[test]
fn the_fast_preset_still_refuses_the_creeping_slope() {
    common::on_own_thread(|| {
        // Without the virtual mass floor, nodes reached only by a point's far tail push that
        // point with its own stress and the failed slope creeps by centimetres a second while
        // K_F and K_E may already meet the tolerance: the static check must refuse to stop.
        // Under the preset itself the creep keeps K_F above the tolerance to the 26 s limit;
        // under MUSL at Courant 1 K_F and K_E are met and a 2 s window closes with centimetres
        // of movement (2.41 cm at 26 s; none has closed at 22 s): either way the run must not
        // stop. (The paper's slope with its 10 s window refuses the same creep, 30 s of
        // simulation: docs/verification.md.)
        for extra in [
            &[][..],
            &["solver.scheme=Musl", "solver.time_step=Courant(1.0)"][..],
        ] {
            let mut set = vec![
                "solver.max_time=26",
                "solver.virtual_mass_floor=0",
                "solver.node_mass_cutoff=1e-9",
            ];
            set.extend_from_slice(extra);
            let mut sim = scene("slope_fast.ron", &set);
            with_simulation!(&mut sim, s => {
                s.run(|_| {}).expect("runs");
                let st = &s.ctx.state;
                assert_eq!(st.stop, Some(StopReason::MaxTime), "{extra:?}");
                if let Some(moved) = st.static_window.movement {
                    assert!(moved > 0.01, "{extra:?}: a window moved only {moved} m");
                } else {
                    assert!(extra.is_empty(), "{extra:?}: no window closed");
                }
            });
        }
    })
}
