//! `pareto.svg`: each run's worst relative error against its wall time, log–log, with the
//! Pareto-optimal runs joined, marked and labelled with their settings.

use super::report::Row;
use super::spec::Study;
use plotters::prelude::*;

/// The picture as SVG text. Runs that did not stop at a static state, or lack a quantity,
/// are left out and counted in the caption; a zero error sits on the axis' floor.
pub fn pareto_svg(study: &Study, rows: &[Row], front: &[usize]) -> String {
    let mut svg = String::new();
    let points: Vec<(usize, f64, f64)> = rows
        .iter()
        .enumerate()
        .filter_map(|(k, r)| {
            r.worst_error()
                .map(|e| (k, r.wall_seconds.max(1e-3), e.max(1e-16)))
        })
        .collect();
    let left_out = rows.len() - points.len();
    let name = study
        .path
        .file_stem()
        .map_or("study".into(), |s| s.to_string_lossy().into_owned());
    let axes: Vec<String> = study.spec.axes.iter().map(|a| a.name()).collect();
    let title = format!("{name}: error against wall time");
    // Drawing into a String cannot fail for lack of space; errors here would be a bug in
    // the ranges, and leave an incomplete picture rather than stop the study.
    let _ = draw(
        &mut svg,
        &title,
        &axes.join(" | "),
        rows,
        &points,
        front,
        left_out,
    );
    svg
}

fn draw<'a>(
    svg: &'a mut String,
    title: &str,
    axes: &str,
    rows: &[Row],
    points: &[(usize, f64, f64)],
    front: &[usize],
    left_out: usize,
) -> Result<(), Box<dyn std::error::Error + 'a>> {
    let root = SVGBackend::with_string(svg, (960, 640)).into_drawing_area();
    root.fill(&WHITE)?;
    let (xs, ys): (Vec<f64>, Vec<f64>) = points.iter().map(|p| (p.1, p.2)).unzip();
    let range = |v: &[f64], default: (f64, f64)| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(0.0f64, f64::max);
        if lo.is_finite() && hi > 0.0 {
            (lo / 1.5, hi * 1.5)
        } else {
            default
        }
    };
    let (x0, x1) = range(&xs, (0.1, 100.0));
    let (y0, y1) = range(&ys, (1e-6, 1.0));
    let caption = if left_out > 0 {
        format!("{title} ({left_out} runs without a static answer not shown)")
    } else {
        title.to_string()
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("wall time of the run (s)")
        .y_desc("worst |relative error| over the quantities")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_labels(8)
        .y_labels(8)
        .light_line_style(WHITE)
        .x_label_formatter(&|v| {
            if *v >= 10.0 {
                format!("{v:.0}")
            } else if *v >= 1.0 {
                format!("{v:.1}")
            } else {
                format!("{v:.2}")
            }
        })
        .label_style(("sans-serif", 15))
        .draw()?;
    chart
        .draw_series(
            points
                .iter()
                .filter(|p| !front.contains(&p.0))
                .map(|&(_, x, y)| Circle::new((x, y), 4, RGBColor(150, 150, 150).filled())),
        )?
        .label("run")
        .legend(|(x, y)| Circle::new((x, y), 4, RGBColor(150, 150, 150).filled()));
    let front_points: Vec<(f64, f64)> = front
        .iter()
        .filter_map(|k| points.iter().find(|p| p.0 == *k).map(|p| (p.1, p.2)))
        .collect();
    chart.draw_series(LineSeries::new(front_points.clone(), RED.stroke_width(2)))?;
    chart
        .draw_series(front.iter().zip(&front_points).map(|(&k, &(x, y))| {
            EmptyElement::at((x, y))
                + Circle::new((0, 0), 6, RED.filled())
                + Text::new(rows[k].label(), (8, -16), ("sans-serif", 13))
        }))?
        .label(format!("Pareto front ({axes})"))
        .legend(|(x, y)| Circle::new((x, y), 6, RED.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .label_font(("sans-serif", 14))
        .draw()?;
    root.present()?;
    Ok(())
}
