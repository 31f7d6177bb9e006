//! Progress over a study's runs: a bar on a terminal, a line a run otherwise, nothing when
//! quiet.

use super::{Finished, Planned};
use std::cell::Cell;

/// Shows which run is under way and how the finished ones ended.
pub(crate) struct StudyProgress {
    bar: Option<indicatif::ProgressBar>,
    lines: bool,
    total: u64,
    done: Cell<u64>,
}

impl StudyProgress {
    /// Progress over `total` runs.
    pub(crate) fn new(total: u64, quiet: bool) -> Self {
        use std::io::IsTerminal;
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_style(
                indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} runs, {elapsed} elapsed, ~{eta} left  {msg}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        StudyProgress {
            bar,
            lines: !quiet && !terminal,
            total,
            done: Cell::new(0),
        }
    }

    /// `run` begins.
    pub(crate) fn start(&self, run: &Planned) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{} {}", run.id, run.values.join(", ")));
        }
    }

    /// A run ended as `f` says.
    pub(crate) fn finish(&self, f: &Finished) {
        self.done.set(self.done.get() + 1);
        let text = format!(
            "{} [{}] {}: {} in {:.1} s{}",
            f.run.id,
            if f.run.values.is_empty() {
                "reference".into()
            } else {
                f.run.values.join(", ")
            },
            self.done.get(),
            f.outcome,
            f.wall_seconds,
            if f.reused {
                " (from an earlier invocation)"
            } else {
                ""
            }
        );
        if let Some(bar) = &self.bar {
            bar.println(text);
            bar.inc(1);
        } else if self.lines {
            eprintln!("run {}/{}: {text}", self.done.get(), self.total);
        }
    }

    /// Clears the bar.
    pub(crate) fn done(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
