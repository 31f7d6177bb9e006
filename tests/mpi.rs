//! Runs over MPI ranks (`cargo test --release --features mpi --test mpi`; needs the
//! system's MPI, see the README). The collectives' tests start this test binary again under
//! `mpirun -n N`, which runs the `ranks_*` body on every rank; the scene tests run
//! `mpirun -n N kdmpm run` and compare what rank 0 writes with a run on one rank.
#![cfg(feature = "mpi")]

mod common;

use kdmpm::infra::comm::Comm;
use kdmpm::infra::decomposition::Decomposition;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Set in the ranks that `mpirun` starts.
const CHILD: &str = "KDMPM_MPI_TEST_CHILD";

/// Runs the test `name` of this binary on `ranks` ranks and checks every rank passed.
fn on_ranks(name: &str, ranks: usize) {
    let exe = std::env::current_exe().expect("the test binary");
    let out = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
        .arg(exe)
        .args([name, "--exact", "--nocapture", "--test-threads", "1"])
        .env(CHILD, "1")
        .output()
        .expect("mpirun starts (install openmpi-bin, see the README)");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.matches("1 passed").count() == ranks,
        "{name} on {ranks} ranks:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn child() -> bool {
    std::env::var_os(CHILD).is_some()
}

/// The collectives on every rank: sums in rank order (the same bits everywhere), the
/// largest value, a NaN that must not hide, `any`, and an exchange with both neighbours.
#[test]
fn ranks_agree_on_sums_maxima_and_exchanges() {
    if !child() {
        for n in [1, 2, 4] {
            on_ranks("ranks_agree_on_sums_maxima_and_exchanges", n);
        }
        return;
    }
    let comm = Comm::world().expect("MPI starts");
    let (r, n) = (comm.rank(), comm.size());
    // Values whose sum depends on the order of the additions.
    let mine = [
        1e16 * (r % 2) as f64 - 1e16 * ((r + 1) % 2) as f64 + r as f64,
        0.1 * (r + 1) as f64,
    ];
    let mut sum = mine;
    comm.sum(&mut sum);
    let all = comm.gather_all(&mine);
    let in_order: Vec<f64> = (0..2)
        .map(|i| (1..n).fold(all[i], |a, q| a + all[q * 2 + i]))
        .collect();
    assert_eq!(
        sum.map(f64::to_bits).to_vec(),
        in_order.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    );
    // Every rank holds the same bits: rank 0's, gathered.
    let everyone = comm.gather_all(&sum);
    assert!(everyone
        .chunks(2)
        .all(|c| c[0].to_bits() == sum[0].to_bits() && c[1].to_bits() == sum[1].to_bits()));
    let mut largest = [r as f64];
    comm.max(&mut largest);
    assert_eq!(largest[0], (n - 1) as f64);
    let mut nan = [if r == n - 1 { f64::NAN } else { 1.0 }];
    comm.max(&mut nan);
    assert!(nan[0].is_nan());
    assert!(comm.any(r == 0));
    assert!(!comm.any(false));
    // The lowest rank's message reaches every rank, whole.
    assert_eq!(comm.first_message(None), None);
    let message = format!("rank {r} says «ü»");
    let from_odd = (r % 2 == 1 || n == 1).then_some(message.as_str());
    let lowest = if n == 1 { 0 } else { 1 };
    assert_eq!(
        comm.first_message(from_odd),
        Some((lowest, format!("rank {lowest} says «ü»")))
    );
    // Up the ranks, then down, messages of the sender's rank + 1 values.
    let up = comm.exchange(
        (r + 1 < n).then_some(r + 1),
        &vec![r as f64; r + 1],
        r.checked_sub(1),
    );
    if r > 0 {
        assert_eq!(up, vec![(r - 1) as f64; r]);
    }
    let down = comm.exchange(
        r.checked_sub(1),
        &vec![r as f64; r + 1],
        (r + 1 < n).then_some(r + 1),
    );
    if r + 1 < n {
        assert_eq!(down, vec![(r + 1) as f64; r + 2]);
    }
}

/// Every rank finds the same decomposition from the same counts.
#[test]
fn ranks_find_the_same_decomposition() {
    if !child() {
        on_ranks("ranks_find_the_same_decomposition", 4);
        return;
    }
    let comm = Comm::world().expect("MPI starts");
    let counts: Vec<u64> = (0..45).map(|c| 180 - 4 * c).collect();
    let d = Decomposition::balanced([&counts, &[1]], [comm.size(), 1], comm.rank(), 3);
    let bounds: Vec<f64> = d.bounds.iter().map(|&b| b as f64).collect();
    let all = comm.gather_all(&bounds);
    assert!(all.chunks(bounds.len()).all(|b| b == &bounds[..]), "{all:?}");
    assert_eq!(d.rank, comm.rank());
}

/// `kdmpm run SCENE` on `ranks` ranks (one thread each) into a scratch directory; its
/// summary.json.
fn run_on(scene: &str, ranks: usize, name: &str, overrides: &[&str]) -> (PathBuf, Value) {
    run_laid(scene, ranks, None, name, overrides)
}

/// [`run_on`] with the ranks laid as `split` asks (`--split SLABSxACROSS`).
fn run_laid(
    scene: &str,
    ranks: usize,
    split: Option<[usize; 2]>,
    name: &str,
    overrides: &[&str],
) -> (PathBuf, Value) {
    let laid = split.map_or(String::new(), |[a, b]| format!("-{a}x{b}"));
    let out = common::scratch("mpi", &format!("{name}-{ranks}{laid}"));
    let path = common::scene(scene);
    let mut cmd = Command::new("mpirun");
    cmd.args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_kdmpm"))
        .args([
            "run",
            path.to_str().expect("UTF-8"),
            "--quiet",
            "--threads",
            "1",
            "--out",
        ])
        .arg(&out);
    for o in overrides {
        cmd.args(["--set", o]);
    }
    if let Some([a, b]) = split {
        cmd.args(["--split", &format!("{a}x{b}")]);
    }
    let o = cmd.output().expect("mpirun starts");
    assert!(
        o.status.success(),
        "{scene} on {ranks} ranks: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    (out, serde_json::from_str(&summary).expect("JSON"))
}

/// Relative difference of two summary numbers.
fn rel(a: &Value, b: &Value) -> f64 {
    let (a, b) = (a.as_f64().expect("a number"), b.as_f64().expect("a number"));
    if a == b {
        return 0.0;
    }
    (a - b).abs() / a.abs().max(b.abs())
}

/// The state figures of a summary that must agree across rank counts.
const STATE: [&str; 6] = [
    "kinetic_energy",
    "external_work",
    "force_ratio_max",
    "force_ratio_mean",
    "energy_ratio",
    "time",
];

/// Same steps and resets as one rank, and every state figure and traced value within
/// `tolerance` of it.
fn agrees(one: &Value, many: &Value, tolerance: f64, what: &str) {
    assert_eq!(one["steps"], many["steps"], "{what}: steps");
    assert_eq!(one["kinetic_resets"], many["kinetic_resets"], "{what}: resets");
    assert_eq!(one["outcome"], many["outcome"], "{what}: outcome");
    assert_eq!(one["particles"], many["particles"], "{what}: points");
    for k in STATE {
        assert!(
            rel(&one[k], &many[k]) <= tolerance,
            "{what}: {k} {} against {}",
            many[k],
            one[k]
        );
    }
    for (a, b) in one["traced"]
        .as_array()
        .unwrap()
        .iter()
        .zip(many["traced"].as_array().unwrap())
    {
        for c in 0..3 {
            let (x, y) = (&a["displacement"][c], &b["displacement"][c]);
            // Below 1e-15 m a displacement is round-off of a zero (the sideways motion of an
            // oedometric column), which the order of additions may flip.
            let noise = x.as_f64().unwrap().abs().max(y.as_f64().unwrap().abs()) < 1e-15;
            assert!(
                noise || rel(x, y) <= tolerance.max(1e-300),
                "{what}: traced {x} against {y}"
            );
        }
    }
}

/// Elastic scenes (the paper's bar, the benchmark block) on 2 and 4 ranks follow one rank
/// step for step: the partial sums of shared nodes and the reductions change only the
/// order of additions.
#[test]
fn the_bar_and_the_block_on_2_and_4_ranks_agree_with_one_rank_to_1e_10() {
    for (scene, name) in [("bar.ron", "bar"), ("block_10k.ron", "block")] {
        let (_, one) = run_on(scene, 1, name, &[]);
        for ranks in [2, 4] {
            let (dir, many) = run_on(scene, ranks, name, &[]);
            agrees(&one, &many, 1e-10, &format!("{name} on {ranks} ranks"));
            assert_eq!(
                one["total_mass"], many["total_mass"],
                "{name} on {ranks} ranks: mass"
            );
            assert!(
                dir.join("points.pvtu").exists() && dir.join(format!("points_{}.vtu", ranks - 1)).exists()
            );
        }
    }
}

/// The fast 3D slope's settings (scenes/slope_fast.ron's three on scenes/slope_3d.ron).
const FAST_3D: [&str; 4] = [
    "solver.scheme=Usf",
    "solver.time_step=Courant(0.8)",
    "solver.static_check=(window: 2.0, max_displacement: 0.01)",
    "output.snapshots=None",
];

/// The fast slope, in 2D and in 3D (two cells thick), fails and runs out across the rank
/// boundaries (points migrate, the split is made again as they pile up at the toe) and
/// stops by itself at the angle one rank finds.
#[test]
fn the_failing_slope_in_2d_and_3d_on_2_and_4_ranks_comes_to_rest_at_the_angle_of_one_rank() {
    for (scene, name, overrides) in [
        ("slope_fast.ron", "slope", &[][..]),
        ("slope_3d.ron", "slope3d", &FAST_3D[..]),
    ] {
        let (_, one) = run_on(scene, 1, name, overrides);
        for ranks in [2, 4] {
            let (_, many) = run_on(scene, ranks, name, overrides);
            let what = format!("{name} on {ranks} ranks");
            assert_eq!(many["outcome"], "converged", "{what}");
            let angle = |s: &Value| s["surface_angle"]["degrees"].as_f64().expect("an angle");
            assert!(
                (angle(&one) - angle(&many)).abs() <= 0.05,
                "{what}: {} against {}",
                angle(&many),
                angle(&one)
            );
            assert_eq!(one["total_mass"], many["total_mass"], "{what}: mass");
            assert!(
                many["ranks"]["migrations"].as_u64().expect("a count") > 0,
                "{what}: no point moved rank"
            );
            let held: u64 = many["ranks"]["points"]
                .as_array()
                .unwrap()
                .iter()
                .map(|p| p.as_u64().unwrap())
                .sum();
            assert_eq!(held, one["particles"].as_u64().unwrap(), "{what}: points");
        }
    }
}

/// Two runs on the same ranks write the same bits.
#[test]
fn two_runs_on_the_same_ranks_give_the_same_bits() {
    let files = |dir: &Path| -> Vec<Vec<u8>> {
        ["history.csv", "points_0.vtu", "points_1.vtu"]
            .iter()
            .map(|f| std::fs::read(dir.join(f)).expect(f))
            .collect()
    };
    let (a, _) = run_on("slope_fast.ron", 2, "again-a", &["solver.max_time=3.0"]);
    let (b, _) = run_on("slope_fast.ron", 2, "again-b", &["solver.max_time=3.0"]);
    assert!(files(&a) == files(&b), "the runs differ");
}

/// The slope with a water table (scenes/slope_water.ron, without the volumetric smoothing
/// that ranks do not sum yet) on 2 and 4 ranks follows one rank step for step: the pore
/// water's load is mapped by each rank from its own points and summed with the rest.
#[test]
fn the_slope_with_a_water_table_on_2_and_4_ranks_agrees_with_one_rank_to_1e_10() {
    let plain = ["solver.anti_locking=Off"];
    let (_, one) = run_on("slope_water.ron", 1, "water", &plain);
    for ranks in [2, 4] {
        let (_, many) = run_on("slope_water.ron", ranks, "water", &plain);
        agrees(&one, &many, 1e-10, &format!("water on {ranks} ranks"));
    }
}

/// The self-weight column turned about its axis (axisymmetric, per radian) on 2 and 4
/// ranks follows one rank step for step.
#[test]
fn an_axisymmetric_column_on_2_and_4_ranks_agrees_with_one_rank_to_1e_10() {
    let axi = ["dimension=Axisymmetric"];
    let (_, one) = run_on("soil_column.ron", 1, "axi", &axi);
    for ranks in [2, 4] {
        let (_, many) = run_on("soil_column.ron", ranks, "axi", &axi);
        agrees(&one, &many, 1e-10, &format!("axisymmetric on {ranks} ranks"));
    }
}

/// The curve of a summary: each static state's step and the force on its body or motion.
fn curve(s: &Value) -> Vec<(u64, [f64; 3])> {
    s["curve"]
        .as_array()
        .expect("a curve")
        .iter()
        .map(|c| {
            let f = &c["force"];
            (
                c["step"].as_u64().expect("a step"),
                std::array::from_fn(|a| f[a].as_f64().expect("a force")),
            )
        })
        .collect()
}

/// The curves of two summaries agree: the same static states at the same steps, every
/// force within `tolerance` of the larger component of its row.
fn curves_agree(one: &Value, many: &Value, tolerance: f64, what: &str) {
    let (a, b) = (curve(one), curve(many));
    assert_eq!(a.len(), b.len(), "{what}: rows");
    assert!(!a.is_empty(), "{what}: no static state");
    for ((sa, fa), (sb, fb)) in a.iter().zip(&b) {
        assert_eq!(sa, sb, "{what}: step of a static state");
        let size = fa.iter().chain(fb).fold(0.0f64, |m, f| m.max(f.abs()));
        for c in 0..3 {
            assert!(
                (fa[c] - fb[c]).abs() <= tolerance * size,
                "{what}: force {fb:?} against {fa:?} at step {sa}"
            );
        }
    }
}

/// The T-bar over its first 0.1 m, in two increments.
const TBAR_SHORT: &str = "rigid_bodies[0].motion=(velocity: [0.0, -0.01], travel: 0.1, increment: 0.05)";

/// The cone over its first quarter diameter, in one increment.
const CONE_FIRST_QUARTER: &str =
    "rigid_bodies[0].motion=(velocity: [0.0, -0.05], travel: 0.25, increment: 0.25)";

/// The penetration problems on 2 and 4 ranks follow one rank step for step: a footing of
/// driven nodes and a rigid one (their reactions summed over the nodes each rank owns), a
/// c–φ footing with the cell means against locking, the T-bar under a confining pressure,
/// the cone's first quarter diameter with its surcharge as a pressure, and a rigid
/// footing and a surface load under load control. Every rank solves the contacts whole,
/// from the nodal values their owners gather, so the curves differ from one rank's only
/// by the order of additions in the shared node layers.
#[test]
fn rigid_bodies_motions_and_loads_on_2_and_4_ranks_agree_with_one_rank_to_1e_10() {
    let cases: [(&str, &str, &[&str]); 7] = [
        ("footing.ron", "footing", &[]),
        ("footing_rigid.ron", "rigid", &[]),
        ("footing_cphi.ron", "cphi", &["motions[0].travel=0.06"]),
        ("tbar.ron", "tbar", &[TBAR_SHORT]),
        ("cpt.ron", "cpt", &[CONE_FIRST_QUARTER]),
        ("footing_rigid_load.ron", "rigid-load", &[]),
        ("footing_load.ron", "load", &[]),
    ];
    for (scene, name, overrides) in cases {
        let (_, one) = run_on(scene, 1, name, overrides);
        for ranks in [2, 4] {
            let (_, many) = run_on(scene, ranks, name, overrides);
            let what = format!("{name} on {ranks} ranks");
            agrees(&one, &many, 1e-10, &what);
            curves_agree(&one, &many, 1e-10, &what);
            let bodies = |s: &Value| s["rigid_bodies"].as_array().cloned().unwrap_or_default();
            for (a, b) in bodies(&one).iter().zip(&bodies(&many)) {
                assert_eq!(a["entries"], b["entries"], "{what}: points put back out");
                assert!(rel(&a["travel"], &b["travel"]) <= 1e-10, "{what}: travel");
            }
        }
    }
}

/// The cone's first quarter diameter with its tip rough on 2 ranks: the clay's strength
/// beside each sample is summed over every rank's points (one strength, so exactly the
/// one rank's), but where a sample sticks or slips turns on the last bits of the nodal
/// sums, whose order of additions the shared node layers change: the kinetic energy at
/// the end differs in its fourth figure, and the tip's force is held to 1e-3 of one
/// rank's, where a smooth cone agrees to 1e-10 (above).
#[test]
fn a_rough_cone_tip_on_2_ranks_bears_as_on_one_to_1e_3() {
    let rough = [
        "rigid_bodies[0].motion=(velocity: [0.0, -0.05], travel: 0.25, increment: 0.25)",
        "rigid_bodies[0].parts[0].interface=Some(Rough)",
    ];
    let (_, one) = run_on("cpt.ron", 1, "rough-cone", &rough);
    let (_, two) = run_on("cpt.ron", 2, "rough-cone", &rough);
    assert_eq!(one["outcome"], two["outcome"]);
    let (a, b) = (curve(&one), curve(&two));
    assert_eq!(a.len(), b.len());
    for ((_, fa), (_, fb)) in a.iter().zip(&b) {
        assert!(
            (fa[1] - fb[1]).abs() <= 1e-3 * fa[1].abs(),
            "{fb:?} against {fa:?}"
        );
    }
}

/// The staged slope on 2 and 4 ranks: its geostatic stage ends where one rank's does, to
/// 1e-10; the second stage turns the soil to Mohr–Coulomb and lets the slope fail, a flow
/// that grows the round-off of another order of additions, and ends at one rank's step.
#[test]
fn the_staged_slope_on_2_and_4_ranks_passes_its_stages_where_one_rank_does() {
    let (_, one) = run_on("slope_staged.ron", 1, "staged", &[]);
    let stages = |s: &Value| s["stages"].as_array().expect("stages").clone();
    for ranks in [2, 4] {
        let (_, many) = run_on("slope_staged.ron", ranks, "staged", &[]);
        let what = format!("staged on {ranks} ranks");
        assert_eq!(one["steps"], many["steps"], "{what}: steps");
        let (a, b) = (stages(&one), stages(&many));
        assert_eq!(a.len(), 2, "{what}: stages");
        assert_eq!(a.len(), b.len(), "{what}: stages");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x["step"], y["step"], "{what}: a stage's last step");
        }
        for k in ["force_ratio", "energy_ratio"] {
            assert!(rel(&a[0][k], &b[0][k]) <= 1e-10, "{what}: geostatic {k}");
        }
    }
}

/// `kdmpm fos` on `ranks` ranks (one thread each): its summary.json.
fn fos_on(scene: &str, ranks: usize) -> Value {
    let out = common::scratch("mpi", &format!("fos-{ranks}"));
    let o = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_kdmpm"))
        .args([
            "fos",
            common::scene(scene).to_str().expect("UTF-8"),
            "--quiet",
            "--threads",
            "1",
            "--out",
        ])
        .arg(&out)
        .output()
        .expect("mpirun starts");
    assert!(
        o.status.success(),
        "fos on {ranks} ranks: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&summary).expect("JSON")
}

/// The factor of safety on 2 ranks: the ranks run every trial together and bisect alike,
/// to one rank's factor, bracket and trials (each trial's outcome and steps).
#[test]
fn the_factor_of_safety_on_2_ranks_is_one_ranks() {
    let (one, two) = (fos_on("slope_fos.ron", 1), fos_on("slope_fos.ron", 2));
    assert_eq!(one["factor_of_safety"], two["factor_of_safety"]);
    assert_eq!(one["bracket"], two["bracket"]);
    let trials = |s: &Value| -> Vec<(Value, Value, Value)> {
        s["trials"]
            .as_array()
            .expect("trials")
            .iter()
            .map(|t| (t["factor"].clone(), t["outcome"].clone(), t["steps"].clone()))
            .collect()
    };
    assert_eq!(trials(&one), trials(&two));
}

/// Snapshots on 2 ranks: the collection lists one rank's snapshots, each a `.pvtu` of the
/// two ranks' pieces, which hold every point once at one rank's displacement (to 1e-10 of
/// the largest).
#[test]
fn snapshots_on_2_ranks_hold_every_point_once_as_one_rank_does() {
    let snapshots = ["output.snapshots=(every_steps: 1000)"];
    let (a, one) = run_on("footing_rigid.ron", 1, "snap", &snapshots);
    let (b, two) = run_on("footing_rigid.ron", 2, "snap", &snapshots);
    assert_eq!(one["snapshots"], two["snapshots"]);
    // The displacement field is drawn from the ranks' pieces of the final points.
    assert!(
        b.join("displacement_field.svg").exists(),
        "no displacement field drawn"
    );
    let pvd = std::fs::read_to_string(b.join("points.pvd")).expect("points.pvd");
    let step = "000005000";
    assert!(pvd.contains(&format!("snapshots/points_{step}.pvtu")), "{pvd}");
    let pvtu = std::fs::read_to_string(b.join(format!("snapshots/points_{step}.pvtu"))).expect("pvtu");
    let pieces: Vec<PathBuf> = (0..2)
        .map(|r| format!("points_{step}_{r}.vtu"))
        .inspect(|p| assert!(pvtu.contains(&format!("Source=\"{p}\"")), "{pvtu}"))
        .map(|p| b.join("snapshots").join(p))
        .collect();
    // Displacements by point id.
    let by_id = |files: &[PathBuf]| -> std::collections::BTreeMap<u64, [f64; 3]> {
        let mut m = std::collections::BTreeMap::new();
        for f in files {
            let v = common::read_vtu(f);
            let (ids, u) = (&v["id"].1, &v["displacement"].1);
            for (k, id) in ids.iter().enumerate() {
                assert!(
                    m.insert(*id as u64, [u[3 * k], u[3 * k + 1], u[3 * k + 2]])
                        .is_none(),
                    "point {id} twice"
                );
            }
        }
        m
    };
    let whole = by_id(&[a.join(format!("snapshots/points_{step}.vtu"))]);
    let split = by_id(&pieces);
    assert_eq!(whole.len(), split.len());
    let largest = whole.values().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    for (id, u) in &whole {
        let v = split[id];
        assert!(
            (0..3).all(|c| (u[c] - v[c]).abs() <= 1e-10 * largest),
            "point {id}: {v:?} against {u:?}"
        );
    }
}

/// Four ranks laid 2 × 2 (slabs cut once more across, so four ranks meet at the corners of
/// their cells): the 3D block, a rigid footing and the T-bar whose bodies span the cut
/// across, the cone about its axis (the cut across is in r), the c–φ footing's cell means
/// and the slope with its water follow one rank step for step, as the slabs do.
#[test]
fn ranks_split_2_by_2_agree_with_one_rank_to_1e_10() {
    let cases: [(&str, &str, &[&str]); 6] = [
        ("block_10k.ron", "block", &[]),
        ("footing_rigid.ron", "rigid", &[]),
        ("tbar.ron", "tbar", &[TBAR_SHORT]),
        ("cpt.ron", "cpt", &[CONE_FIRST_QUARTER]),
        ("footing_cphi.ron", "cphi", &["motions[0].travel=0.06"]),
        ("slope_water.ron", "water", &["solver.anti_locking=Off"]),
    ];
    for (scene, name, overrides) in cases {
        let (_, one) = run_on(scene, 1, name, overrides);
        let (_, many) = run_laid(scene, 4, Some([2, 2]), name, overrides);
        let what = format!("{name} on 2 × 2 ranks");
        agrees(&one, &many, 1e-10, &what);
        if one["curve"].is_array() {
            curves_agree(&one, &many, 1e-10, &what);
        }
        assert_eq!(many["ranks"]["split"], serde_json::json!([2, 2]), "{what}");
        let points = many["ranks"]["points"].as_array().unwrap();
        assert!(
            points.iter().all(|p| p.as_u64().unwrap() > 0),
            "{what}: every rank holds points ({points:?})"
        );
        // Each rank holds the nodes its points reach, not the grid's.
        let (nodes, all) = (
            &many["ranks"]["nodes"],
            many["ranks"]["grid_nodes"].as_u64().unwrap(),
        );
        let held: Vec<u64> = nodes
            .as_array()
            .unwrap()
            .iter()
            .map(|n| n.as_u64().unwrap())
            .collect();
        assert!(
            held.iter().all(|&n| n < all) && held.iter().sum::<u64>() > all,
            "{what}: nodes {held:?} of {all}"
        );
        if name == "block" {
            // Linear shapes; 13 and 11 cell layers along z and y, both cut at 6; x whole (12
            // nodes). A part holds what its points reach from one cell beyond its own each
            // way: 8 node layers for a lower part (0..8), 10 for an upper one (4..14).
            assert_eq!((held, all), (vec![768, 768, 960, 960], 2016), "{what}");
        }
    }
    // Laid other than as many parts as ranks: refused, naming the count.
    let o = kdmpm_on(
        4,
        &[
            "run",
            common::scene("block_10k.ron").to_str().unwrap(),
            "--split",
            "3x2",
        ],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("4 rank(s)"), "{e}");
}

/// The fast slope laid 2 × 2 fails and runs out across both cuts (points move along each
/// axis, two hops at a corner, and the cells are cut again along both as they pile up at
/// the toe); it stops by itself at one rank's angle. Checkpointed at step 2 000 and resumed
/// on 2 × 2, it writes the bytes of the run that never stopped.
#[test]
fn the_failing_slope_split_2_by_2_comes_to_rest_at_the_angle_of_one_rank_and_resumes() {
    let (_, one) = run_on("slope_fast.ron", 1, "slope22", &[]);
    let every = ["solver.checkpoint_every=Steps(2000)"];
    let (run, many) = run_laid("slope_fast.ron", 4, Some([2, 2]), "slope22", &every);
    assert_eq!(many["outcome"], "converged");
    let angle = |s: &Value| s["surface_angle"]["degrees"].as_f64().expect("an angle");
    assert!(
        (angle(&one) - angle(&many)).abs() <= 0.05,
        "{} against {}",
        angle(&many),
        angle(&one)
    );
    assert_eq!(one["total_mass"], many["total_mass"]);
    assert!(many["ranks"]["migrations"].as_u64().unwrap() > 0);
    let held: u64 = many["ranks"]["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_u64().unwrap())
        .sum();
    assert_eq!(held, one["particles"].as_u64().unwrap());
    assert!(many["ranks"]["rebalances"].as_u64().unwrap() > 0);
    let full = run.with_file_name("slope22-full");
    let _ = std::fs::remove_dir_all(&full);
    common::copy_dir(&run, &full);
    let o = kdmpm_on(4, &["resume", run.to_str().expect("UTF-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_results_over(&run, &full, 4);
}

/// `mpirun -n RANKS kdmpm ARGS` (one thread each), waited for.
fn kdmpm_on(ranks: usize, args: &[&str]) -> std::process::Output {
    Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
        .arg(env!("CARGO_BIN_EXE_kdmpm"))
        .args(args)
        .args(["--quiet", "--threads", "1"])
        .output()
        .expect("mpirun starts")
}

/// The results of run directories `a` and `b` over `ranks` ranks have the same bytes:
/// history, curve, the final points (the `.pvtu` and every rank's piece) and the summary's
/// figures.
fn same_results_over(a: &Path, b: &Path, ranks: usize) {
    let mut files: Vec<String> = vec!["history.csv".into(), "points.pvtu".into()];
    files.extend((0..ranks).map(|r| format!("points_{r}.vtu")));
    if a.join("curve.csv").exists() {
        files.push("curve.csv".into());
    }
    for f in &files {
        let (x, y) = (std::fs::read(a.join(f)), std::fs::read(b.join(f)));
        assert!(
            x.is_ok() && x.ok() == y.ok(),
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
    assert_eq!(common::summary_numbers(a), common::summary_numbers(b));
}

/// The fast slope on 2 ranks with a checkpoint every 2 000 steps (it stops at 3 767): each
/// rank writes its part, rank 0 the manifest; resumed from step 2 000 on 2 ranks it writes
/// the bytes of the run that never stopped (points migrate and the split is made again
/// after the checkpoint). On one rank or on 3 the checkpoint is refused with the count.
#[test]
fn the_slope_checkpointed_on_2_ranks_resumes_to_the_bytes_of_the_uninterrupted_run() {
    let (run, _) = run_on(
        "slope_fast.ron",
        2,
        "ckpt",
        &["solver.checkpoint_every=Steps(2000)"],
    );
    let manifest = std::fs::read(run.join("checkpoint.kdc")).expect("the manifest");
    assert!(manifest.starts_with(b"KDMPMMF\0"));
    for r in 0..2 {
        assert!(
            run.join(format!("checkpoint.{:012}.{r}.kdc", 2000)).exists(),
            "rank {r}'s part"
        );
    }
    let parts = std::fs::read_dir(&run)
        .expect("the run's directory")
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".kdc"))
        .count();
    assert_eq!(parts, 3, "the manifest and the last checkpoint's two parts");
    let full = run.with_file_name("ckpt-full");
    let _ = std::fs::remove_dir_all(&full);
    common::copy_dir(&run, &full);
    let dir = run.to_str().expect("UTF-8");
    for ranks in [1, 3] {
        let o = kdmpm_on(ranks, &["resume", dir]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "resumed on {ranks}: {e}");
        assert!(e.contains("2 ranks"), "resumed on {ranks}: {e}");
    }
    // A part changed after the manifest was written, or gone: refused on every rank (bad
    // input, exit 2), never a hang of the ranks that could read theirs.
    let part = format!("checkpoint.{:012}.1.kdc", 2000);
    for (case, spoil) in [
        (
            "changed",
            &(|p: &Path| {
                let mut b = std::fs::read(p).expect("the part");
                let at = b.len() / 2;
                b[at] ^= 1;
                std::fs::write(p, b).expect("written");
            }) as &dyn Fn(&Path),
        ),
        ("gone", &|p: &Path| std::fs::remove_file(p).expect("removed")),
    ] {
        let spoilt = run.with_file_name(format!("ckpt-{case}"));
        let _ = std::fs::remove_dir_all(&spoilt);
        common::copy_dir(&run, &spoilt);
        spoil(&spoilt.join(&part));
        let o = kdmpm_on(2, &["resume", spoilt.to_str().expect("UTF-8")]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "a part {case}: {e}");
        assert!(e.contains(&part), "a part {case}: {e}");
    }
    let o = kdmpm_on(2, &["resume", dir]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_results_over(&run, &full, 2);
}

/// SIGTERM to `mpirun` (what a batch system sends at a job's time limit) mid-run: mpirun
/// passes it to every rank, the ranks stop together after the same step and leave a
/// checkpoint, and the run resumed on 2 ranks writes the bytes of the 2-rank run that was
/// never interrupted.
#[test]
fn sigterm_to_mpirun_leaves_a_checkpoint_that_resumes_to_the_uninterrupted_bytes() {
    let steps = "solver.max_steps=3000";
    let (whole, _) = run_on("slope.ron", 2, "term-whole", &[steps]);
    let cut = common::scratch("mpi", "term-cut");
    let scene = common::scene("slope.ron");
    let child = Command::new("mpirun")
        .args(["--allow-run-as-root", "--oversubscribe", "-n", "2"])
        .arg(env!("CARGO_BIN_EXE_kdmpm"))
        .args(["run", scene.to_str().expect("UTF-8"), "--quiet", "--threads", "1"])
        .args(["--set", steps, "--out"])
        .arg(&cut)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("mpirun starts");
    common::wait_until_running(&cut);
    common::signal(child.id(), "TERM");
    let o = child.wait_with_output().expect("mpirun ends");
    let summary = common::summary_numbers(&cut);
    assert_eq!(
        summary["outcome"],
        "interrupted",
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(summary["steps"].as_u64().expect("steps") < 3000);
    assert!(cut.join("checkpoint.kdc").exists());
    let o = kdmpm_on(2, &["resume", cut.to_str().expect("UTF-8")]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    same_results_over(&cut, &whole, 2);
}

/// `kdmpm fos --refine 2` on 2 ranks: every trial of both cell sizes over the ranks, to one
/// rank's answers and estimate (the slope from h = 1 m, as `refine::two_cell_sizes_of_the_slope_…`
/// pins on one rank: 1.4140625 and 1.3828125, extrapolated 1.3515625).
#[test]
fn the_factor_of_safety_refined_on_2_ranks_is_one_ranks() {
    let scene = common::scene("slope_fos.ron");
    let refined = |ranks: usize| -> Value {
        let out = common::scratch("mpi", &format!("fos-refine-{ranks}"));
        let (s, o) = (scene.to_str().expect("UTF-8"), out.to_str().expect("UTF-8"));
        let args = [
            "fos",
            s,
            "--out",
            o,
            "--refine",
            "2",
            "--set",
            "grid.cell_size=1.0",
        ];
        let r = kdmpm_on(ranks, &[&args[..], &["--set", "grid.cells=[55, 12]"]].concat());
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
        let v: Value = serde_json::from_str(&text).expect("JSON");
        v["refinement"].clone()
    };
    let (one, two) = (refined(1), refined(2));
    let values = |r: &Value| -> Vec<Value> {
        r["levels"]
            .as_array()
            .expect("levels")
            .iter()
            .map(|l| l["value"].clone())
            .collect()
    };
    assert_eq!(values(&one), values(&two));
    assert_eq!(values(&two), [Value::from(1.4140625), Value::from(1.3828125)]);
    assert_eq!(one["extrapolated"], two["extrapolated"]);
}

/// A point that leaves the grid in one rank's layers (the column flung upwards by a
/// gravity of 10⁵ m/s², on 2 and 4 ranks: the top rank's points leave first) stops every
/// rank at the same system: the run ends as failed with that rank's error, in rank 0's
/// summary and on stderr once, and no rank waits for the others for ever.
#[test]
fn a_point_leaving_the_grid_on_one_rank_stops_every_rank_with_its_error() {
    for ranks in [2, 4] {
        let out = common::scratch("mpi", &format!("flung-{ranks}"));
        let mut child = Command::new("mpirun")
            .args(["--allow-run-as-root", "--oversubscribe", "-n", &ranks.to_string()])
            .arg(env!("CARGO_BIN_EXE_kdmpm"))
            .args(["run", common::scene("soil_column.ron").to_str().expect("UTF-8")])
            .args([
                "--quiet",
                "--threads",
                "1",
                "--set",
                "gravity.acceleration=[0.0, 1e5]",
                "--out",
            ])
            .arg(&out)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("mpirun starts");
        let start = std::time::Instant::now();
        while child.try_wait().expect("mpirun").is_none() {
            if start.elapsed().as_secs() > 120 {
                let _ = child.kill();
                panic!("{ranks} ranks: the ranks still wait after 120 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let o = child.wait_with_output().expect("mpirun ends");
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{ranks} ranks: {e}");
        let last = format!("rank {}: step 2, system `kinematics`", ranks - 1);
        assert_eq!(e.matches("left the grid").count(), 1, "{ranks} ranks: {e}");
        assert!(e.contains(&last), "{ranks} ranks: {e}");
        let s = common::summary_numbers(&out);
        assert_eq!(s["outcome"], "failed");
        assert!(s["error"].as_str().expect("the error").starts_with(&last), "{s}");
    }
}

/// `kdmpm study --launcher "mpirun … -n 2"` starts each of its runs over 2 ranks and
/// tabulates what one-process runs give, to 1e-10 (the ranks sum in another order); under
/// mpirun itself the study is refused, naming the launcher.
#[test]
fn a_study_launching_its_runs_on_2_ranks_tabulates_one_ranks_answers() {
    if child() {
        return;
    }
    let dir = common::scratch("mpi", "study");
    let study = dir.join("slope.ron");
    let scene = common::scene("slope_fast.ron");
    std::fs::write(
        &study,
        format!(
            "Study(scene: {:?}, axes: [Set(path: \"solver.time_step\", values: [\"Courant(0.4)\", \
             \"Courant(0.5)\"])], quantities: [(name: \"angle\", of: SurfaceAngle, compare: \
             Analytic(30.0)), (name: \"crest\", of: Displacement(point: \"crest\", component: 0), \
             compare: Analytic(-1.0))])",
            scene.to_str().expect("UTF-8")
        ),
    )
    .unwrap();
    let conduct = |name: &str, launcher: Option<&str>| {
        let out = dir.join(name);
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_kdmpm"));
        cmd.arg("study")
            .arg(&study)
            .arg("--out")
            .arg(&out)
            .args(["--quiet", "--threads", "1"]);
        if let Some(l) = launcher {
            cmd.args(["--launcher", l]);
        }
        let o = cmd.output().expect("kdmpm starts");
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        out
    };
    let one = conduct("one", None);
    let two = conduct("two", Some("mpirun --allow-run-as-root --oversubscribe -n 2"));
    let table = |out: &Path| -> Vec<Vec<String>> {
        let text = std::fs::read_to_string(out.join("study.csv")).expect("study.csv");
        text.lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let (a, b) = (table(&one), table(&two));
    assert_eq!(a.len(), 3, "{a:?}");
    assert_eq!(a[0], b[0], "the same columns");
    for (ra, rb) in a[1..].iter().zip(&b[1..]) {
        for ((head, x), y) in a[0].iter().zip(ra).zip(rb) {
            // Machine figures, and the front they decide.
            if [
                "wall_seconds",
                "particle_steps_per_second",
                "peak_memory_bytes",
                "pareto",
            ]
            .contains(&head.as_str())
            {
                continue;
            }
            match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(p), Ok(q)) => assert!(
                    p == q || (p - q).abs() <= 1e-10 * p.abs().max(q.abs()),
                    "{head}: {p} on one rank, {q} on 2"
                ),
                _ => assert_eq!(x, y, "{head}"),
            }
        }
    }
    // Each run of the second study went over 2 ranks, to one rank's answer at full precision.
    for run in ["run-001", "run-002"] {
        let read = |d: &Path| -> Value {
            serde_json::from_str(&std::fs::read_to_string(d.join(run).join("summary.json")).unwrap()).unwrap()
        };
        let (a, b) = (read(&one), read(&two));
        assert_eq!(b["ranks"]["count"], 2, "{run}");
        assert!(a["ranks"].is_null(), "{run}");
        assert_eq!(a["steps"], b["steps"], "{run}");
        let angle = |s: &Value| s["surface_angle"]["degrees"].clone();
        assert!(
            rel(&angle(&a), &angle(&b)) <= 1e-10,
            "{run}: {} {}",
            angle(&a),
            angle(&b)
        );
    }
    let o = kdmpm_on(2, &["study", study.to_str().expect("UTF-8")]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--launcher"), "{e}");
}

/// The oedometer's clay pressed past v = 1 (cell 0.125 m, 240 and 16 points on the two
/// ranks): on 2 ranks the run stops at one rank's static state, naming one rank's point
/// (the smallest faulty id over the ranks) with its reason, exit 1.
#[test]
fn a_clay_with_no_voids_left_stops_2_ranks_where_it_stops_one() {
    let scene = common::scene("clay_oedometer.ron");
    let fault = |ranks: usize| {
        let out = common::scratch("mpi", &format!("no-voids-{ranks}"));
        let mut args = vec![
            "run",
            scene.to_str().expect("UTF-8"),
            "--out",
            out.to_str().expect("UTF-8"),
        ];
        let sets = [
            "tractions[0].pressure=6.0e6",
            "materials.clay.max_mean_stress=2.9e6",
            "grid.cell_size=0.125",
            "grid.cells=[8, 12]",
            "tractions[0].min=[0.0, 0.875]",
        ];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let o = kdmpm_on(ranks, &args);
        assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
        summary["error"].as_str().expect("the error").to_string()
    };
    let (one, two) = (fault(1), fault(2));
    for e in [&one, &two] {
        assert!(
            e.contains("step 1557") && e.contains("point 144") && e.contains("no voids left"),
            "{e}"
        );
    }
}
