//! A scene pays only for what it uses: no gravity system without gravity, no plastic state
//! on elastic points, no peak watch without kinetic damping, no point-load system without
//! loads, no sort system when sorting is off, no smaller time step for a material no body
//! uses; 2D scenes store 2-vectors and the four stress components of plane strain.

use kdmpm::components::{PointLoad, Position, Stress};
use kdmpm::infra::columns::points_with;
use kdmpm::materials::PlasticStrain;
use kdmpm::scene::{build, LoadedScene};
use kdmpm::tensor::{PlanarSym3, Sym3};
use kdmpm::{AnySimulation, Dim2, Dim3};
use std::path::Path;

fn load(name: &str, overrides: &[&str]) -> AnySimulation {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    build(&LoadedScene::from_file(&path, &o).unwrap()).unwrap().0
}

#[test]
fn elastic_bar_without_gravity_has_no_gravity_system_and_no_plastic_state() {
    let AnySimulation::Three(sim) = load("bar.ron", &[]) else {
        panic!("the bar is 3D")
    };
    let names = sim.schedule.names();
    assert!(!names.contains(&"gravity".to_string()), "{names:?}");
    assert!(names.contains(&"peak_watch".to_string()) && names.contains(&"point_loads".to_string()));
    assert_eq!(points_with::<PlasticStrain>(&sim.ctx.world).count(), 0);
    // Exactly one archetype carries the load, holding exactly one point.
    let loaded: Vec<_> = points_with::<PointLoad<glam::DVec3>>(&sim.ctx.world).collect();
    assert_eq!(loaded.len(), 1);
    assert_eq!(loaded[0].len(), 1);
    assert!(
        loaded[0].get::<&Stress<Sym3>>().is_none(),
        "a load carrier has no stress"
    );
}

#[test]
fn viscous_damping_has_no_peak_watch_and_musl_only_has_a_remap() {
    let AnySimulation::Three(sim) = load("bar_viscous.ron", &[]) else {
        panic!()
    };
    assert!(!sim.schedule.names().contains(&"peak_watch".to_string()));
    let AnySimulation::Three(usl) = load("bar.ron", &["solver.scheme=Usl"]) else {
        panic!()
    };
    assert!(!usl.schedule.names().contains(&"remap".to_string()));
}

#[test]
fn a_scene_that_never_sorts_has_no_sort_system() {
    let AnySimulation::Three(sorted) = load("bar.ron", &[]) else {
        panic!()
    };
    assert!(sorted.schedule.names().contains(&"spatial_sort".to_string()));
    let AnySimulation::Three(never) = load("bar.ron", &["solver.sort_every=0"]) else {
        panic!()
    };
    assert!(!never.schedule.names().contains(&"spatial_sort".to_string()));
}

#[test]
fn plastic_slope_has_plastic_state_on_every_point_and_gravity_but_no_loads() {
    let AnySimulation::Two(sim) = load("slope.ron", &[]) else {
        panic!("the slope is 2D")
    };
    let names = sim.schedule.names();
    assert!(names.contains(&"gravity".to_string()) && !names.contains(&"point_loads".to_string()));
    let stressed: u32 = points_with::<Stress<PlanarSym3>>(&sim.ctx.world)
        .map(|a| a.len())
        .sum();
    let plastic: u32 = points_with::<PlasticStrain>(&sim.ctx.world)
        .map(|a| a.len())
        .sum();
    assert_eq!(stressed, plastic);
    // 2D scenes store two components per vector, and of the stress only xx, yy, zz and xy
    // (plane strain has no out-of-plane shear).
    assert_eq!(points_with::<Stress<Sym3>>(&sim.ctx.world).count(), 0);
    assert_eq!(std::mem::size_of::<Position<<Dim2 as kdmpm::Dim>::Vec>>(), 16);
    assert_eq!(std::mem::size_of::<Position<<Dim3 as kdmpm::Dim>::Vec>>(), 24);
    assert_eq!(std::mem::size_of::<Stress<<Dim2 as kdmpm::Dim>::Stress>>(), 32);
    assert_eq!(std::mem::size_of::<Stress<<Dim3 as kdmpm::Dim>::Stress>>(), 48);
}

#[test]
fn a_run_whose_time_step_is_far_too_large_stops_with_a_located_error() {
    // Bypass validation: triple the bar's critical step after building.
    let AnySimulation::Three(mut sim) = load("bar.ron", &["solver.time_step=Fixed(1.0)"]) else {
        panic!()
    };
    sim.ctx.numerics.dt = 3.0;
    let err = sim
        .run(|_| {})
        .expect_err("an explicit step three times the critical one blows up");
    let msg = err.to_string();
    assert!(msg.starts_with("step "), "{msg}");
    assert!(
        msg.contains("unstable") || msg.contains("left the grid") || msg.contains("non-finite"),
        "{msg}"
    );
}

#[test]
fn displacements_are_kept_only_when_asked_for_and_traced_points_do_without() {
    use kdmpm::components::Displacement;
    use kdmpm::measure::max_displacements;
    let AnySimulation::Three(mut bar) =
        load("bar.ron", &["output.displacements=false", "solver.max_steps=50"])
    else {
        panic!()
    };
    assert_eq!(
        points_with::<Displacement<glam::DVec3>>(&bar.ctx.world).count(),
        0
    );
    bar.run(|_| {}).unwrap();
    assert_eq!(max_displacements(&bar), None);
    let without = bar.traced_results()[0].displacement;
    let AnySimulation::Three(mut kept) = load("bar.ron", &["solver.max_steps=50"]) else {
        panic!()
    };
    kept.run(|_| {}).unwrap();
    let with = kept.traced_results()[0].displacement;
    // Without the column a traced point reports x − x₀, with it the accumulated Σ Δt v: the
    // same displacement up to the positions' rounding (an ulp of 10 m is 1.8e-15 m a step).
    let gap = (0..3).map(|a| (without[a] - with[a]).abs()).fold(0.0, f64::max);
    assert!(with[0] != 0.0 && gap <= 50.0 * 1.8e-15, "{without:?} vs {with:?}");
    let (max_u, _) = max_displacements(&kept).expect("kept by default");
    assert!(max_u >= with[0].abs());
}

/// Where each point was when a static check's window opened is a point column, carried
/// only by the points of a scene with a `static_check`.
#[test]
fn only_a_scene_with_a_static_check_keeps_where_its_points_were() {
    use kdmpm::components::WindowStart;
    let count = |sim: &AnySimulation| match sim {
        AnySimulation::Two(s) => points_with::<WindowStart<glam::DVec2>>(&s.ctx.world)
            .map(|a| a.len() as usize)
            .sum::<usize>(),
        _ => panic!("a plane-strain slope"),
    };
    let with = load("slope_fast.ron", &[]);
    let without = load("slope_fast.ron", &["solver.static_check=None"]);
    let points = match &with {
        AnySimulation::Two(s) => s.point_count(),
        _ => panic!(),
    };
    assert_eq!((count(&with), count(&without)), (points, 0));
}

#[test]
fn a_material_no_body_uses_does_not_set_the_time_step() {
    // The bar (E = 1, ρ = 1, ν = 0: c_p = 1 m/s) with a rock 100 times stiffer (c_p = 10 m/s)
    // defined beside it.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/bar.ron");
    let text = std::fs::read_to_string(&path).unwrap().replace(
        r#""bar": LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0),"#,
        r#""bar": LinearElastic(density: 1.0, youngs_modulus: 1.0, poisson_ratio: 0.0),
        "rock": LinearElastic(density: 1.0, youngs_modulus: 100.0, poisson_ratio: 0.0),"#,
    );
    assert!(
        text.contains("\"rock\""),
        "the bar scene changed: update this test"
    );
    let derived = |text: &str| {
        let courant = ["solver.time_step=Courant(0.5)".to_string()];
        build(&LoadedScene::from_text(&path, text, &courant).unwrap())
            .unwrap()
            .1
    };
    let unused = derived(&text);
    assert_eq!(unused.p_wave_speed, 1.0);
    assert_eq!(unused.time_step, 0.5);
    assert_eq!(unused.unused_materials, ["rock"]);
    // Once a body is made of rock, rock sets the step.
    let used = derived(&text.replace(r#"(material: "bar""#, r#"(material: "rock""#));
    assert_eq!(used.p_wave_speed, 10.0);
    assert_eq!(used.time_step, 0.05);
    assert_eq!(used.unused_materials, ["bar"]);
}
