//! A checkpoint is resumed only when it is whole, unchanged, of this build and of the
//! scene and history it claims: random byte flips, truncations and a checkpoint of another
//! scene are refused with the reason (never a panic), and only the untouched file resumes,
//! to the bits of the run that never stopped.

use crate::common;

use kdmpm::checkpoint::{self, Header};
use kdmpm::components::{MaterialId, PointId};
use kdmpm::infra::columns::{col_mut, points_with};
use kdmpm::scene::{build, LoadedScene};
use kdmpm::{AnySimulation, Dim2, Simulation};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::Path;

fn column(sets: &[&str]) -> (LoadedScene, Simulation<Dim2>) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let loaded = LoadedScene::from_file(&common::scene("soil_column.ron"), &sets).unwrap();
    let AnySimulation::Two(sim) = build(&loaded).unwrap().0 else {
        unreachable!("2D scene")
    };
    (loaded, sim)
}

fn header(loaded: &LoadedScene) -> Header {
    Header {
        scene_path: loaded.path.clone(),
        scene_text: loaded.text.clone(),
        ..Header::default()
    }
}

/// The column after 40 steps as checkpoint bytes, and the bytes of the same run at its end.
fn saved_and_final() -> (LoadedScene, Vec<u8>, Vec<u8>) {
    let (loaded, mut sim) = column(&["solver.max_steps=80"]);
    for _ in 0..40 {
        sim.step().unwrap();
    }
    let saved = checkpoint::encode(&sim, &header(&loaded));
    sim.run(|_| {}).unwrap();
    let end = checkpoint::encode(&sim, &header(&loaded));
    (loaded, saved, end)
}

/// Restores `bytes` into a fresh column and runs it to its end: its final bytes, or the
/// refusal.
fn resume(loaded: &LoadedScene, bytes: &[u8]) -> Result<Vec<u8>, String> {
    let h = checkpoint::header(bytes, Path::new("c")).map_err(|e| e.to_string())?;
    let (_, mut sim) = column(&["solver.max_steps=80"]);
    checkpoint::restore(&mut sim, bytes, Path::new("c")).map_err(|e| e.to_string())?;
    assert_eq!(h.scene_text, loaded.text);
    sim.run(|_| {}).unwrap();
    Ok(checkpoint::encode(&sim, &header(loaded)))
}

#[derive(Clone, Debug)]
enum Damage {
    /// XOR one byte at a fraction of the file with a non-zero mask.
    Flip(f64, u8),
    /// Keep a fraction of the file.
    Truncate(f64),
    /// Append bytes.
    Append(Vec<u8>),
}

#[test]
fn a_damaged_checkpoint_is_refused_and_only_the_whole_one_resumes_to_the_same_bits() {
    let (loaded, saved, end) = saved_and_final();
    assert_eq!(
        resume(&loaded, &saved).unwrap(),
        end,
        "the untouched file resumes bit for bit"
    );
    let damage = prop_oneof![
        6 => (0.0..1.0f64, 1..=255u8).prop_map(|(f, m)| Damage::Flip(f, m)),
        2 => (0.0..1.0f64).prop_map(Damage::Truncate),
        1 => prop::collection::vec(any::<u8>(), 1..16).prop_map(Damage::Append),
    ];
    let config = Config {
        cases: 300,
        failure_persistence: None,
        ..Config::default()
    };
    let mut runner = TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &[3; 32]));
    runner
        .run(&damage, |d| {
            let mut bytes = saved.clone();
            match d {
                Damage::Flip(f, m) => {
                    let at = ((f * bytes.len() as f64) as usize).min(bytes.len() - 1);
                    bytes[at] ^= m;
                }
                Damage::Truncate(f) => bytes.truncate((f * bytes.len() as f64) as usize),
                Damage::Append(extra) => bytes.extend(extra),
            }
            match resume(&loaded, &bytes) {
                Err(e) => prop_assert!(e.starts_with("checkpoint c: "), "{e}"),
                Ok(b) => prop_assert!(b == end, "a damaged checkpoint resumed to other bits"),
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn a_checkpoint_with_an_edited_scene_is_refused_by_its_checksum() {
    let (loaded, saved, _) = saved_and_final();
    let mut bytes = saved.clone();
    // The column's density, 1800, becomes 1900 inside the stored scene text.
    let at = bytes
        .windows(6)
        .position(|w| w == b"1800.0")
        .expect("the scene text is stored");
    bytes[at + 1] = b'9';
    let e = resume(&loaded, &bytes).unwrap_err();
    assert!(e.contains("checksum does not match"), "{e}");
}

#[test]
fn a_checkpoint_holding_an_out_of_range_id_is_refused_never_a_panic() {
    // Bytes a checksum vouches for but that do not fit the scene: ids past its materials
    // and points, as a checkpoint of another scene made to fit would hold.
    for (what, expect) in [
        ("material", "material id 7"),
        ("point", "id 4000000000"),
        ("twice", "two points"),
    ] {
        let (loaded, mut sim) = column(&[]);
        sim.step().unwrap();
        for arch in points_with::<MaterialId>(&sim.ctx.world) {
            match what {
                "material" => col_mut::<MaterialId>(arch)[0] = MaterialId(7),
                "point" => col_mut::<PointId>(arch)[3] = PointId(4_000_000_000),
                _ => {
                    let mut ids = col_mut::<PointId>(arch);
                    ids[5] = ids[6];
                }
            }
        }
        let bytes = checkpoint::encode(&sim, &header(&loaded));
        let (_, mut fresh) = column(&[]);
        let e = checkpoint::restore(&mut fresh, &bytes, Path::new("c"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(expect), "{what}: {e}");
    }
}

#[test]
fn resume_refuses_a_checkpoint_beside_another_runs_history() {
    let dir = common::scratch("integrity", "history");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let bar = common::scene("bar.ron");
    let run = |out: &Path, sets: &[&str]| {
        let o = common::run_into(&bar, out, sets);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&a, &["solver.checkpoint_every=Steps(300)"]);
    // Another run of the bar with another time step: a longer history, with other rows.
    run(&b, &["solver.time_step=Fixed(0.005)"]);
    std::fs::copy(a.join("checkpoint.kdc"), b.join("checkpoint.kdc")).unwrap();
    let before = std::fs::read(b.join("history.csv")).unwrap();
    let o = common::kdmpm(&["resume", b.to_str().unwrap(), "--quiet"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("not the history this checkpoint continues"), "{err}");
    assert_eq!(
        std::fs::read(b.join("history.csv")).unwrap(),
        before,
        "the history was cut"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
