//! A study's table: one row a run, the Pareto front of error against wall time, and the
//! observed order of convergence over a `Refine` axis.

use super::spec::{expected, read, relative_error, Axis, Compare, Study};
use super::Finished;
use std::fmt::Write;

/// The outcome of a `kdmpm fos` run that bracketed its factor of safety.
pub const BRACKETED: &str = "bracketed";

/// True when a run gave its answer: a run that stopped at a static state (`converged`), or
/// a strength reduction that bracketed its factor of safety.
pub fn answered(outcome: &str) -> bool {
    outcome == "converged" || outcome == BRACKETED
}

/// One run's figures.
#[derive(Clone, Debug)]
pub struct Row {
    /// The run's directory name.
    pub id: String,
    /// One value per axis.
    pub values: Vec<String>,
    /// Its outcome (`converged`, `max_time`, `failed`, `timeout`, ...).
    pub outcome: String,
    /// Wall-clock seconds of the whole command.
    pub wall_seconds: f64,
    /// Steps taken.
    pub steps: Option<u64>,
    /// Points × steps per second of stepping.
    pub particle_steps_per_second: Option<f64>,
    /// Peak resident memory (bytes).
    pub peak_memory_bytes: Option<u64>,
    /// Each quantity's value, in study order.
    pub quantities: Vec<Option<f64>>,
    /// Each quantity's signed relative error, in study order.
    pub errors: Vec<Option<f64>>,
}

impl Row {
    /// The row of a finished run; `reference` supplies `Reference` comparisons.
    pub fn new(study: &Study, f: &Finished, reference: Option<&Finished>) -> Self {
        let s = f.summary.as_ref();
        let mut quantities = Vec::new();
        let mut errors = Vec::new();
        for q in &study.spec.quantities {
            let measured = s.and_then(|s| read(&q.of, s));
            let reference_value = match q.compare {
                Compare::Reference => reference
                    .and_then(|r| r.summary.as_ref())
                    .and_then(|s| read(&q.of, s))
                    .map(|v| v.0),
                _ => None,
            };
            let want = measured.and_then(|(_, at)| expected(&q.compare, at, reference_value));
            let value = measured.map(|m| m.0);
            quantities.push(value);
            errors.push(relative_error(value, want));
        }
        Row {
            id: f.run.id.clone(),
            values: f.run.values.clone(),
            outcome: f.outcome.clone(),
            wall_seconds: f.wall_seconds,
            steps: s.and_then(|s| s["steps"].as_u64()),
            particle_steps_per_second: s.and_then(|s| s["particle_steps_per_second"].as_f64()),
            peak_memory_bytes: s.and_then(|s| s["peak_memory_bytes"].as_u64()),
            quantities,
            errors,
        }
    }

    /// The run's accuracy: the largest |relative error| over the quantities, when the run
    /// stopped at a static state and gave them all.
    pub fn worst_error(&self) -> Option<f64> {
        if !answered(&self.outcome) {
            return None;
        }
        self.errors
            .iter()
            .try_fold(0.0f64, |m, e| e.map(|e| m.max(e.abs())))
    }

    /// The axis values joined, for labels.
    pub fn label(&self) -> String {
        self.values.join(", ")
    }
}

fn cell(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v:.6e}"))
}

/// Quotes a CSV field when it holds a comma, quote or line break.
fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `study.csv`: the varied values, outcome, cost and each quantity's value and signed
/// relative error. A figure the run did not produce is an empty cell.
pub fn csv(study: &Study, rows: &[Row]) -> String {
    let mut out = String::from("run");
    for a in &study.spec.axes {
        let _ = write!(out, ",{}", quote(&a.name()));
    }
    out.push_str(",outcome,wall_seconds,steps,particle_steps_per_second,peak_memory_bytes");
    for q in &study.spec.quantities {
        let _ = write!(out, ",{},{}", quote(&q.name), quote(&format!("error {}", q.name)));
    }
    out.push_str(",pareto\n");
    let front = pareto_front(rows);
    for (k, r) in rows.iter().enumerate() {
        out.push_str(&r.id);
        for v in &r.values {
            let _ = write!(out, ",{}", quote(v));
        }
        let _ = write!(
            out,
            ",{},{:.3},{},{},{}",
            quote(&r.outcome),
            r.wall_seconds,
            r.steps.map_or(String::new(), |s| s.to_string()),
            r.particle_steps_per_second
                .map_or(String::new(), |v| format!("{v:.4e}")),
            r.peak_memory_bytes.map_or(String::new(), |v| v.to_string()),
        );
        for (v, e) in r.quantities.iter().zip(&r.errors) {
            let _ = write!(out, ",{},{}", cell(*v), cell(*e));
        }
        let _ = writeln!(out, ",{}", front.contains(&k));
    }
    out
}

/// Indices of the Pareto-optimal rows, fastest first: runs that stopped at a static state
/// and that no other such run beats in both wall time and worst error.
pub fn pareto_front(rows: &[Row]) -> Vec<usize> {
    let scored: Vec<(usize, f64, f64)> = rows
        .iter()
        .enumerate()
        .filter_map(|(k, r)| r.worst_error().map(|e| (k, r.wall_seconds, e)))
        .collect();
    let mut front: Vec<(usize, f64, f64)> = scored
        .iter()
        .filter(|&&(k, w, e)| {
            !scored
                .iter()
                .any(|&(j, wj, ej)| j != k && wj <= w && ej <= e && (wj < w || ej < e))
        })
        .copied()
        .collect();
    front.sort_by(|a, b| a.1.total_cmp(&b.1));
    front.into_iter().map(|f| f.0).collect()
}

/// The observed order of convergence of one quantity between two refinements.
#[derive(Clone, Debug)]
pub struct Order {
    /// The other axes' values.
    pub group: String,
    /// The quantity.
    pub quantity: String,
    /// Coarser and finer refinement factors.
    pub refine: (u32, u32),
    /// |error| at each.
    pub errors: (f64, f64),
    /// p = ln(|e₁|/|e₂|) / ln(r₂/r₁).
    pub order: f64,
}

/// Observed orders over the `Refine` axis, for quantities compared with an analytic value,
/// between successive factors with the other axes held.
pub fn convergence_orders(study: &Study, rows: &[Row]) -> Vec<Order> {
    let Some(ax) = study.spec.axes.iter().position(|a| matches!(a, Axis::Refine(_))) else {
        return Vec::new();
    };
    let mut groups: Vec<(String, Vec<(u32, &Row)>)> = Vec::new();
    for r in rows {
        let group: Vec<&str> = r
            .values
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != ax)
            .map(|(_, v)| v.as_str())
            .collect();
        let group = group.join(", ");
        let Ok(factor) = r.values[ax].parse::<u32>() else {
            continue;
        };
        match groups.iter_mut().find(|g| g.0 == group) {
            Some(g) => g.1.push((factor, r)),
            None => groups.push((group, vec![(factor, r)])),
        }
    }
    let mut orders = Vec::new();
    for (group, mut members) in groups {
        members.sort_by_key(|m| m.0);
        for (q, spec) in study.spec.quantities.iter().enumerate() {
            if matches!(spec.compare, Compare::Reference) {
                continue;
            }
            for pair in members.windows(2) {
                let ((r1, a), (r2, b)) = (pair[0], pair[1]);
                if !answered(&a.outcome) || !answered(&b.outcome) || r1 == r2 {
                    continue;
                }
                let (Some(e1), Some(e2)) = (a.errors[q], b.errors[q]) else {
                    continue;
                };
                let (e1, e2) = (e1.abs(), e2.abs());
                if e1 == 0.0 || e2 == 0.0 {
                    continue;
                }
                orders.push(Order {
                    group: group.clone(),
                    quantity: spec.name.clone(),
                    refine: (r1, r2),
                    errors: (e1, e2),
                    order: (e1 / e2).ln() / (r2 as f64 / r1 as f64).ln(),
                });
            }
        }
    }
    orders
}

/// `convergence.csv`.
pub fn orders_csv(orders: &[Order]) -> String {
    let mut out = String::from("group,quantity,refine_coarse,refine_fine,error_coarse,error_fine,order\n");
    for o in orders {
        let _ = writeln!(
            out,
            "{},{},{},{},{:.6e},{:.6e},{:.3}",
            quote(&o.group),
            quote(&o.quantity),
            o.refine.0,
            o.refine.1,
            o.errors.0,
            o.errors.1,
            o.order
        );
    }
    out
}

/// The Pareto front as a printed table.
pub fn front_table(study: &Study, rows: &[Row], front: &[usize]) -> String {
    let mut out = String::new();
    let names: Vec<String> = study.spec.axes.iter().map(Axis::name).collect();
    let _ = writeln!(out, "Pareto front (worst |relative error| against wall time):");
    let _ = writeln!(
        out,
        "  {:<8} {:>9} {:>8} {:>12}  {}",
        "run",
        "wall s",
        "steps",
        "worst error",
        names.join(" | ")
    );
    for &k in front {
        let r = &rows[k];
        let _ = writeln!(
            out,
            "  {:<8} {:>9.2} {:>8} {:>12.3e}  {}",
            r.id,
            r.wall_seconds,
            r.steps.map_or("-".into(), |s| s.to_string()),
            r.worst_error().unwrap_or(f64::INFINITY),
            r.values.join(" | ")
        );
    }
    if front.is_empty() {
        let _ = writeln!(
            out,
            "  (no run stopped at a static state with every quantity measured)"
        );
    }
    out
}

/// The observed orders as a printed table.
pub fn orders_table(orders: &[Order]) -> String {
    let mut out = String::from("Observed order of convergence in h:\n");
    for o in orders {
        let group = if o.group.is_empty() {
            String::new()
        } else {
            format!(" [{}]", o.group)
        };
        let _ = writeln!(
            out,
            "  {:<24} refine {}→{}: |e| {:.3e} → {:.3e}, order {:.2}{group}",
            o.quantity, o.refine.0, o.refine.1, o.errors.0, o.errors.1, o.order
        );
    }
    out
}
