//! The paper's figures of a run, drawn from its files (SVG, plotters; no font files and no
//! external program): kinetic energy with its resets (Figs. 3 and 6), the force and energy
//! ratios against the tolerance, the traced displacements (Fig. 4) and the displacement
//! field over the deformed points (Fig. 7). `kdmpm plot DIR` redraws them from a finished
//! or a running output directory.

use crate::output::dir::write_atomic;
use crate::output::field_sample::FieldSample;
use plotters::prelude::*;
use std::io::Write;
use std::path::Path;

/// The files [`draw`] writes.
pub const FILES: [&str; 4] = [
    "kinetic_energy.svg",
    "convergence.svg",
    "traced_displacement.svg",
    "displacement_field.svg",
];

/// The load–displacement plot, drawn when the run wrote `curve.csv`.
pub const CURVE_PLOT: &str = "curve.svg";

/// A piezocone's log drawn as a CPT log, when the run wrote `cpt.csv`.
pub const CPT_PLOT: &str = "cpt.svg";

/// `history.csv` as columns of numbers (an empty cell, or `undefined` in the files of
/// earlier versions, is NaN here, and
/// left out of every plot).
struct History {
    names: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl History {
    fn read(path: &Path) -> std::io::Result<History> {
        let text = std::fs::read_to_string(path)?;
        let mut lines = text.lines();
        let names: Vec<String> = lines
            .next()
            .unwrap_or("")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|v| v.parse().unwrap_or(f64::NAN))
                    .collect::<Vec<f64>>()
            })
            .filter(|r| r.len() == names.len())
            .collect();
        Ok(History { names, rows })
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.names.iter().position(|n| n == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

/// Draws the four figures of the run in `dir` next to its results. Returns the names
/// written and, for a figure that could not be drawn, why (a run without `points.vtu` yet
/// has no displacement field).
pub fn draw(dir: &Path) -> std::io::Result<(Vec<&'static str>, Vec<String>)> {
    let history = History::read(&dir.join("history.csv"))?;
    let summary: serde_json::Value = std::fs::read_to_string(dir.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .unwrap_or_default();
    let tolerance = summary["tolerance"].as_f64();
    let mut written = Vec::new();
    let mut skipped = Vec::new();
    let t = history.column("time").unwrap_or_default();
    let save = |name: &str, svg: String| write_atomic(&dir.join(name), |out| out.write_all(svg.as_bytes()));

    if let (Some(ke), Some(resets)) = (history.column("kinetic_energy"), history.column("resets")) {
        save(FILES[0], kinetic_energy(&t, &ke, &resets))?;
        written.push(FILES[0]);
    }
    if let (Some(kf), Some(ke)) = (history.column("force_ratio_max"), history.column("energy_ratio")) {
        save(FILES[1], ratios(&t, &kf, &ke, tolerance))?;
        written.push(FILES[1]);
    }
    let traced: Vec<(String, Vec<f64>)> = history
        .names
        .iter()
        .filter(|n| n.ends_with("_ux") || n.ends_with("_uy") || n.ends_with("_uz"))
        .filter_map(|n| Some((n.clone(), history.column(n)?)))
        .collect();
    if traced.is_empty() {
        skipped.push(format!("{}: the scene traces no point", FILES[2]));
    } else {
        save(FILES[2], traced_plot(&t, &traced))?;
        written.push(FILES[2]);
    }
    match FieldSample::read_run(dir) {
        Ok(Some(sample)) => {
            save(FILES[3], field(&sample))?;
            written.push(FILES[3]);
        }
        Ok(None) => skipped.push(format!("{}: the run keeps no displacements", FILES[3])),
        Err(e) => skipped.push(format!("{}: {e}", FILES[3])),
    }
    if let Ok(curve) = History::read(&dir.join("curve.csv")) {
        // The first column (the motion's name) reads as NaN: the rows are in file order.
        let names: Vec<String> = std::fs::read_to_string(dir.join("curve.csv"))?
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap_or("").to_string())
            .collect();
        let y = curve
            .column("pressure")
            .map(|p| (p, "mean pressure (Pa)"))
            .or_else(|| {
                let f = curve.column("force_y")?;
                Some((f.iter().map(|v| -v).collect(), "-force_y (N; N/m in 2D)"))
            });
        if let (Some(u), Some((y, label))) = (curve.column("displacement"), y) {
            save(CURVE_PLOT, curve_plot(&names, &u, &y, label))?;
            written.push(CURVE_PLOT);
        }
    }
    if let Ok(log) = History::read(&dir.join(crate::rigid::cpt::LOG_FILE)) {
        if let Some(svg) = cpt_log(&log) {
            save(CPT_PLOT, svg)?;
            written.push(CPT_PLOT);
        }
    }
    Ok((written, skipped))
}

/// The piezocone's three readings against depth, as a CPT log is read: q_t, f_s, and u2
/// with the hydrostatic u0, side by side, depth down; `None` without a row.
fn cpt_log(log: &History) -> Option<String> {
    let depth = log.column("depth")?;
    if depth.iter().all(|d| !d.is_finite()) {
        return None;
    }
    let kpa = |name: &str| {
        log.column(name)
            .map(|c| c.iter().map(|v| v / 1e3).collect::<Vec<f64>>())
    };
    // Each panel: its axis label and its series (values in kPa, name).
    type Series = (Vec<f64>, &'static str);
    let panels: [(&str, Vec<Series>); 3] = [
        ("q_t (kPa)", vec![(kpa("q_t")?, "q_t")]),
        ("f_s (kPa)", vec![(kpa("f_s")?, "f_s")]),
        ("u (kPa)", vec![(kpa("u2")?, "u2"), (kpa("u0")?, "u0")]),
    ];
    let deepest = depth
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(0.0f64, f64::max);
    Some(svg((1200, 700), |root| {
        let root = root.titled("Piezocone log (static states)", ("sans-serif", 22))?;
        for (area, (label, series)) in root.split_evenly((1, 3)).iter().zip(&panels) {
            let (lo, hi) = (series.iter().flat_map(|s| s.0.iter()))
                .filter(|v| v.is_finite())
                .fold((0.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
            let pad = 0.05 * (hi - lo).max(1e-30);
            let mut c = ChartBuilder::on(area)
                .margin(15)
                .x_label_area_size(45)
                .y_label_area_size(60)
                .build_cartesian_2d((lo - pad)..(hi + pad), (deepest * 1.05).max(1e-30)..0.0)?;
            // Five labels, with a decimal where the panel spans less than 20 kPa.
            let decimals = if hi - lo < 20.0 { 1 } else { 0 };
            c.configure_mesh()
                .x_labels(5)
                .x_label_formatter(&|v| format!("{v:.decimals$}"))
                .x_desc(*label)
                .y_desc("depth of the apex (m)")
                .label_style(("sans-serif", 15))
                .draw()?;
            for (k, (values, name)) in series.iter().enumerate() {
                let colour = Palette99::pick(k).to_rgba();
                let pts: Vec<(f64, f64)> = (values.iter().zip(&depth))
                    .filter(|(v, d)| v.is_finite() && d.is_finite())
                    .map(|(v, d)| (*v, *d))
                    .collect();
                c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
                    .label(*name)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
                    });
                c.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
            }
            c.configure_series_labels()
                // At the top, above the first reading (the apex starts below the surface).
                .position(SeriesLabelPosition::UpperRight)
                .border_style(BLACK)
                .background_style(WHITE.mix(0.9))
                .label_font(("sans-serif", 14))
                .draw()?;
        }
        Ok(())
    }))
}

/// Each motion's static states: pressure (or force) against displacement.
fn curve_plot(names: &[String], u: &[f64], y: &[f64], label: &str) -> String {
    svg((960, 600), |root| {
        let hi_u = u.iter().copied().fold(0.0f64, f64::max).max(1e-30);
        let (lo, hi) = y
            .iter()
            .filter(|v| v.is_finite())
            .fold((0.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        let pad = 0.05 * (hi - lo).max(1e-30);
        let mut c = ChartBuilder::on(&root)
            .caption("Load against displacement (static states)", ("sans-serif", 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(0.0..hi_u * 1.05, (lo - pad)..(hi + pad))?;
        c.configure_mesh()
            .x_desc("displacement along the motion (m)")
            .y_desc(label)
            .y_label_formatter(&|v| format!("{v:.3e}"))
            .label_style(("sans-serif", 15))
            .draw()?;
        let mut seen: Vec<&String> = Vec::new();
        for n in names {
            if !seen.contains(&n) {
                seen.push(n);
            }
        }
        for (k, name) in seen.into_iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
                .chain(
                    names
                        .iter()
                        .zip(u.iter().zip(y))
                        .filter(|p| p.0 == name && p.1 .1.is_finite())
                        .map(|(_, (a, b))| (*a, *b)),
                )
                .collect();
            // A part without an area has no pressure: no line.
            if pts.len() < 2 {
                continue;
            }
            c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            c.draw_series(
                pts.into_iter()
                    .skip(1)
                    .map(|p| Circle::new(p, 4, colour.filled())),
            )?;
        }
        c.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    })
}

/// The lower and upper ends of a log axis through the positive finite values of `v`, with
/// a factor of 2 of room each side. The ends stay normal, finite numbers (a value near
/// f64::MAX doubled would be infinite, and a log axis to infinity is never drawn), and the
/// axis spans at most [`MAX_DECADES`] decades below its top: smaller values sit on its
/// floor.
pub(crate) fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if !lo.is_finite() {
        return (1e-12, 1.0);
    }
    let top = if hi < f64::MAX / 2.0 { hi * 2.0 } else { f64::MAX };
    let floor = (top * 10f64.powi(-MAX_DECADES)).max(f64::MIN_POSITIVE);
    ((lo / 2.0).max(floor), top)
}

/// The most decades a log axis spans.
const MAX_DECADES: i32 = 40;

/// A chart with a linear x axis and a log y axis.
pub(crate) type LogChart<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::combinators::LogCoord<f64>>,
>;

/// The house style of a log chart: its caption, a linear x axis over `x` and a log y axis
/// over `y` (from [`log_range`]), each with its label, ticks as powers of ten, and
/// `y_labels` pixels for the y labels; the mesh is drawn.
pub(crate) fn log_chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    caption: &str,
    x: (std::ops::Range<f64>, &str),
    y: ((f64, f64), &str),
    y_labels: u32,
) -> Result<LogChart<'a, 'b>> {
    let ((y0, y1), y_desc) = y;
    let mut c = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(y_labels)
        .build_cartesian_2d(x.0, (y0..y1).log_scale())?;
    c.configure_mesh()
        .x_desc(x.1)
        .y_desc(y_desc)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 15))
        .draw()?;
    Ok(c)
}

fn time_range(t: &[f64]) -> (f64, f64) {
    let hi = t.iter().copied().filter(|x| x.is_finite()).fold(0.0f64, f64::max);
    (0.0, if hi > 0.0 { hi } else { 1.0 })
}

type Result<T> = std::result::Result<T, Box<dyn std::error::Error>>;

/// Runs a drawing into an SVG string; a drawing error leaves what was drawn.
fn svg(
    size: (u32, u32),
    f: impl FnOnce(DrawingArea<SVGBackend, plotters::coord::Shift>) -> Result<()>,
) -> String {
    let mut s = String::new();
    {
        let root = SVGBackend::with_string(&mut s, size).into_drawing_area();
        let _ = root.fill(&WHITE);
        let _ = f(root);
    }
    s
}

/// Kinetic energy against time on a log scale, each reset marked where the count rises.
fn kinetic_energy(t: &[f64], ke: &[f64], resets: &[f64]) -> String {
    svg((960, 600), |root| {
        let (y0, y1) = log_range(ke.iter().copied());
        let (x0, x1) = time_range(t);
        let mut c = log_chart(
            &root,
            "Kinetic energy (velocities reset at each peak)",
            (x0..x1, "simulated time t (s)"),
            ((y0, y1), "kinetic energy E_k (J)"),
            80,
        )?;
        let pts: Vec<(f64, f64)> = t
            .iter()
            .zip(ke)
            .filter(|p| *p.1 > 0.0 && p.1.is_finite())
            .map(|(a, b)| (*a, *b))
            .collect();
        c.draw_series(LineSeries::new(pts, BLUE.stroke_width(2)))?
            .label("E_k")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        let marks: Vec<f64> = (1..resets.len())
            .filter(|&k| resets[k] > resets[k - 1])
            .map(|k| t[k])
            .collect();
        c.draw_series(
            marks
                .iter()
                .map(|&x| PathElement::new(vec![(x, y0), (x, y1)], RED.mix(0.35))),
        )?
        .label(format!("reset ({} rows with one)", marks.len()))
        .legend(|(x, y)| PathElement::new(vec![(x, y - 8), (x, y + 8)], RED));
        c.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    })
}

/// K_F and K_E against time on a log scale, with the tolerance.
fn ratios(t: &[f64], kf: &[f64], ke: &[f64], tolerance: Option<f64>) -> String {
    svg((960, 600), |root| {
        let (y0, y1) = log_range(kf.iter().chain(ke).copied().chain(tolerance));
        let (x0, x1) = time_range(t);
        let mut c = log_chart(
            &root,
            "Convergence: force ratio K_F and energy ratio K_E",
            (x0..x1, "simulated time t (s)"),
            ((y0, y1), "ratio (dimensionless)"),
            80,
        )?;
        let series = |v: &[f64]| -> Vec<(f64, f64)> {
            t.iter()
                .zip(v)
                .filter(|p| *p.1 > 0.0 && p.1.is_finite())
                .map(|(a, b)| (*a, *b))
                .collect()
        };
        c.draw_series(LineSeries::new(series(kf), BLUE.stroke_width(2)))?
            .label("K_F (max norm, eq. 3)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        c.draw_series(LineSeries::new(series(ke), GREEN.stroke_width(2)))?
            .label("K_E (eq. 4)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], GREEN.stroke_width(2)));
        if let Some(tol) = tolerance {
            c.draw_series(LineSeries::new(vec![(x0, tol), (x1, tol)], RED.stroke_width(2)))?
                .label(format!("tolerance {tol:e}"))
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        }
        c.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    })
}

/// Each traced point's displacement components against time.
fn traced_plot(t: &[f64], traced: &[(String, Vec<f64>)]) -> String {
    svg((960, 600), |root| {
        let all = traced
            .iter()
            .flat_map(|(_, v)| v.iter().copied())
            .filter(|v| v.is_finite());
        let (lo, hi) = all.fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        let pad = 0.05 * (hi - lo).max(1e-30);
        let (x0, x1) = time_range(t);
        let mut c = ChartBuilder::on(&root)
            .caption("Traced points: displacement against time", ("sans-serif", 22))
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(x0..x1, (lo - pad)..(hi + pad))?;
        c.configure_mesh()
            .x_desc("simulated time t (s)")
            .y_desc("displacement (m)")
            .y_label_formatter(&|v| format!("{v:.3e}"))
            .label_style(("sans-serif", 15))
            .draw()?;
        for (k, (name, v)) in traced.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64)> = t
                .iter()
                .zip(v)
                .filter(|p| p.1.is_finite())
                .map(|(a, b)| (*a, *b))
                .collect();
            c.draw_series(LineSeries::new(pts, colour.stroke_width(2)))?
                .label(name.replace("_u", " u_"))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        }
        c.configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE.mix(0.9))
            .label_font(("sans-serif", 14))
            .draw()?;
        Ok(())
    })
}

/// A colour for a value in [0, 1]: dark blue through green to yellow.
fn colour(s: f64) -> RGBColor {
    let s = s.clamp(0.0, 1.0);
    let stops = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let x = s * (stops.len() - 1) as f64;
    let k = (x.floor() as usize).min(stops.len() - 2);
    let f = x - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    let m = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    RGBColor(m(a.0, b.0), m(a.1, b.1), m(a.2, b.2))
}

/// The final points at their deformed positions (x, y), coloured by |u|, with a colour bar.
fn field(sample: &FieldSample) -> String {
    let every = sample.every;
    svg((1100, 620), |root| {
        let (main, bar) = root.split_horizontally(980);
        let top = sample.top.max(1e-300);
        let [xl, xh, yl, yh] = sample.bounds;
        let caption = if every > 1 {
            format!("Displacement magnitude |u| on the deformed points (one in {every} drawn)")
        } else {
            "Displacement magnitude |u| on the deformed points".to_string()
        };
        let main = main.titled(&caption, ("sans-serif", 22))?;
        // One metre is as many pixels along x as along y, so that a slope's final angle
        // looks like its angle: the shorter extent is widened to the plot's aspect.
        let (margin, y_labels, x_labels) = (20u32, 70u32, 50u32);
        let (w, h) = main.dim_in_pixel();
        let plot_w = w.saturating_sub(2 * margin + y_labels).max(1) as f64;
        let plot_h = h.saturating_sub(2 * margin + x_labels).max(1) as f64;
        let pad = 0.03 * (xh - xl).max(yh - yl).max(1e-9);
        let (span_x, span_y) = (xh - xl + 2.0 * pad, yh - yl + 2.0 * pad);
        let per_pixel = (span_x / plot_w).max(span_y / plot_h);
        let (cx, cy) = (0.5 * (xl + xh), 0.5 * (yl + yh));
        let (hx, hy) = (0.5 * per_pixel * plot_w, 0.5 * per_pixel * plot_h);
        let mut c = ChartBuilder::on(&main)
            .margin(margin)
            .x_label_area_size(x_labels)
            .y_label_area_size(y_labels)
            .build_cartesian_2d((cx - hx)..(cx + hx), (cy - hy)..(cy + hy))?;
        c.configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(("sans-serif", 15))
            .disable_mesh()
            .draw()?;
        c.draw_series(
            (sample.drawn.iter()).map(|(p, m)| Circle::new((p[0], p[1]), 2, colour(m / top).filled())),
        )?;
        // The colour bar: |u| from 0 to its maximum.
        let mut b = ChartBuilder::on(&bar)
            .margin_top(60)
            .margin_bottom(70)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, 0.0..top)?;
        b.configure_mesh()
            .disable_x_axis()
            .disable_mesh()
            .y_desc("|u| (m)")
            .y_label_formatter(&|v| format!("{v:.2}"))
            .label_style(("sans-serif", 13))
            .draw()?;
        let n = 100;
        b.draw_series((0..n).map(|k| {
            let (a, z) = (top * k as f64 / n as f64, top * (k + 1) as f64 / n as f64);
            Rectangle::new([(0.0, a), (1.0, z)], colour((k as f64 + 0.5) / n as f64).filled())
        }))?;
        Ok(())
    })
}
