//! Element tests: one material point driven along a laboratory path, without a grid, to
//! check a constitutive model against closed forms (`kdmpm triaxial`).
//!
//! A triaxial compression test on a sample whose axis is y: the sample starts under an
//! isotropic effective stress p′₀ (the cell pressure, with no pore pressure), its axial
//! strain is raised in equal increments, and the radial strain (x and z alike) is
//!
//! * drained: whatever keeps the radial stress at the cell pressure, found in each increment
//!   by the secant method on the material's own update (a material that holds its own
//!   undrained water, `ModifiedCamClay` with `drainage: Undrained`, then gives an undrained
//!   test with that water's stiffness: its excess pore pressure is the row's u);
//! * undrained: minus half the axial one, so the volume does not change (water and grains
//!   incompressible); the excess pore pressure is then what the radial total stress, held at
//!   the cell pressure, leaves to the water: u = p′₀ − σ′_r.
//!
//! Strains and stresses are compression positive here, as a laboratory reports them.

use crate::materials::{MaterialModel, MaterialState, StateVisitor};
use crate::tensor::Sym3;
use std::fmt;
use std::io::Write;
use std::path::Path;

/// How the sample's water behaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drainage {
    /// The water leaves freely: the radial effective stress stays at the cell pressure.
    Drained,
    /// No water leaves: the volume stays as it was.
    Undrained,
}

/// A triaxial compression test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triaxial {
    /// p′₀ (Pa, > 0): the isotropic effective stress the sample starts at.
    pub cell_pressure: f64,
    /// How the water behaves.
    pub drainage: Drainage,
    /// The last axial strain (compression positive, in (0, 1]).
    pub axial_strain: f64,
    /// The number of equal axial increments (≥ 1).
    pub steps: usize,
}

/// The sample after an increment (compression positive).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// ε_a, the axial strain.
    pub axial_strain: f64,
    /// ε_v = ε_a + 2ε_r, the volumetric strain.
    pub volumetric_strain: f64,
    /// p′ (Pa), the mean effective stress.
    pub mean_stress: f64,
    /// q = σ′_a − σ′_r (Pa), the deviator stress.
    pub deviator: f64,
    /// u (Pa): the excess pore pressure (the material's own when the test is drained).
    pub pore_pressure: f64,
    /// The material's state by name ([`MaterialState::fields`]).
    pub state: Vec<(&'static str, f64)>,
}

/// Why a test could not be run or finished.
#[derive(Debug, Clone, PartialEq)]
pub enum ElementError {
    /// A setting of the test breaks a rule: the setting and the rule.
    Input(&'static str, String),
    /// The sample reached a state with no physical meaning ([`MaterialState::fault`]).
    NoState {
        /// The increment (from 1).
        step: usize,
        /// Why.
        why: String,
    },
    /// The drained increment found no radial strain that holds the cell pressure.
    NoBalance {
        /// The increment (from 1).
        step: usize,
        /// The radial effective stress missed by (Pa).
        residual: f64,
    },
}

impl fmt::Display for ElementError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ElementError::Input(field, rule) => write!(f, "{field}: {rule}"),
            ElementError::NoState { step, why } => write!(
                f,
                "increment {step}: the sample reached {why}: the material has no state there"
            ),
            ElementError::NoBalance { step, residual } => write!(
                f,
                "increment {step}: no radial strain holds the cell pressure (off by {residual:e} \
                 Pa): the material has no drained state there"
            ),
        }
    }
}

impl std::error::Error for ElementError {}

impl Triaxial {
    /// The test's settings checked.
    fn check(&self) -> Result<(), ElementError> {
        if !(self.cell_pressure > 0.0 && self.cell_pressure.is_finite()) {
            return Err(ElementError::Input(
                "cell_pressure",
                format!("must be > 0 Pa, found {}", self.cell_pressure),
            ));
        }
        if !(self.axial_strain > 0.0 && self.axial_strain <= 1.0) {
            return Err(ElementError::Input(
                "axial_strain",
                format!("must be in (0, 1], found {}", self.axial_strain),
            ));
        }
        if self.steps == 0 {
            return Err(ElementError::Input("steps", "must be at least 1".into()));
        }
        Ok(())
    }
}

/// Runs `test` on `model`: the start and a row after every increment.
pub fn triaxial(model: &MaterialModel, test: &Triaxial) -> Result<Vec<Row>, ElementError> {
    test.check()?;
    let radial = match test.drainage {
        Drainage::Drained => Radial::Balanced,
        Drainage::Undrained => Radial::Isochoric,
    };
    with_state(model, test, radial)
}

/// One-dimensional compression (an oedometer): the sample starts under an isotropic
/// effective stress `p0` (Pa) and its axial (y) strain is raised to `axial_strain` in `steps`
/// equal increments with no radial strain; rows as [`triaxial`]'s (u the material's own,
/// ε_v = ε_a).
pub fn oedometer(
    model: &MaterialModel,
    p0: f64,
    axial_strain: f64,
    steps: usize,
) -> Result<Vec<Row>, ElementError> {
    let test = Triaxial {
        cell_pressure: p0,
        drainage: Drainage::Drained,
        axial_strain,
        steps,
    };
    test.check()?;
    with_state(model, &test, Radial::Fixed)
}

/// What each increment's radial strain is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Radial {
    /// Whatever holds the radial stress at the cell pressure.
    Balanced,
    /// Minus half the axial strain: no volume change.
    Isochoric,
    /// None.
    Fixed,
}

/// [`run`] with the state type of `model`.
fn with_state(model: &MaterialModel, test: &Triaxial, radial: Radial) -> Result<Vec<Row>, ElementError> {
    struct Run<'a>(
        &'a MaterialModel,
        &'a Triaxial,
        Radial,
        Option<Result<Vec<Row>, ElementError>>,
    );
    impl StateVisitor for Run<'_> {
        fn visit<S: MaterialState>(&mut self) {
            self.3 = Some(run::<S>(self.0, self.1, self.2));
        }
    }
    let mut r = Run(model, test, radial, None);
    model.visit_state(&mut r);
    r.3.expect("every model has a state type")
}

/// The row of a sample at `stress` (tension positive; σ′ − u I for a material that holds
/// undrained water) and strains `ea`, `ev`.
fn row<S: MaterialState>(test: &Triaxial, stress: &Sym3, state: &S, ea: f64, ev: f64) -> Row {
    let u = state.excess_pore_pressure();
    let (sa, sr) = (-stress.yy - u, -stress.xx - u);
    Row {
        axial_strain: ea,
        volumetric_strain: ev,
        mean_stress: (sa + 2.0 * sr) / 3.0,
        deviator: sa - sr,
        pore_pressure: match test.drainage {
            Drainage::Drained => u,
            Drainage::Undrained => test.cell_pressure - sr,
        },
        state: state.fields(),
    }
}

fn run<S: MaterialState>(
    model: &MaterialModel,
    test: &Triaxial,
    radial: Radial,
) -> Result<Vec<Row>, ElementError> {
    let p0 = test.cell_pressure;
    let mut stress = Sym3::diagonal(-p0, -p0, -p0);
    let mut state = S::default();
    // A zero increment starts a state that is set from the first stress.
    model.update(&mut stress, &Sym3::ZERO, &mut state);
    if let Some(why) = state.fault() {
        return Err(ElementError::Input(
            "cell_pressure",
            format!("the sample starts at {p0:e} Pa with {why}"),
        ));
    }
    let de_a = test.axial_strain / test.steps as f64;
    let (mut ea, mut ev) = (0.0, 0.0);
    let mut rows = vec![row(test, &stress, &state, ea, ev)];
    // The last increment's radial over axial strain (tension positive): the first guess of
    // the next.
    let mut ratio = 0.3;
    for step in 1..=test.steps {
        let de_r = match radial {
            Radial::Fixed => 0.0,
            Radial::Isochoric => 0.5 * de_a,
            Radial::Balanced => {
                let radial = |de_r: f64| {
                    let (mut s, mut st) = (stress, state);
                    model.update(&mut s, &Sym3::diagonal(de_r, -de_a, de_r), &mut st);
                    s.xx + p0
                };
                balance(radial, ratio * de_a, de_a, p0)
                    .map_err(|residual| ElementError::NoBalance { step, residual })?
            }
        };
        ratio = de_r / de_a;
        model.update(&mut stress, &Sym3::diagonal(de_r, -de_a, de_r), &mut state);
        ea += de_a;
        ev += de_a - 2.0 * de_r;
        rows.push(row(test, &stress, &state, ea, ev));
        if let Some(why) = state.fault() {
            return Err(ElementError::NoState { step, why });
        }
    }
    Ok(rows)
}

/// The radial strain increment x with |f(x)| ≤ 1e-10 p′₀ (Pa), by the secant method from
/// `guess`; `scale` is the axial increment. Err: the smallest residual reached.
fn balance(f: impl Fn(f64) -> f64, guess: f64, scale: f64, p0: f64) -> Result<f64, f64> {
    let tolerance = 1e-10 * p0;
    let (mut x0, mut x1) = (guess, guess + 1e-3 * scale);
    let (mut f0, mut f1) = (f(x0), f(x1));
    let mut best = if f0.abs() < f1.abs() { (x0, f0) } else { (x1, f1) };
    for _ in 0..100 {
        if best.1.abs() <= tolerance {
            return Ok(best.0);
        }
        if f1 == f0 {
            break;
        }
        let x2 = x1 - f1 * (x1 - x0) / (f1 - f0);
        (x0, f0) = (x1, f1);
        x1 = x2;
        f1 = f(x1);
        if !f1.is_finite() {
            break;
        }
        if f1.abs() < best.1.abs() {
            best = (x1, f1);
        }
    }
    if best.1.abs() <= tolerance {
        Ok(best.0)
    } else {
        Err(best.1.abs())
    }
}

/// Writes `rows` to `path` as CSV (whole or not at all): ε_a, ε_v, p′, q (Pa), u (Pa), then
/// the state's fields.
pub fn write_csv(rows: &[Row], path: &Path) -> std::io::Result<()> {
    crate::output::dir::write_atomic(path, |out| {
        write!(
            out,
            "axial_strain,volumetric_strain,mean_stress,deviator,pore_pressure"
        )?;
        for (name, _) in rows.first().map(|r| r.state.as_slice()).unwrap_or(&[]) {
            write!(out, ",{name}")?;
        }
        writeln!(out)?;
        for r in rows {
            write!(
                out,
                "{:.9e},{:.9e},{:.9e},{:.9e},{:.9e}",
                r.axial_strain, r.volumetric_strain, r.mean_stress, r.deviator, r.pore_pressure
            )?;
            for (_, v) in &r.state {
                write!(out, ",{v:.9e}")?;
            }
            writeln!(out)?;
        }
        Ok(())
    })
}
