//! Self-weight under oedometric conditions (rollers on the sides, fixed base), against the
//! analytic static answer: σv = −ρ g d, σh/σv = K0 = ν/(1 − ν), top settlement
//! ρ g H² / (2M) with M = E(1 − ν)/((1 + ν)(1 − 2ν)).
//!
//! With linear shape functions both points of a cell see the same strain, so a point's
//! stress is that of its cell centre: the depth compared is the cell centre's.

use crate::common::{rel, run};

#[test]
fn soil_column_reaches_the_k0_state_and_the_oedometric_settlement() {
    let s = run("soil_column.ron", &[]);
    assert!(s.converged, "{s:?}");
    let (rho, g, e, nu, h, cell) = (1800.0, 9.81, 10e6, 0.3, 10.0, 0.5);
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mid = s.traced.iter().find(|t| t.name == "mid").unwrap();
    let centre = (mid.initial_position[1] / cell).floor() * cell + 0.5 * cell;
    let sv = -rho * g * (h - centre);
    assert!(
        rel(mid.stress.yy, sv).abs() < 0.01,
        "σv = {} vs {sv}",
        mid.stress.yy
    );
    assert!(
        rel(mid.stress.xx / mid.stress.yy, nu / (1.0 - nu)).abs() < 1e-3,
        "K0 = {}",
        mid.stress.xx / mid.stress.yy
    );
    let top = s.traced.iter().find(|t| t.name == "top").unwrap();
    let settlement = -rho * g * h * h / (2.0 * m);
    assert!(
        rel(top.displacement[1], settlement).abs() < 0.005,
        "{} vs {settlement}",
        top.displacement[1]
    );
}

#[test]
fn elastic_block_settles_to_k0_between_rollers_in_3d() {
    // The 10k throughput block (11 m high), run to a static state.
    let s = run(
        "block_10k.ron",
        &[
            "solver.max_steps=20000",
            "solver.tolerance=1e-4",
            "traced=[(name: \"deep\", position: [5.25, 5.25, 2.25])]",
        ],
    );
    assert!(s.converged, "{s:?}");
    let nu = 0.3;
    let deep = &s.traced[0];
    let k0 = deep.stress.xx / deep.stress.zz;
    assert!(rel(k0, nu / (1.0 - nu)).abs() < 0.01, "K0 = {k0}");
    assert!(
        rel(deep.stress.yy, deep.stress.xx).abs() < 1e-6,
        "σxx = σyy by symmetry"
    );
    // Cell centre at z = 2.5 m, 8.5 m below the top.
    let sv = -2000.0 * 9.81 * 8.5;
    assert!(
        rel(deep.stress.zz, sv).abs() < 0.01,
        "σzz = {} vs {sv}",
        deep.stress.zz
    );
}
