//! A run's progress on stderr: a live line on a terminal (indicatif), plain lines every few
//! seconds otherwise, nothing when quiet.

use crate::state::SolverState;
use crate::systems::convergence::{is_defined, ratio_text};
use indicatif::{ProgressBar, ProgressStyle};
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Samples of ln K_F kept for the trend (one a refresh).
const TREND: usize = 40;

/// Reports step, simulated time, K_F, K_E, resets, steps a second and an estimate of the
/// time until K_F reaches the tolerance, from the trend of ln K_F over the last samples
/// (a least-squares line in the step number). A static check adds its window after that.
pub struct Progress {
    bar: Option<ProgressBar>,
    every: Duration,
    tolerance: f64,
    trend: VecDeque<(f64, f64)>,
    start: Instant,
    start_step: u64,
    last: Instant,
}

impl Progress {
    /// Progress for a run that starts (or resumes) at `start_step` and stops at
    /// `tolerance`. `quiet` prints nothing; off a terminal it prints a line every 2 s.
    pub fn new(quiet: bool, tolerance: f64, start_step: u64) -> Progress {
        use std::io::IsTerminal;
        let terminal = !quiet && std::io::stderr().is_terminal();
        let bar = terminal.then(|| {
            let bar = ProgressBar::new_spinner();
            bar.set_style(
                ProgressStyle::with_template("{spinner} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_spinner()),
            );
            bar
        });
        let every = if quiet {
            Duration::MAX
        } else if terminal {
            Duration::from_millis(250)
        } else {
            Duration::from_secs(2)
        };
        let now = Instant::now();
        Progress {
            bar,
            every,
            tolerance,
            trend: VecDeque::with_capacity(TREND),
            start: now,
            start_step,
            last: now,
        }
    }

    /// Called after every step; refreshes when it is time to.
    pub fn update(&mut self, st: &SolverState) {
        if self.every == Duration::MAX || self.last.elapsed() < self.every {
            return;
        }
        self.last = Instant::now();
        let kf = st.convergence.force_ratio_max;
        if is_defined(kf) && kf > 0.0 {
            if self.trend.len() == TREND {
                self.trend.pop_front();
            }
            self.trend.push_back((st.clock.step as f64, kf.ln()));
        }
        let rate = (st.clock.step - self.start_step) as f64 / self.start.elapsed().as_secs_f64().max(1e-9);
        let eta = self
            .eta(kf, rate)
            .map_or("?".into(), |s| format!("~{}", duration(s)));
        let text = format!(
            "step {:>8}  t = {:<9.4} s  K_F = {}  K_E = {}  resets {:>4}  {:>7.0} steps/s  K_F ≤ {:e} in {eta}",
            st.clock.step,
            st.clock.time,
            ratio_text(kf, 3),
            ratio_text(st.convergence.energy_ratio, 3),
            st.resets.count,
            rate,
            self.tolerance
        );
        match &self.bar {
            Some(bar) => {
                bar.set_message(text);
                bar.tick();
            }
            None => eprintln!("  {text}"),
        }
    }

    /// Seconds until K_F meets the tolerance on the present trend, when it is falling.
    fn eta(&self, kf: f64, rate: f64) -> Option<f64> {
        if !is_defined(kf) || kf <= self.tolerance {
            return Some(0.0);
        }
        if self.trend.len() < 4 || rate <= 0.0 {
            return None;
        }
        let n = self.trend.len() as f64;
        let (sx, sy) = self
            .trend
            .iter()
            .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
        let (mx, my) = (sx / n, sy / n);
        let (sxy, sxx) = self.trend.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
            (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
        });
        let slope = sxy / sxx;
        if slope.is_nan() || slope >= 0.0 {
            return None;
        }
        let steps = (self.tolerance.ln() - kf.ln()) / slope;
        Some(steps / rate)
    }

    /// Clears the live line.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// `s` seconds as `1h02m`, `3m05s` or `12s`.
fn duration(s: f64) -> String {
    let s = s.round() as u64;
    match s {
        0..60 => format!("{s}s"),
        60..3600 => format!("{}m{:02}s", s / 60, s % 60),
        _ => format!("{}h{:02}m", s / 3600, s % 3600 / 60),
    }
}
