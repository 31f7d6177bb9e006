//! A 3D slab between rollers on both z faces is plane strain: it must move exactly as the
//! 2D scene does. The z-face node layers gather half the mass of the middle layer, so every
//! mass threshold (node cut-off, virtual mass floor) has to scale with the node's share of a
//! cell, or the light surface nodes of the slab are treated differently from 2D's.

use kdmpm::scene::{build, LoadedScene};
use kdmpm::with_simulation;
use std::path::Path;

/// A small cohesionless slope (8 m high, 30° face, φ = 20°) that fails under gravity.
fn small_slope(dimension: usize) -> kdmpm::AnySimulation {
    let (cells, z, ppc, rollers, g) = if dimension == 2 {
        ("[34, 10]", "", "[3, 3]", "", "[0.0, -9.81]")
    } else {
        (
            "[34, 10, 2]",
            ", z: [0.0, 2.0]",
            "[3, 3, 1]",
            "(face: ZMin, condition: Roller), (face: ZMax, condition: Roller),",
            "[0.0, -9.81, 0.0]",
        )
    };
    let origin = if dimension == 2 {
        "[0.0, 0.0]"
    } else {
        "[0.0, 0.0, 0.0]"
    };
    let text = format!(
        r#"Scene(
    dimension: {dimension},
    grid: (origin: {origin}, cell_size: 1.0, cells: {cells}),
    shape: QuadraticBSpline,
    materials: {{
        "soil": MohrCoulomb(density: 2000.0, youngs_modulus: 20.0e6, poisson_ratio: 0.4,
            cohesion: 0.0, friction_angle: 20.0, dilatancy_angle: 0.0),
    }},
    bodies: [(material: "soil",
        region: Polygon(vertices: [[0.0, 0.0], [19.86, 0.0], [6.0, 8.0], [0.0, 8.0]]{z}),
        points_per_cell: {ppc})],
    boundaries: [(face: YMin, condition: Fixed), (face: XMin, condition: Roller),
        (face: XMax, condition: Roller), {rollers}],
    gravity: (acceleration: {g}),
    traced: [(name: "crest", position: [5.83, 7.83{crest_z}]), (name: "toe", position: [19.5, 0.17{crest_z}])],
    solver: (damping: Kinetic, time_step: Courant(0.2), max_steps: 2500),
)"#,
        crest_z = if dimension == 2 { "" } else { ", 0.5" },
    );
    let loaded = LoadedScene::from_text(Path::new("small_slope.ron"), &text, &[]).unwrap();
    build(&loaded).unwrap().0
}

/// Traced displacements and K_F (max norm) after every step.
fn run(dimension: usize) -> Vec<[f64; 5]> {
    let mut sim = small_slope(dimension);
    with_simulation!(&mut sim, s => {
        let mut rows = Vec::new();
        while s.ctx.state.stop.is_none() {
            s.step().unwrap();
            let t = s.traced_results();
            let (c, toe) = (t[0].displacement, t[1].displacement);
            rows.push([c[0], c[1], toe[0], toe[1], s.ctx.state.convergence.force_ratio_max]);
        }
        rows
    })
}

#[test]
fn slab_between_z_rollers_moves_as_the_2d_scene() {
    let (two, three) = (run(2), run(3));
    assert_eq!(two.len(), three.len(), "both stop at the same step");
    let crest_moved = two.last().unwrap()[0].abs();
    assert!(crest_moved > 0.1, "the slope fails (crest u_x = {crest_moved} m)");
    for (step, (a, b)) in two.iter().zip(&three).enumerate() {
        for (q, (x, y)) in a.iter().zip(b).enumerate() {
            // Only the summation order differs (two node layers instead of one).
            assert!(
                (x - y).abs() <= 1e-8 * (1.0 + x.abs()),
                "step {step}, quantity {q}: 2D {x} vs 3D {y}"
            );
        }
    }
}
