//! Nothing silently wrong in rigid bodies, meshes, water and axisymmetry: one regression
//! test per class of bad or extreme input that gave a wrong answer, an abort or a
//! non-finite output. Each gives the right answer or is refused naming the field and the
//! rule (exit 2), or stops as a run that went wrong (exit 1).

use crate::common;

use std::path::Path;

/// The text of shipped scene `name` with each `(from, to)` replaced once.
fn edited(name: &str, edits: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(common::scene(name)).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name} holds no `{from}`");
        text = text.replacen(from, to, 1);
    }
    text
}

/// The text of shipped scene `name` with `fields` (RON, one or more lines) put before its
/// `solver`.
fn before_solver(name: &str, fields: &str) -> String {
    edited(
        name,
        &[("    solver: (", &format!("    {fields}\n    solver: ("))],
    )
}

fn assert_refused(text: &str, expect: &[&str]) {
    let e = common::refusal(text);
    for x in expect {
        assert!(e.contains(x), "expected `{x}` in: {e}");
    }
}

const FOOTING: &str = "[[-1.0, 4.0], [1.0, 4.0], [1.0, 4.5], [-1.0, 4.5]]";

/// A body's polygon follows the rule a soil region's does: no two edges cross.
#[test]
fn a_self_crossing_body_polygon_is_refused() {
    let text = edited(
        "footing_rigid.ron",
        &[(FOOTING, "[[-1.0, 4.0], [1.0, 4.5], [1.0, 4.0], [-1.0, 4.6]]")],
    );
    assert_refused(&text, &["rigid_bodies[0].parts[0].geometry.vertices", "cross"]);
}

/// A load of 1e160 N or 1e-170 N keeps its direction: the squares of its entries once
/// overflowed (or vanished) and the body never moved.
#[test]
fn a_huge_or_tiny_body_load_keeps_its_direction() {
    for f in [-1e160, -1e300, -1e-170] {
        let l = kdmpm::rigid::BodyLoad {
            force: vec![0.0, f],
            increments: 1,
            stage: None,
            mass: None,
        };
        assert_eq!(l.direction(), [0.0, -1.0, 0.0], "{f}");
    }
}

/// The smooth footing of footing_rigid.ron pulled 4 cm up off weightless clay: it carries
/// no force at any static state. Once a body that touched nothing never found a static
/// state (K_F 0/0) and the run ended at max_time.
#[test]
fn a_smooth_body_pulled_off_the_soil_carries_nothing() {
    let text = edited(
        "footing_rigid.ron",
        &[
            ("cells: [24, 18]", "cells: [24, 20]"),
            (
                "velocity: [0.0, -0.01], travel: 0.1",
                "velocity: [0.0, 0.01], travel: 0.04",
            ),
        ],
    );
    let s = common::run_text("up.ron", &text);
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.curve.len(), 4);
    assert!(s.curve.iter().all(|c| c.force == [0.0; 3]), "{:?}", s.curve);
}

/// The same strip thinner than the B-splines' reach from both its faces (three cells: 0.4,
/// 0.25 and 0.125 m at h = 0.25 m) pulled 4 cm up off the clay: the nodes inside it and
/// above its top carry the clay beyond its far face, and without reading which face that
/// clay lies against the strip dragged it along (1.7 to 9.6 kN/m, docs/verification.md).
/// It carries nothing at any static state.
#[test]
fn a_strip_thinner_than_the_shapes_reach_pulled_off_the_soil_carries_nothing() {
    for top in ["4.4", "4.25", "4.125"] {
        let text = edited(
            "footing_rigid.ron",
            &[
                ("cells: [24, 18]", "cells: [24, 20]"),
                (
                    "velocity: [0.0, -0.01], travel: 0.1",
                    "velocity: [0.0, 0.01], travel: 0.04",
                ),
                ("[1.0, 4.5], [-1.0, 4.5]", &format!("[1.0, {top}], [-1.0, {top}]")),
            ],
        );
        let s = common::run_text("thin_up.ron", &text);
        assert!(s.converged, "top {top}: {:?}", s.error);
        assert_eq!(s.curve.len(), 4, "top {top}");
        assert!(
            s.curve.iter().all(|c| c.force == [0.0; 3]),
            "top {top}: {:?}",
            s.curve
        );
    }
}

/// A smooth wall a cell thick (0.2 m at h = 0.2 m) moved 4 cm away from weightless c–φ soil
/// (c = 10 kPa, φ = 30°, only in front of it), which stands unsupported: it carries
/// nothing. Its back face's samples and the nodes inside it reach the soil in front, and
/// pulled on it with −2.7 to −2.8 kN/m while they held it.
#[test]
fn a_wall_a_cell_thick_moved_away_from_soil_that_stands_unsupported_carries_nothing() {
    let s = common::run(
        "passive_wall_cphi.ron",
        &[
            "grid.cell_size=0.2",
            "grid.cells=[65, 25]",
            r#"bodies=[(material: "soil", region: Box(min: [0.0, 0.0], max: [10.0, 4.0]), points_per_cell: [2, 2])]"#,
            r#"rigid_bodies=[(name: "wall", parts: [(name: "face", geometry: Polygon(vertices: [[-0.2, 2.0], [0.0, 2.0], [0.0, 4.6], [-0.2, 4.6]]))], interface: Smooth, motion: (velocity: [-0.01, 0.0], travel: 0.04, increment: 0.01), area: 2.0)]"#,
        ],
    );
    assert!(s.converged, "{:?}", s.error);
    assert_eq!(s.curve.len(), 4);
    assert!(s.curve.iter().all(|c| c.force == [0.0; 3]), "{:?}", s.curve);
}

/// A scene whose only rigid body holds its place applies no load: refused as such rather
/// than run to max_steps with K_F undefined.
#[test]
fn a_scene_whose_only_body_holds_its_place_is_refused() {
    let text = edited(
        "footing_rigid.ron",
        &[(
            "            motion: (velocity: [0.0, -0.01], travel: 0.1, increment: 0.01),\n",
            "",
        )],
    );
    assert_refused(&text, &["applies no load", "driven rigid body"]);
}

/// Two bodies apart at the start whose travels cross are refused: bodies meet the soil,
/// not each other.
#[test]
fn bodies_whose_paths_cross_are_refused() {
    let text = edited(
        "footing_rigid.ron",
        &[(
            "            area: 1.0,\n        ),",
            "            area: 1.0,\n        ),\n        (name: \"plate\", parts: [(name: \"p\", geometry: Polygon(vertices: \
             [[2.0, 3.95], [3.0, 3.95], [3.0, 4.3], [2.0, 4.3]]))], motion: (velocity: [-0.1, 0.0], travel: 1.5)),",
        )],
    );
    assert_refused(&text, &["rigid_bodies[1].motion", "path crosses rigid_bodies[0]"]);
}

/// A circle of radius 1e9 m as a base, and a polygon 2e9 m wide: only what the grid can
/// reach is sampled (once 1.4 TB and 3.7 GB), and both carry the block on them as a flat
/// base does: the same weight, to 1 %.
#[test]
fn a_base_far_larger_than_the_grid_is_sampled_where_the_grid_reaches() {
    let scene = |geometry: &str| {
        format!(
            r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: 0.25, cells: [24, 18]),
    shape: QuadraticBSpline,
    materials: {{"clay": MohrCoulomb(density: 2000.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3, cohesion: 10.0e3, friction_angle: 0.0)}},
    bodies: [(material: "clay", region: Box(min: [0.0, 0.5], max: [6.0, 4.0]), points_per_cell: [2, 2])],
    boundaries: [(face: XMin, condition: Roller), (face: XMax, condition: Roller)],
    gravity: (acceleration: [0.0, -9.81]),
    rigid_bodies: [(name: "base", parts: [(name: "base", geometry: {geometry})])],
    solver: (damping: Kinetic, time_step: Courant(0.5), tolerance: 0.01, max_time: 20.0),
)"#
        )
    };
    let flat = common::run_text(
        "flat.ron",
        &scene("Polygon(vertices: [[-1.0, 0.0], [7.0, 0.0], [7.0, 0.5], [-1.0, 0.5]])"),
    );
    let held = flat.curve[0].force[1];
    for g in [
        "Circle(centre: [3.0, -999999999.5], radius: 1.0e9)",
        "Polygon(vertices: [[-1.0e9, 0.0], [1.0e9, 0.0], [1.0e9, 0.5], [-1.0e9, 0.5]])",
    ] {
        let s = common::run_text("huge.ron", &scene(g));
        assert!(s.converged, "{g}: {:?}", s.error);
        let f = s.curve[0].force[1];
        assert!(common::rel(f, held).abs() < 1e-2, "{g}: {f} N/m against {held}");
    }
}

/// The STL of a box `lo`..`hi` (ASCII), its first line `header`, each coordinate written by
/// `write`.
fn box_stl(lo: [f64; 3], hi: [f64; 3], header: &str, write: impl Fn(f64) -> String) -> String {
    common::stl(header, &kdmpm::rigid::mesh::box_triangles(lo, hi), write)
}

/// A footing in 3D on a block of clay, its part `Mesh(file: "FILE")`.
const MESH_FOOTING: &str = r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: 0.25, cells: [8, 8, 6]),
    shape: QuadraticBSpline,
    materials: {"clay": MohrCoulomb(density: 2000.0, youngs_modulus: 10.0e6, poisson_ratio: 0.3, cohesion: 10.0e3, friction_angle: 0.0)},
    bodies: [(material: "clay", region: Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 1.0]), points_per_cell: [2, 2, 2])],
    boundaries: [(face: ZMin, condition: Fixed)],
    rigid_bodies: [(name: "footing", parts: [(name: "base", geometry: Mesh(file: "FILE"))],
        motion: (velocity: [0.0, 0.0, -0.01], travel: 0.02))],
    solver: (damping: Kinetic, time_step: Courant(0.5), tolerance: 0.01, max_time: 20.0),
)"#;

/// The footing of [`MESH_FOOTING`] on the mesh `file`, its scene written into `dir` and
/// checked: the error, if any.
fn footing_on(dir: &Path, file: &str) -> Result<(), String> {
    let path = dir.join("scene.ron");
    std::fs::write(&path, MESH_FOOTING.replace("FILE", file)).unwrap();
    kdmpm::scene::LoadedScene::from_file(&path, &[])
        .and_then(|l| kdmpm::scene::build(&l).map(|_| ()))
        .map_err(|e| e.to_string())
}

/// The footing on `body.stl` of STL text `stl` (scratch case `name`), checked.
fn mesh_check(name: &str, stl: &str) -> Result<(), String> {
    let dir = common::scratch("robustness_bodies", name);
    std::fs::write(dir.join("body.stl"), stl).unwrap();
    footing_on(&dir, "body.stl")
}

/// Meshes as CAD tools export them load: an ASCII file whose first line is a bare
/// `solid`, a corner written `-0` once (welded with `0`), a face split with a 5e-8 m²
/// sliver. Each was once "not a closed surface" or "not an STL file".
#[test]
fn stl_meshes_as_cad_tools_write_them_load() {
    let plain = |x: f64| format!("{x:?}");
    mesh_check(
        "bare",
        &box_stl([0.5, 0.5, 1.0], [1.5, 1.5, 1.25], "solid", plain),
    )
    .unwrap();
    let negative_zero = |x: f64| if x == 0.0 { "-0.0".into() } else { format!("{x:?}") };
    mesh_check(
        "zero",
        &box_stl([0.0, 0.5, 1.0], [1.0, 1.5, 1.25], "solid cube", negative_zero),
    )
    .unwrap();
    // The top face's diagonal carries a third corner 1e-7 m off it: a sliver of 5e-8 m².
    let mut t = kdmpm::rigid::mesh::box_triangles([0.5, 0.5, 1.0], [1.5, 1.5, 1.25]);
    let top: Vec<[[f64; 3]; 3]> = t.drain(2..4).collect();
    let (a, b, c, d) = (top[0][0], top[0][1], top[0][2], top[1][2]);
    let m = [0.5 * (a[0] + c[0]) - 0.5e-7, 0.5 * (a[1] + c[1]) + 0.5e-7, a[2]];
    t.extend([[a, b, c], [a, m, d], [m, c, d], [a, c, m]]);
    let stl = common::stl("solid sliver", &t, |x| format!("{x:?}"));
    mesh_check("sliver", &stl).unwrap();
}

/// Two closed shells that overlap in one file are refused (they bore 4 % more than their
/// union and left points inside the body); so are a device and a file that is not STL.
#[test]
fn overlapping_shells_a_device_or_a_file_that_is_no_stl_are_refused() {
    let plain = |x: f64| format!("{x:?}");
    let two = box_stl([0.5, 0.5, 1.0], [1.25, 1.5, 1.25], "solid a", plain).replace("endsolid\n", "")
        + &box_stl([0.75, 0.5, 1.0], [1.5, 1.5, 1.25], "", plain);
    let e = mesh_check("overlap", &two).unwrap_err();
    assert!(
        e.contains("geometry.file") && e.contains("cross or one holds the other"),
        "{e}"
    );
    let e = mesh_check("garbage", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n").unwrap_err();
    assert!(e.contains("not an STL file"), "{e}");
    if Path::new("/dev/zero").exists() {
        let dir = common::scratch("robustness_bodies", "device");
        let e = footing_on(&dir, "/dev/zero").unwrap_err();
        assert!(e.contains("not a regular file"), "{e}");
    }
}

/// Under a water table a stage's gravity keeps to the water's axis, and an axisymmetric
/// scene's to the axis; a stage's dry density stays below the saturated one; a table so
/// high its pore pressure is not a number is refused; the water's maps take each name
/// once.
#[test]
fn water_and_axisymmetric_inputs_the_engine_cannot_mean_are_refused() {
    let staged = |stage: &str| {
        before_solver(
            "slope_water.ron",
            &format!("stages: [(name: \"a\"), (name: \"b\", {stage})],"),
        )
    };
    assert_refused(
        &staged("gravity: (acceleration: [-9.81, 0.0])"),
        &["stages[1].gravity.acceleration", "down axis 1"],
    );
    let soil = "MohrCoulomb(density: 2500.0, youngs_modulus: 20.0e6, poisson_ratio: 0.3, cohesion: 10.0e3, friction_angle: 20.0)";
    assert_refused(
        &staged(&format!("materials: {{\"soil\": {soil}}}")),
        &["stages[1].materials.soil.density", "saturated density"],
    );
    let line = "table: Polyline([[0.0, 0.0], [15.0, 0.0], [35.0, 6.0], [55.0, 9.0]])";
    let high = edited("slope_water.ron", &[(line, "table: Level(1e306)")]);
    assert_refused(&high, &["water.table", "1e15"]);
    let twice = edited(
        "slope_water.ron",
        &[(
            "saturated_density: {\"soil\": 2038.74}",
            "saturated_density: {\"soil\": 2038.74, \"soil\": 3000.0}",
        )],
    );
    let e = kdmpm::scene::LoadedScene::from_text(Path::new("twice.ron"), &twice, &[])
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("\"soil\" is given twice"), "{e}");
    let axi = before_solver(
        "footing_circular.ron",
        "gravity: (acceleration: [0.0, 0.0]),\n    stages: [(name: \"a\"), (name: \"b\", gravity: (acceleration: [1.0, -9.81]))],",
    );
    assert_refused(&axi, &["stages[1].gravity.acceleration", "x entry must be 0"]);
}

/// A centrifuge stage doubles gravity and with it γ_w: a saturated column under a table at
/// its top settles twice as far as under normal gravity, as its buoyant weight doubles.
/// Once γ_w stayed 9 810 N/m³ and the settlement was 3 times, not twice.
#[test]
fn the_waters_unit_weight_follows_a_stages_gravity() {
    let column = |g: f64| {
        let text = before_solver(
            "soil_column.ron",
            &format!(
                "water: (table: Level(10.0), saturated_density: {{\"soil\": 2000.0}}),\n    stages: [(name: \"g\", gravity: (acceleration: [0.0, {g}]))],"
            ),
        );
        let s = common::run_text("wet.ron", &text);
        assert!(s.converged, "{:?}", s.error);
        -s.traced[1].displacement[1]
    };
    let (one, two) = (column(-9.81), column(-19.62));
    assert!(
        common::rel(two, 2.0 * one).abs() < 0.01,
        "{one} m at 1 g, {two} m at 2 g"
    );
}

/// In an axisymmetric scene a motion may not drive nodes on the axis along r (it would
/// override the axis's roller), and a traction on the axis face, which has no area, is
/// refused.
#[test]
fn a_radial_drive_or_a_traction_on_the_axis_is_refused() {
    let radial = edited(
        "footing_circular.ron",
        &[(
            "velocity: [None, Some(-0.01)]",
            "velocity: [Some(0.01), Some(-0.01)]",
        )],
    );
    assert_refused(&radial, &["motions[0].velocity", "on the axis"]);
    let traction = before_solver(
        "footing_circular.ron",
        "tractions: [(name: \"axis\", surface: XMin, min: [0.0, 0.0], max: [0.1, 4.0], traction: [1.0e3, 0.0])],",
    );
    assert_refused(&traction, &["tractions[0].surface", "on the axis"]);
}
