//! `points.vtu` holds every material point once, in id order, with the values the columns
//! hold: read back, each number is the column's to the last bit.

use glam::DVec2;
use kdmpm::components::*;
use kdmpm::infra::columns::{col, points_with};
use kdmpm::materials::PlasticStrain;
use kdmpm::output::vtk::write_points;
use kdmpm::tensor::{PlanarSym3, StoredSym};
use kdmpm::{Dim2, Simulation};
use std::collections::BTreeMap;
use std::path::Path;

use crate::common;

/// The failing bank of `common::bank_on_layer` on an elastic layer (two archetypes, the bank
/// with plastic strain, and a load carrier, which is not a material point), run 300 steps
/// with a sort every 10, so that storage order and id order differ.
fn simulation(displacements: bool) -> Simulation<Dim2> {
    let mut sim = common::bank_on_layer(common::ROCK, 300, 10, displacements);
    sim.run(|_| {}).expect("runs");
    sim
}

/// The numbers of every `DataArray` of a `.vtu` file, by name (`Points` for the positions).
fn read_arrays(path: &Path) -> BTreeMap<String, Vec<f64>> {
    common::read_vtu(path)
        .into_iter()
        .map(|(name, (_, values))| (name, values))
        .collect()
}

/// What the columns hold for every material point, by id: position, displacement,
/// stress, volume, plastic strain (0 for bodies without plastic state).
type Expected = BTreeMap<u32, (DVec2, Option<DVec2>, [f64; 6], f64, f64)>;

fn expected(sim: &Simulation<Dim2>) -> Expected {
    let mut all = Expected::new();
    for arch in points_with::<Stress<PlanarSym3>>(&sim.ctx.world) {
        let (ids, x, s, v) = (
            col::<PointId>(arch),
            col::<Position<DVec2>>(arch),
            col::<Stress<PlanarSym3>>(arch),
            col::<Volume>(arch),
        );
        let u = arch.get::<&Displacement<DVec2>>();
        let eps = arch.get::<&PlasticStrain>();
        for p in 0..ids.len() {
            let s = s[p].0.to_sym3();
            let row = (
                x[p].0,
                u.as_ref().map(|u| u[p].0),
                [s.xx, s.yy, s.zz, s.xy, s.yz, s.zx],
                v[p].0,
                eps.as_ref().map_or(0.0, |e| e[p].0),
            );
            assert!(all.insert(ids[p].0, row).is_none());
        }
    }
    all
}

fn path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

#[test]
fn points_vtu_holds_every_material_point_in_id_order_with_its_column_values() {
    let sim = simulation(true);
    let stored: Vec<u32> = points_with::<Stress<PlanarSym3>>(&sim.ctx.world)
        .flat_map(|a| col::<PointId>(a).iter().map(|id| id.0).collect::<Vec<_>>())
        .collect();
    assert!(
        stored.windows(2).any(|w| w[0] > w[1]),
        "storage order should differ from id order, or the test shows nothing"
    );
    let file = path("points_kept.vtu");
    write_points(&sim, &file).unwrap();
    let arrays = read_arrays(&file);
    let want = expected(&sim);
    let n = want.len();
    assert!(
        String::from_utf8_lossy(&std::fs::read(&file).unwrap()).contains(&format!("NumberOfPoints=\"{n}\""))
    );

    let ids: Vec<u32> = arrays["id"].iter().map(|&id| id as u32).collect();
    assert_eq!(ids, want.keys().copied().collect::<Vec<_>>(), "ids, ascending");
    assert!(
        want.values().any(|w| w.4 > 0.0),
        "the bank should have yielded somewhere"
    );
    for (k, (x, u, s, v, e)) in want.values().enumerate() {
        assert_eq!(
            arrays["Points"][3 * k..3 * k + 3],
            [x.x, x.y, 0.0],
            "position {k}"
        );
        let u = u.expect("kept");
        assert_eq!(arrays["displacement"][3 * k..3 * k + 3], [u.x, u.y, 0.0]);
        assert_eq!(arrays["stress"][6 * k..6 * k + 6], *s);
        assert_eq!(arrays["mean_stress"][k], (s[0] + s[1] + s[2]) / 3.0);
        assert_eq!(arrays["volume"][k], *v);
        assert_eq!(arrays["plastic_strain"][k], *e);
    }
    // One vertex cell per point.
    assert_eq!(arrays["connectivity"].len(), n);
    assert_eq!(arrays["offsets"].last().copied(), Some(n as f64));
    assert!(arrays["types"].iter().all(|&t| t == 1.0));
}

#[test]
fn points_vtu_has_no_displacement_field_when_the_scene_keeps_none() {
    let sim = simulation(false);
    let file = path("points_not_kept.vtu");
    write_points(&sim, &file).unwrap();
    let arrays = read_arrays(&file);
    assert!(!arrays.contains_key("displacement"));
    assert_eq!(arrays["volume"].len(), expected(&sim).len());
}
