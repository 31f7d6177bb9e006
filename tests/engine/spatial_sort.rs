//! The spatial sort puts points back in cell order without changing what they are: every
//! point keeps all its data under its `PointId`, traced points and the static check follow
//! it, and a sorted run ends where an unsorted one does (to round-off: only the order of
//! the sums at the nodes changes).

use glam::{DMat2, DVec2};
use kdmpm::components::*;
use kdmpm::infra::columns::{col, points_with};
use kdmpm::materials::PlasticStrain;
use kdmpm::measure::{max_movement, positions};
use kdmpm::systems::SpatialSort;
use kdmpm::tensor::{PlanarSym3, StoredSym};
use kdmpm::{Dim2, Simulation, StepError, System};
use std::collections::BTreeMap;

use crate::common;

/// The failing bank of `common::bank_on_layer`, all of sand (one archetype).
fn simulation(steps: u64, sort_every: u64) -> Simulation<Dim2> {
    common::bank_on_layer(common::SAND, steps, sort_every, true)
}

/// Everything a point carries, as raw bits, by point id.
type Record = Vec<u64>;

fn records(sim: &Simulation<Dim2>) -> BTreeMap<u32, Record> {
    let mut all = BTreeMap::new();
    for arch in points_with::<PointId>(&sim.ctx.world) {
        let ids = col::<PointId>(arch);
        let x = col::<Position<DVec2>>(arch);
        let v = col::<Velocity<DVec2>>(arch);
        let m = col::<Mass>(arch);
        let u = arch.get::<&Displacement<DVec2>>();
        let l = arch.get::<&VelocityGradient<DMat2>>();
        let s = arch.get::<&Stress<PlanarSym3>>();
        let vol = arch.get::<&Volume>();
        let mat = arch.get::<&MaterialId>();
        let eps = arch.get::<&PlasticStrain>();
        let load = arch.get::<&PointLoad<DVec2>>();
        for p in 0..ids.len() {
            let mut r: Record = Vec::new();
            r.extend(x[p].0.to_array().map(f64::to_bits));
            r.extend(v[p].0.to_array().map(f64::to_bits));
            r.push(m[p].0.to_bits());
            r.extend(u.iter().flat_map(|u| u[p].0.to_array().map(f64::to_bits)));
            r.extend(l.iter().flat_map(|l| l[p].0.to_cols_array().map(f64::to_bits)));
            r.extend(
                s.iter()
                    .flat_map(|s| s[p].0.to_sym3().to_array().map(f64::to_bits)),
            );
            r.extend(vol.iter().map(|vol| vol[p].0.to_bits()));
            r.extend(mat.iter().map(|mat| mat[p].0 as u64));
            r.extend(eps.iter().map(|e| e[p].0.to_bits()));
            r.extend(load.iter().flat_map(|f| f[p].0.to_array().map(f64::to_bits)));
            assert!(all.insert(ids[p].0, r).is_none(), "id {} twice", ids[p].0);
        }
    }
    all
}

/// Cell keys (id of the cell's lowest node) of each archetype's rows, in row order.
fn cell_keys(sim: &Simulation<Dim2>) -> Vec<Vec<usize>> {
    let grid = &sim.ctx.grid;
    points_with::<PointId>(&sim.ctx.world)
        .map(|arch| {
            col::<Position<DVec2>>(arch)
                .iter()
                .map(|x| grid.cell_key(x.0))
                .collect()
        })
        .collect()
}

fn is_sorted(keys: &[usize]) -> bool {
    keys.windows(2).all(|w| w[0] <= w[1])
}

#[test]
fn set_up_leaves_the_points_in_cell_order() {
    // Bodies are filled row of points by row of points, and the layer after the bank.
    let sim = simulation(1, 0);
    assert!(cell_keys(&sim).iter().all(|k| is_sorted(k)));
    let ids: Vec<u32> = points_with::<PointId>(&sim.ctx.world)
        .flat_map(|a| col::<PointId>(a).iter().map(|id| id.0).collect::<Vec<_>>())
        .collect();
    assert!(ids.windows(2).any(|w| w[0] > w[1]), "the sort reordered the fill");
}

#[test]
fn sorting_puts_rows_in_cell_order_and_every_point_keeps_all_its_data() {
    // 400 steps without sorting: the bank fails, so points have crossed cells, and
    // velocities, gradients, stresses and plastic strains are all non-trivial.
    let mut sim = simulation(400, 0);
    sim.run(|_| {}).unwrap();
    assert!(
        cell_keys(&sim).iter().any(|k| !is_sorted(k)),
        "the failing bank should have mixed the points"
    );
    let before = records(&sim);
    assert!(
        before.values().any(|r| r.len() > 12),
        "plastic points carry more data"
    );

    let mut sort = SpatialSort::new(1);
    System::<Dim2>::run(&mut sort, &mut sim.ctx).unwrap();
    assert!(sim.ctx.state.points_reordered);
    assert!(cell_keys(&sim).iter().all(|k| is_sorted(k)), "rows in cell order");
    assert_eq!(records(&sim), before, "every point keeps every bit of its data");

    // Sorting sorted points moves nothing.
    System::<Dim2>::run(&mut sort, &mut sim.ctx).unwrap();
    assert!(!sim.ctx.state.points_reordered);
    assert_eq!(records(&sim), before);
}

#[test]
fn a_run_sorted_every_step_ends_where_an_unsorted_run_does() {
    let mut sorted = simulation(600, 1);
    let mut unsorted = simulation(600, 0);
    sorted.run(|_| {}).unwrap();
    unsorted.run(|_| {}).unwrap();
    assert!(cell_keys(&sorted).iter().all(|k| is_sorted(k)));
    assert!(cell_keys(&unsorted).iter().any(|k| !is_sorted(k)));
    // Only the order in which the points' shares are summed at a node differs, so the two
    // runs agree to round-off amplified over 600 steps of a failing bank.
    let (mut a, mut b) = (Vec::new(), Vec::new());
    positions::<Dim2>(&sorted.ctx.world, &mut a);
    positions::<Dim2>(&unsorted.ctx.world, &mut b);
    let moved = {
        let mut start = Vec::new();
        positions::<Dim2>(&simulation(1, 0).ctx.world, &mut start);
        max_movement(&start, &b)
    };
    assert!(moved > 0.05, "the bank should fail visibly: moved {moved} m");
    let apart = max_movement(&a, &b);
    eprintln!("unsorted run moved up to {moved:.3} m; sorted and unsorted differ by {apart:.2e} m");
    assert!(apart < 1e-9, "positions differ by {apart} m");
    // Traced points follow their points through the sorts.
    for (s, u) in sorted.traced_results().iter().zip(unsorted.traced_results()) {
        assert_eq!(s.name, u.name);
        assert_eq!(s.initial_position, u.initial_position);
        for a in 0..3 {
            let d = (s.displacement[a] - u.displacement[a]).abs();
            assert!(d < 1e-9, "{}: displacement differs by {d} m", s.name);
        }
        assert!((s.stress.yy - u.stress.yy).abs() < 1e-6 * u.stress.yy.abs().max(1.0));
    }
}

/// A user component the sort does not know.
struct Tag;

#[test]
fn a_point_component_added_by_user_code_stops_the_sort_with_a_clear_error() {
    let mut sim = simulation(5, 1);
    let first = sim.traced[0].entity;
    sim.ctx.world.insert_one(first, Tag).unwrap();
    let e = sim.run(|_| {}).unwrap_err();
    assert!(matches!(e, StepError::Unsortable { step: 1 }), "{e:?}");
    assert!(e.to_string().contains("solver.sort_every: 0"), "{e}");
}
