//! The study file: a base scene, the settings axes to vary, how to combine them and what
//! accuracy means. Parsed and checked with the same `file:line:col` messages as scenes;
//! every run it describes is built and validated before the first one starts.

use crate::error::SceneError;
use crate::scene::{self, locate, LoadedScene};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A study as written in its RON file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Study")]
pub struct StudySpec {
    /// The base scene, relative to the study file.
    pub scene: PathBuf,
    /// Overrides (`path=value`, as `--set`) applied to every run before the axes.
    #[serde(default)]
    pub set: Vec<String>,
    /// The settings varied.
    pub axes: Vec<Axis>,
    /// How the axes' values are combined into runs.
    #[serde(default)]
    pub combine: Combine,
    /// Overrides of the reference run, run first, against which `Reference` quantities
    /// are compared.
    #[serde(default)]
    pub reference: Option<Vec<String>>,
    /// What is measured in each run and what it is compared with.
    pub quantities: Vec<QuantitySpec>,
    /// Wall-clock seconds after which a run is stopped and recorded as `timeout`.
    #[serde(default)]
    pub run_limit: Option<f64>,
}

/// One varied setting.
#[derive(Clone, Debug, Deserialize)]
pub enum Axis {
    /// Any scene field, as with `--set path=value`; the values are RON text.
    Set {
        /// Dotted field path, e.g. `solver.time_step`.
        path: String,
        /// The values taken, as RON text, e.g. `"Courant(0.5)"`.
        values: Vec<String>,
    },
    /// Grid refinement: `grid.cell_size` divided and `grid.cells` multiplied by each
    /// factor, so the domain stays the same.
    Refine(Vec<u32>),
}

impl Axis {
    /// The axis' name in tables and file headers.
    pub fn name(&self) -> String {
        match self {
            Axis::Set { path, .. } => path.clone(),
            Axis::Refine(_) => "refine".into(),
        }
    }

    /// The values as text.
    pub fn values(&self) -> Vec<String> {
        match self {
            Axis::Set { values, .. } => values.clone(),
            Axis::Refine(f) => f.iter().map(u32::to_string).collect(),
        }
    }
}

/// How axes combine.
#[derive(Clone, Debug, Default, Deserialize)]
pub enum Combine {
    /// Every combination of every axis' values.
    #[default]
    Product,
    /// Only the combinations listed, one value per axis in axis order; each value must be
    /// one of its axis' values.
    Listed(Vec<Vec<String>>),
}

/// A measured quantity.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuantitySpec {
    /// Its name in the table (a column `error <name>`).
    pub name: String,
    /// What is read from the run's `summary.json`.
    pub of: Quantity,
    /// What it is compared with.
    pub compare: Compare,
}

/// A value read from `summary.json`.
#[derive(Clone, Debug, Deserialize)]
pub enum Quantity {
    /// A traced point's displacement component (m; 0 = x).
    Displacement {
        /// The traced point's name.
        point: String,
        /// Component index.
        component: usize,
    },
    /// A traced point's stress component (Pa; `xx`, `yy`, `zz`, `xy`, `yz`, `zx`).
    Stress {
        /// The traced point's name.
        point: String,
        /// Component name.
        component: String,
    },
    /// The failed surface's angle (degrees; needs `output.surface_angle`).
    SurfaceAngle,
    /// The largest point displacement (m).
    MaxDisplacement,
    /// The simulated time at which the run stopped (s).
    StopTime,
    /// The limit pressure of the scene's motions (Pa; needs a motion with a loaded `area`).
    LimitPressure,
    /// The mean pressure of `curve.csv`'s rows named `name` (a motion, a rigid body, or a
    /// body's part as `body.part`, with an `area`) whose displacement is at least `from`
    /// (m): a penetrometer's steady resistance, where the largest would be one state's
    /// swing.
    MeanPressure {
        /// The rows' name.
        name: String,
        /// The displacement from which rows count (m, ≥ 0).
        from: f64,
    },
    /// The factor of safety by strength reduction (needs `strength_reduction`): each run
    /// is a `kdmpm fos` analysis, so a study of it measures nothing else.
    FactorOfSafety,
}

/// The value a quantity is compared with.
#[derive(Clone, Debug, Deserialize)]
pub enum Compare {
    /// A fixed analytic value, in the quantity's unit.
    Analytic(f64),
    /// An analytic field evaluated at the traced point's initial position:
    /// Σ_k c_k x_axis^k (e.g. the self-weight column's stress, linear in height).
    Polynomial {
        /// The coordinate the polynomial is in (0 = x).
        axis: usize,
        /// c_0, c_1, ...
        coefficients: Vec<f64>,
    },
    /// The same quantity in the reference run.
    Reference,
}

const STRESS_COMPONENTS: [&str; 6] = ["xx", "yy", "zz", "xy", "yz", "zx"];

/// One run of a study: its id (its directory's name) and its overrides.
#[derive(Clone, Debug, PartialEq)]
pub struct Planned {
    /// Directory name under the study's output directory.
    pub id: String,
    /// One value (as text) per axis; empty for the reference run.
    pub values: Vec<String>,
    /// Every `--set` override of the run, the study's own first.
    pub overrides: Vec<String>,
    /// The rule its scene breaks, when validation refuses it (the run is a row, not run).
    pub refused: Option<String>,
}

/// A study read from its file and checked, with every run planned.
#[derive(Clone, Debug)]
pub struct Study {
    /// The study file.
    pub path: PathBuf,
    /// Its contents.
    pub spec: StudySpec,
    /// The base scene's path (resolved against the study file's folder).
    pub scene: PathBuf,
    /// The reference run, when there is one.
    pub reference: Option<Planned>,
    /// The runs, in order.
    pub runs: Vec<Planned>,
}

impl Study {
    /// The `kdmpm` command each run is: `fos` for a study of the factor of safety, `run`
    /// otherwise.
    pub fn command(&self) -> &'static str {
        match self.spec.quantities.first().map(|q| &q.of) {
            Some(Quantity::FactorOfSafety) => "fos",
            _ => "run",
        }
    }

    /// Reads, parses and checks a study file, and builds and validates every run's scene.
    pub fn from_file(path: &Path) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_text(path, &text)
    }

    /// Parses study text; `path` names it in messages and anchors the scene path.
    pub fn from_text(path: &Path, text: &str) -> Result<Self, SceneError> {
        let spec = parse(path, text)?;
        let at = Place { path, text };
        let scene_path = path.parent().unwrap_or(Path::new("")).join(&spec.scene);
        let base = LoadedScene::from_file(&scene_path, &spec.set)
            .map_err(|e| at.invalid("scene", format!("the base scene with the study's `set`: {e}")))?;
        check_axes(&spec, &at)?;
        let combos = combinations(&spec, &at)?;
        let mut runs = plan_runs(&spec, &scene_path, combos, &at)?;
        let mut reference = spec.reference.as_ref().map(|r| Planned {
            id: "reference".into(),
            values: Vec::new(),
            overrides: spec.set.iter().chain(r).cloned().collect(),
            refused: None,
        });
        check_runs(&scene_path, reference.as_mut(), &mut runs, &at)?;
        check_quantities(&spec, &base, reference.is_some(), &at)?;
        Ok(Study {
            path: path.to_path_buf(),
            scene: scene_path,
            spec,
            reference,
            runs,
        })
    }
}

/// Where a study file's rules are checked: its path and text, to place an error.
struct Place<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Place<'_> {
    /// The error for `field` of the study file, breaking `rule`.
    fn invalid(&self, field: &str, rule: String) -> SceneError {
        let (line, column) = locate::field_position(self.text, field).unwrap_or((0, 0));
        SceneError::Invalid {
            path: self.path.to_path_buf(),
            line,
            column,
            field: field.to_string(),
            note: String::new(),
            rule,
        }
    }
}

/// The study file's RON, its syntax errors placed as a scene's are.
fn parse(path: &Path, text: &str) -> Result<StudySpec, SceneError> {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
        .from_str(text)
        .map_err(|e| {
            let message = e.code.to_string();
            let (line, column, field) = locate::parse_error_place(text, &e);
            let field = field.map_or(String::new(), |f| format!("field `{f}`: "));
            SceneError::Syntax {
                path: path.to_path_buf(),
                line,
                column,
                field,
                message,
            }
        })
}

/// The axes: at least one, each with values, refinement factors ≥ 1, none varied twice;
/// and the run limit.
fn check_axes(spec: &StudySpec, at: &Place) -> Result<(), SceneError> {
    if spec.axes.is_empty() {
        return Err(at.invalid("axes", "a study varies at least one setting".into()));
    }
    for (i, axis) in spec.axes.iter().enumerate() {
        let values = axis.values();
        if values.is_empty() {
            return Err(at.invalid(&format!("axes[{i}]"), "an axis needs at least one value".into()));
        }
        if let Axis::Refine(f) = axis {
            if f.contains(&0) {
                return Err(at.invalid(&format!("axes[{i}]"), "refinement factors are ≥ 1".into()));
            }
        }
        if spec.axes[..i].iter().any(|a| a.name() == axis.name()) {
            return Err(at.invalid(
                &format!("axes[{i}]"),
                format!("`{}` is varied by an earlier axis", axis.name()),
            ));
        }
    }
    if let Some(limit) = spec.run_limit {
        if !(limit.is_finite() && limit > 0.0) {
            return Err(at.invalid(
                "run_limit",
                format!("must be a positive number of seconds, found {limit}"),
            ));
        }
    }
    Ok(())
}

/// The combinations of axis values to run: every one, or the listed ones (each a value of
/// its axis).
fn combinations(spec: &StudySpec, at: &Place) -> Result<Vec<Vec<String>>, SceneError> {
    let combos: Vec<Vec<String>> = match &spec.combine {
        Combine::Product => product(&spec.axes),
        Combine::Listed(list) => {
            for (k, combo) in list.iter().enumerate() {
                let field = format!("combine[{k}]");
                if combo.len() != spec.axes.len() {
                    return Err(at.invalid(
                        &field,
                        format!("lists {} values for {} axes", combo.len(), spec.axes.len()),
                    ));
                }
                for (v, axis) in combo.iter().zip(&spec.axes) {
                    if !axis.values().contains(v) {
                        return Err(
                            at.invalid(&field, format!("`{v}` is not a value of axis `{}`", axis.name()))
                        );
                    }
                }
            }
            list.clone()
        }
    };
    if combos.is_empty() {
        return Err(at.invalid("combine", "the study has no run".into()));
    }
    Ok(combos)
}

/// One planned run a combination: the study's `set` and each axis's overrides; a `Refine`
/// factor last, as `--refine` makes its finer scenes ([`crate::refine::finer_overrides`])
/// from the scene the other axes set.
fn plan_runs(
    spec: &StudySpec,
    scene_path: &Path,
    combos: Vec<Vec<String>>,
    at: &Place,
) -> Result<Vec<Planned>, SceneError> {
    let mut runs = Vec::with_capacity(combos.len());
    for (k, values) in combos.into_iter().enumerate() {
        let mut overrides = spec.set.clone();
        let mut ratio = 1;
        for (i, (axis, v)) in spec.axes.iter().zip(&values).enumerate() {
            match axis {
                Axis::Set { path, .. } => overrides.push(format!("{path}={v}")),
                Axis::Refine(_) => {
                    ratio = v
                        .parse()
                        .map_err(|_| at.invalid(&format!("axes[{i}]"), format!("`{v}` is not a factor")))?
                }
            }
        }
        if ratio > 1 {
            let with = LoadedScene::from_file(scene_path, &overrides)
                .map_err(|e| at.invalid("axes", format!("run {} with {}: {e}", k + 1, values.join(", "))))?;
            overrides.extend(crate::refine::finer_overrides(&with.scene, ratio));
        }
        runs.push(Planned {
            id: format!("run-{:03}", k + 1),
            values,
            overrides,
            refused: None,
        });
    }
    Ok(runs)
}

/// Every run's overrides must apply and parse: a typo is reported now, at the axis that set
/// it, rather than as a failed row an hour later. A scene that parses but breaks a rule (a
/// Courant number above a scheme's limit, say) is a row: studies map limits. The reference
/// must be valid.
fn check_runs(
    scene_path: &Path,
    reference: Option<&mut Planned>,
    runs: &mut [Planned],
    at: &Place,
) -> Result<(), SceneError> {
    for run in reference.into_iter().chain(runs.iter_mut()) {
        let field = if run.id == "reference" {
            "reference"
        } else {
            "axes"
        };
        let with = if run.values.is_empty() {
            String::new()
        } else {
            format!(" with {}", run.values.join(", "))
        };
        let loaded = LoadedScene::from_file(scene_path, &run.overrides)
            .map_err(|e| at.invalid(field, format!("run {}{with}: {e}", run.id)))?;
        if let Err(e) = scene::check(&loaded) {
            if run.id == "reference" {
                return Err(at.invalid(field, format!("the reference run: {e}")));
            }
            run.refused = Some(e.to_string());
        }
    }
    Ok(())
}

/// The quantities: at least one, each of a traced point or a measured figure of the scene,
/// compared with something that exists, each name once.
fn check_quantities(
    spec: &StudySpec,
    base: &LoadedScene,
    has_reference: bool,
    at: &Place,
) -> Result<(), SceneError> {
    let traced: Vec<&str> = base.scene.traced.iter().map(|t| t.name.as_str()).collect();
    let dim = base.scene.dimension.axes();
    if spec.quantities.is_empty() {
        return Err(at.invalid("quantities", "a study measures at least one quantity".into()));
    }
    for (k, q) in spec.quantities.iter().enumerate() {
        let field = format!("quantities[{k}]");
        match &q.of {
            Quantity::Displacement { point, component } => {
                if !traced.contains(&point.as_str()) {
                    return Err(at.invalid(&field, format!("the scene traces no point `{point}`")));
                }
                if *component >= dim {
                    return Err(at.invalid(&field, format!("component {component} of a {dim}D displacement")));
                }
            }
            Quantity::Stress { point, component } => {
                if !traced.contains(&point.as_str()) {
                    return Err(at.invalid(&field, format!("the scene traces no point `{point}`")));
                }
                if !STRESS_COMPONENTS.contains(&component.as_str()) {
                    return Err(at.invalid(
                        &field,
                        format!("stress component `{component}` is none of xx yy zz xy yz zx"),
                    ));
                }
            }
            Quantity::SurfaceAngle if !base.scene.output.surface_angle => {
                return Err(at.invalid(
                    &field,
                    "the scene does not measure the surface angle (output.surface_angle)".into(),
                ));
            }
            Quantity::FactorOfSafety if base.scene.strength_reduction.is_none() => {
                return Err(at.invalid(
                    &field,
                    "the scene has no `strength_reduction`: no factor of safety".into(),
                ));
            }
            Quantity::MeanPressure { name, from } => {
                if let Some(rule) = base.scene.pressure_window_fault(name, *from) {
                    return Err(at.invalid(&field, rule));
                }
            }
            Quantity::LimitPressure if !base.scene.has_limit_pressure() => {
                return Err(at.invalid(
                    &field,
                    "the scene has no motion with a loaded `area`: no limit pressure".into(),
                ));
            }
            _ => {}
        }
        match &q.compare {
            Compare::Analytic(v) if !(v.is_finite() && *v != 0.0) => {
                return Err(at.invalid(
                    &field,
                    format!("an analytic value must be finite and non-zero for a relative error, found {v}"),
                ));
            }
            Compare::Polynomial { axis, coefficients } => {
                if *axis >= dim || coefficients.is_empty() || coefficients.iter().any(|c| !c.is_finite()) {
                    return Err(at.invalid(
                        &field,
                        "a polynomial needs a coordinate axis of the scene and finite coefficients".into(),
                    ));
                }
                if !matches!(q.of, Quantity::Displacement { .. } | Quantity::Stress { .. }) {
                    return Err(at.invalid(
                        &field,
                        "a polynomial is evaluated at a traced point: use it with Displacement or Stress"
                            .into(),
                    ));
                }
            }
            Compare::Reference if !has_reference => {
                return Err(at.invalid(
                    &field,
                    "compares with the reference run, but the study names none (`reference`)".into(),
                ));
            }
            _ => {}
        }
        let analysis = |q: &QuantitySpec| matches!(q.of, Quantity::FactorOfSafety);
        if analysis(q) != analysis(&spec.quantities[0]) {
            return Err(at.invalid(
                &field,
                "a factor of safety is the answer of a whole strength reduction (`kdmpm fos`), not \
                 of one run: a study of it measures nothing else"
                    .into(),
            ));
        }
        if spec.quantities[..k].iter().any(|p| p.name == q.name) {
            return Err(at.invalid(&field, format!("the name `{}` is used twice", q.name)));
        }
    }
    Ok(())
}

/// Every combination of the axes' values, the last axis varying fastest.
fn product(axes: &[Axis]) -> Vec<Vec<String>> {
    axes.iter().fold(vec![Vec::new()], |acc, axis| {
        acc.iter()
            .flat_map(|prefix| {
                axis.values().into_iter().map(move |v| {
                    let mut next = prefix.clone();
                    next.push(v);
                    next
                })
            })
            .collect()
    })
}

/// The value of `q` in a run's summary, and the traced point's initial position when the
/// quantity belongs to one. `None` when the run did not produce it.
pub fn read(q: &Quantity, summary: &serde_json::Value) -> Option<(f64, Option<[f64; 3]>)> {
    let traced = |name: &str| {
        summary["traced"]
            .as_array()?
            .iter()
            .find(|t| t["name"].as_str() == Some(name))
    };
    let initial = |t: &serde_json::Value| {
        let p = t["initial_position"].as_array()?;
        Some([p.first()?.as_f64()?, p.get(1)?.as_f64()?, p.get(2)?.as_f64()?])
    };
    match q {
        Quantity::Displacement { point, component } => {
            let t = traced(point)?;
            Some((t["displacement"][*component].as_f64()?, initial(t)))
        }
        Quantity::Stress { point, component } => {
            let t = traced(point)?;
            Some((t["stress"][component.as_str()].as_f64()?, initial(t)))
        }
        Quantity::SurfaceAngle => Some((summary["surface_angle"]["degrees"].as_f64()?, None)),
        Quantity::MaxDisplacement => Some((summary["max_displacement"].as_f64()?, None)),
        Quantity::StopTime => Some((summary["time"].as_f64()?, None)),
        Quantity::LimitPressure => Some((summary["limit_pressure"].as_f64()?, None)),
        Quantity::MeanPressure { name, from } => {
            let rows: Vec<f64> = summary["curve"]
                .as_array()?
                .iter()
                .filter(|r| {
                    r["name"] == name.as_str() && r["displacement"].as_f64().is_some_and(|d| d >= *from)
                })
                .filter_map(|r| r["pressure"].as_f64())
                .collect();
            (!rows.is_empty()).then(|| (rows.iter().sum::<f64>() / rows.len() as f64, None))
        }
        Quantity::FactorOfSafety => Some((summary["factor_of_safety"].as_f64()?, None)),
    }
}

/// The value `compare` expects of a quantity measured at `initial` (for a polynomial);
/// `reference` is the reference run's value of the same quantity.
pub fn expected(compare: &Compare, initial: Option<[f64; 3]>, reference: Option<f64>) -> Option<f64> {
    match compare {
        Compare::Analytic(v) => Some(*v),
        Compare::Polynomial { axis, coefficients } => {
            let x = initial?[*axis];
            Some(coefficients.iter().rev().fold(0.0, |acc, c| acc * x + c))
        }
        Compare::Reference => reference,
    }
}

/// Signed relative error (value − expected)/|expected|; `None` when either is missing or
/// the expected value is zero.
pub fn relative_error(value: Option<f64>, expected: Option<f64>) -> Option<f64> {
    match (value, expected) {
        (Some(v), Some(e)) if e != 0.0 && v.is_finite() && e.is_finite() => Some((v - e) / e.abs()),
        _ => None,
    }
}
