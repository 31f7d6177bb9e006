//! The library's runner, in process: a run interrupted by its stop signal writes a
//! checkpoint, and resumed from it ends with the same files, bit for bit, as a run that was
//! never stopped.

use crate::common::{on_own_thread, scene, scratch};
use kdmpm::output::Outcome;
use kdmpm::run::Run;
use kdmpm::scene::LoadedScene;
use kdmpm::StopSignal;

/// The footing loaded in traction increments, on 0.5 m cells (3158 steps; the runner is
/// under test, not the footing): a stop halfway falls inside an increment.
fn footing() -> LoadedScene {
    let sets = [
        "output.snapshots=None",
        "grid.cell_size=0.5",
        "grid.cells=[12, 9]",
    ];
    LoadedScene::from_file(&scene("footing_load.ron"), &sets.map(String::from)).expect("scene loads")
}

#[test]
fn a_run_stopped_in_process_resumes_to_the_same_bits() {
    on_own_thread(stopped_and_resumed)
}

fn stopped_and_resumed() {
    let d = scratch("run-in-process", "resume");
    let (whole, parted) = (d.join("whole"), d.join("parted"));
    let straight = Run::scene(footing())
        .into_dir(&whole)
        .quiet(true)
        .go()
        .expect("runs");
    assert_eq!(straight.summary.outcome, Outcome::Converged);
    assert_eq!(straight.summary.steps, 3158);
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
    let report = on_own_thread(|| Run::scene(footing()).quiet(true).go().expect("runs"));
    assert_eq!(report.summary.outcome, Outcome::Converged);
    assert!(report.dir.is_none() && report.error.is_none());
    assert!(
        report.describe().starts_with("converged after "),
        "{}",
        report.describe()
    );
}
