//! The ParaView series of a run (`points.pvd` and `snapshots/*.vtu`), read back with an XML
//! parser of its own (roxmltree) and VTK's definition of raw appended data, not with the
//! writer's code: every snapshot's time is the history's at its step, the final snapshot
//! holds the traced points' displacement and stress of summary.json, and a resumed run
//! continues the series.

use std::collections::BTreeMap;
use std::path::Path;

use crate::common;

/// (time, file) of every DataSet of a collection, parsed as XML.
fn read_pvd(path: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(path).expect("points.pvd");
    let doc = roxmltree::Document::parse(&text).expect("the collection is well-formed XML");
    assert_eq!(doc.root_element().attribute("type"), Some("Collection"));
    doc.descendants()
        .filter(|n| n.has_tag_name("DataSet"))
        .map(|n| {
            (
                n.attribute("timestep").unwrap().parse().unwrap(),
                n.attribute("file").unwrap().to_string(),
            )
        })
        .collect()
}

/// Step and time of every history row.
fn history_times(dir: &Path) -> BTreeMap<u64, f64> {
    let text = std::fs::read_to_string(dir.join("history.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let mut f = l.split(',');
            (
                f.next().unwrap().parse().unwrap(),
                f.next().unwrap().parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_series_reads_back_with_history_times_and_summary_values() {
    let out = common::scratch("snapshots", "series");
    let column = common::scene("soil_column.ron");
    let o = common::kdmpm(&[
        "run",
        column.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "output.snapshots=(every_steps: 20, at_resets: true)",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let series = read_pvd(&out.join("points.pvd"));
    assert_eq!(series.len() as u64, summary["snapshots"].as_u64().unwrap());
    assert!(summary["output_wait_seconds"].as_f64().unwrap() >= 0.0);
    let steps = summary["steps"].as_u64().unwrap();
    let history = history_times(&out);
    let dt = summary["time_step"].as_f64().unwrap();
    let mut previous = 0.0;
    for (t, file) in &series {
        let step: u64 = file
            .trim_start_matches("snapshots/points_")
            .trim_end_matches(".vtu")
            .parse()
            .unwrap();
        // Simulated time n Δt; the history (every 10 steps) has the same time at its rows.
        assert!((t / (step as f64 * dt) - 1.0).abs() < 1e-12, "{file}: {t}");
        if let Some(h) = history.get(&step) {
            assert!((t / h - 1.0).abs() < 1e-9, "{file}: pvd {t}, history {h}");
        }
        assert!(*t > previous, "times increase");
        previous = *t;
        assert!(out.join(file).exists());
    }
    // The four figures are written next to the results, as well-formed SVG.
    for plot in kdmpm::output::plots::FILES {
        let text = std::fs::read_to_string(out.join(plot)).unwrap_or_else(|e| panic!("{plot}: {e}"));
        let doc = roxmltree::Document::parse(&text).unwrap_or_else(|e| panic!("{plot}: {e}"));
        assert_eq!(doc.root_element().tag_name().name(), "svg", "{plot}");
    }
    let last = &series.last().unwrap().1;
    assert_eq!(
        last,
        &format!("snapshots/points_{steps:09}.vtu"),
        "the last step is a snapshot"
    );

    // The final snapshot holds every point, and the traced points' values of summary.json.
    let arrays = common::read_vtu(&out.join(last));
    let (_, ids) = &arrays["id"];
    assert_eq!(ids.len() as u64, summary["particles"].as_u64().unwrap());
    let (_, x) = &arrays["Points"];
    let (_, u) = &arrays["displacement"];
    let (_, s) = &arrays["stress"];
    for name in [
        "velocity",
        "mean_stress",
        "deviatoric_stress",
        "material",
        "plastic_strain",
        "volume",
    ] {
        assert!(arrays.contains_key(name), "{name}");
    }
    for traced in summary["traced"].as_array().unwrap() {
        let x0: Vec<f64> = traced["initial_position"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let k = (0..ids.len())
            .min_by(|&a, &b| {
                let d = |k: usize| {
                    (0..3)
                        .map(|c| (x[3 * k + c] - u[3 * k + c] - x0[c]).powi(2))
                        .sum::<f64>()
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        for c in 0..3 {
            assert_eq!(
                u[3 * k + c],
                traced["displacement"][c].as_f64().unwrap(),
                "{traced}"
            );
        }
        for (c, name) in ["xx", "yy", "zz", "xy", "yz", "zx"].iter().enumerate() {
            assert_eq!(
                s[6 * k + c],
                traced["stress"][*name].as_f64().unwrap(),
                "{traced}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_resumed_run_continues_the_series_of_the_run_it_resumes() {
    // The bar, checkpointed every 300 steps and stopped by max_steps at 700, then resumed
    // with a longer limit: the series holds the first run's snapshots up to its checkpoint
    // (step 600) and the resumed run's after it, each once.
    let out = common::scratch("snapshots", "resume");
    let bar = common::scene("bar.ron");
    let first = common::kdmpm(&[
        "run",
        bar.to_str().unwrap(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--set",
        "output.snapshots=(every_steps: 100)",
        "--set",
        "solver.checkpoint_every=Steps(300)",
        "--set",
        "solver.max_steps=700",
    ]);
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    // Resume from the checkpoint at step 600 as if the run had stopped there.
    let resumed = common::kdmpm(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    let steps: Vec<u64> = read_pvd(&out.join("points.pvd"))
        .iter()
        .map(|(_, f)| {
            f.trim_start_matches("snapshots/points_")
                .trim_end_matches(".vtu")
                .parse()
                .unwrap()
        })
        .collect();
    let mut sorted = steps.clone();
    sorted.dedup();
    assert_eq!(sorted, steps, "each step once, in order: {steps:?}");
    assert_eq!(&steps[..6], &[100, 200, 300, 400, 500, 600], "{steps:?}");
    let _ = std::fs::remove_dir_all(&out);
}
