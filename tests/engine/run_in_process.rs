//! The library's runner, in process: a run interrupted by its stop signal writes a
//! checkpoint, and resumed from it ends with the same files, bit for bit, as a run that was
//! never stopped.

use crate::common::{scene, scratch};
use kdmpm::output::Outcome;
use kdmpm::run::Run;
use kdmpm::scene::LoadedScene;
use kdmpm::StopSignal;

/// The footing loaded in traction increments to its limit (7146 steps, 72 resets): a stop
/// halfway falls inside an increment.
fn footing() -> LoadedScene {
    LoadedScene::from_file(&scene("footing_load.ron"), &["output.snapshots=None".into()])
        .expect("scene loads")
}

#[test]
fn a_run_stopped_in_process_resumes_to_the_same_bits() {
    let d = scratch("run-in-process", "resume");
    let (whole, parted) = (d.join("whole"), d.join("parted"));
    let straight = Run::scene(footing())
        .into_dir(&whole)
        .quiet(true)
        .go()
        .expect("runs");
    assert_eq!(straight.summary.outcome, Outcome::Converged);
    assert_eq!(straight.summary.steps, 7146);
    let stop_at = straight.summary.steps / 2;

    // Stopped halfway by its own signal (the process's flag, and so the other tests of
    // this binary, are not touched).
    let stop = StopSignal::private();
    let asker = stop.clone();
    let first = Run::scene(footing())
        .into_dir(&parted)
        .quiet(true)
        .stop_signal(stop)
        .observe(move |st| {
            if st.clock.step == stop_at {
                asker.request();
            }
        })
        .go()
        .expect("runs");
    assert_eq!(first.summary.outcome, Outcome::Interrupted);
    assert_eq!(first.summary.steps, stop_at, "stops after the step that asked");
    assert!(parted.join("checkpoint.kdc").exists());

    let resumed = Run::resume(&parted).quiet(true).go().expect("resumes");
    assert_eq!(resumed.summary.outcome, Outcome::Converged);
    assert_eq!(resumed.summary.steps, straight.summary.steps);
    for file in ["history.csv", "points.vtu", "curve.csv"] {
        let a = std::fs::read(whole.join(file)).unwrap();
        let b = std::fs::read(parted.join(file)).unwrap();
        assert!(
            a == b,
            "{file} of the resumed run differs from the run never stopped"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_run_in_memory_writes_nothing_and_reports_its_summary() {
    let report = Run::scene(footing()).quiet(true).go().expect("runs");
    assert_eq!(report.summary.outcome, Outcome::Converged);
    assert!(report.dir.is_none() && report.error.is_none());
    assert!(
        report.describe().starts_with("converged after "),
        "{}",
        report.describe()
    );
}
