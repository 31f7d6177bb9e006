//! A rank's part of a scene (`scene::build_part`): each rank spawns only the points of its
//! own cell layers, and the parts of every rank together are the one-rank build, point for
//! point: ids, places, masses, volumes, stresses and the loads tractions and point loads
//! put on them, with the same traced points, pressures and split on every rank. No MPI is
//! needed: the parts are built side by side in one process.

use crate::common;

use kdmpm::components::{Mass, PointId, PointLoad, Position, Stress, Volume};
use kdmpm::scene::{build, build_part, LoadedScene, RankPart};
use kdmpm::tensor::StoredSym;
use kdmpm::with_simulation;
use kdmpm::Dim;
use kdmpm::Simulation;

/// One point as bits: id, place, mass, volume, the stress's xx and yy, and its load.
type Row = (u32, [u64; 3], u64, u64, [u64; 2], Option<[u64; 3]>);

fn rows<D: Dim>(sim: &Simulation<D>) -> Vec<Row> {
    let bits = |v: D::Vec| D::vec_to3(v).map(f64::to_bits);
    let mut rows: Vec<Row> = sim
        .ctx
        .world
        .query::<(
            &PointId,
            &Position<D::Vec>,
            &Mass,
            Option<&Volume>,
            Option<&Stress<D::Stress>>,
            Option<&PointLoad<D::Vec>>,
        )>()
        .iter()
        .map(|(id, x, m, v, s, l)| {
            let s = s.map_or([0.0; 2], |s| {
                let t = s.0.to_sym3();
                [t.xx, t.yy]
            });
            (
                id.0,
                bits(x.0),
                m.0.to_bits(),
                v.map_or(0, |v| v.0.to_bits()),
                s.map(f64::to_bits),
                l.map(|l| bits(l.0)),
            )
        })
        .collect();
    rows.sort();
    rows
}

/// The points a part holds outside its own cells.
fn outside<D: Dim>(sim: &Simulation<D>) -> usize {
    let (grid, d) = (&sim.ctx.grid, &sim.ctx.decomposition);
    sim.ctx
        .world
        .query::<&Position<D::Vec>>()
        .iter()
        .filter(|x| !d.holds(grid.split_cell(x.0)))
        .count()
}

/// What every rank must agree on: the traced points, the pressures' points, the split.
fn shared<D: Dim>(sim: &Simulation<D>) -> String {
    let traced: Vec<_> = sim.traced.iter().map(|t| (t.id, t.initial_position)).collect();
    format!(
        "{traced:?} {:?} {:?}",
        sim.ctx.model.pressures, sim.ctx.model.load_steps
    )
}

/// Builds `scene` whole and as the parts of `ranks` ranks (laid as `split` asks); the parts'
/// points together are the whole's, each part holds the points of its own cells only, and
/// every part agrees on what is global.
fn parts_make_the_whole(scene: &str, sets: &[&str], ranks: usize, split: Option<[usize; 2]>) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_file(&common::scene(scene), &sets).unwrap();
    let (mut whole, derived) = build(&loaded).unwrap();
    let (whole_rows, whole_shared) = with_simulation!(&mut whole, s => (rows(s), shared(s)));
    assert_eq!(whole_rows.len(), derived.points);
    let mut union = Vec::new();
    let mut held = Vec::new();
    for rank in 0..ranks {
        let (mut part, d) = build_part(&loaded, Some(RankPart { ranks, rank, split })).unwrap();
        assert_eq!(
            d.points, derived.points,
            "{scene}: rank {rank} counts every point"
        );
        assert_eq!(d.active_nodes, derived.active_nodes, "{scene}: rank {rank}");
        let (r, sh, outside, laid) =
            with_simulation!(&mut part, s => (rows(s), shared(s), outside(s), s.ctx.decomposition.split()));
        assert_eq!(laid[0] * laid[1], ranks);
        if let Some(asked) = split {
            assert_eq!(laid, asked, "{scene}: laid as asked");
        }
        assert_eq!(
            outside, 0,
            "{scene}: rank {rank} holds points of another rank's layers"
        );
        assert_eq!(
            sh, whole_shared,
            "{scene}: rank {rank} agrees on the global set-up"
        );
        held.push(r.len());
        union.extend(r);
    }
    union.sort();
    assert_eq!(union, whole_rows, "{scene}: the parts are the whole");
    assert!(
        held.iter().filter(|&&n| n > 0).count() >= 2,
        "{scene}: the points are split ({held:?})"
    );
}

#[test]
fn each_ranks_part_of_a_scene_is_the_one_rank_build_cut_to_its_layers() {
    // Tractions in increments and a traced point (plane strain).
    parts_make_the_whole("footing_load.ron", &[], 2, None);
    // A pressure beside a rigid body, an initial pressure, axisymmetry.
    parts_make_the_whole(
        "cpt.ron",
        &[
            "grid.cell_size=0.25",
            "grid.cells=[20, 104]",
            "tractions[0].min=[0.5, 13.75]",
        ],
        4,
        None,
    );
    // Water and traced points.
    parts_make_the_whole("slope_water.ron", &[], 3, None);
    // 3D.
    parts_make_the_whole("block_10k.ron", &[], 2, None);
}

/// Split along a second axis too: 2 × 2 in 3D (slabs along z cut along y) and in plane
/// strain (slabs along y cut along x), each part the whole's points in its own cells.
#[test]
fn each_ranks_part_of_a_two_axis_split_is_the_one_rank_build_cut_to_its_cells() {
    parts_make_the_whole("block_10k.ron", &[], 4, Some([2, 2]));
    parts_make_the_whole("footing_load.ron", &[], 4, Some([2, 2]));
    parts_make_the_whole("slope_water.ron", &[], 6, Some([3, 2]));
}

/// The nearest point to a traced place is the first made among equals, so that every rank
/// names the same one: a traced place at a cell corner is as near four points.
#[test]
fn a_traced_place_equidistant_from_points_names_the_first_of_them_on_every_rank() {
    let loaded = LoadedScene::from_file(
        &common::scene("footing_load.ron"),
        &["traced=[(name: \"corner\", position: [2.0, 2.0])]".to_string()],
    )
    .unwrap();
    let (mut whole, _) = build(&loaded).unwrap();
    let id = with_simulation!(&mut whole, s => s.traced[0].id);
    for rank in 0..2 {
        let (mut part, _) = build_part(
            &loaded,
            Some(RankPart {
                ranks: 2,
                rank,
                split: None,
            }),
        )
        .unwrap();
        assert_eq!(with_simulation!(&mut part, s => s.traced[0].id), id);
    }
    // The four points round (2, 2) at a quarter cell each way; the lowest id is the point
    // below and to the left, made first (rows of points fill from the bottom up).
    let (mut whole, _) = build(&loaded).unwrap();
    let x = with_simulation!(&mut whole, s => s.traced[0].initial_position);
    assert!(x[0] < 2.0 && x[1] < 2.0, "{x:?}");
}
