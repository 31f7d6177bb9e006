//! Modified Cam Clay (Roscoe & Burland 1968), in effective stress, as Wood (1990, *Soil
//! Behaviour and Critical State Soil Mechanics*, ch. 4–7) sets it out. Compression positive in
//! this file's p′ and ε_v; the engine's stress is tension positive (p′ = −tr σ/3).
//!
//! * yield surface   f = q²/M² + p′ (p′ − p′_c) = 0, an ellipse through the origin and p′_c,
//!   its top on the critical state line q = M p′ (q = √(3/2 s:s), s the deviator), the same
//!   M in every direction of the deviatoric plane;
//! * associated flow δε_v^p = δγ (2p′ − p′_c), δε_q^p = δγ 2q/M²;
//! * elasticity on the unloading line: δv = −κ δp′/p′, so K = v p′/κ, and G from K and a
//!   constant Poisson's ratio: G = 3K(1 − 2ν)/(2(1 + ν));
//! * hardening on the normal compression line: δv^p = −(λ − κ) δp′_c/p′_c, so
//!   p′_c ← p′_c exp(v δε_v^p/(λ − κ)).
//!
//! The specific volume follows the total volumetric strain, v ← v exp(tr Δε), so that a
//! state that reaches the critical state lies on Γ − λ ln p′ with Γ = N − (λ − κ) ln 2, N the
//! isotropic normal compression line's v at 1 kPa.
//!
//! One step: an elastic trial with K and G of the step's starting p′ and v, then, where the
//! trial lies outside the surface, the closest-point return of Borja & Lee (1990, CMAME 78)
//! solved for δγ and the new p′_c together by Newton's method, so that the returned stress
//! lies on the surface of its own p′_c (eqs. in [`return_map`]). A step whose Newton solve does
//! not settle is cut in halves.
//!
//! Undrained (`drainage: Undrained(bulk_modulus)`), the pores' water takes the step's
//! volumetric strain as an excess pressure, δu = K_f δε_v with K_f = K_w/n, and the point's
//! stress column holds σ′ − u I (tension positive): the grid's forces see the water, the
//! clay's law sees σ′ = σ + u I. u is part of the point's state. K_f adds to the P-wave
//! modulus and so shortens the time step as 1/√(M′ + K_f). In a run the points of a
//! cell share one rate of volume change before every update and their mean u after it
//! (`systems/pore_pressure_field.rs`). A K_f far below water's own
//! (2.2 GPa/n) but far above the clay's K′ holds the volume nearly constant at a step that
//! stays practical (docs/verification.md measures the trade).
//!
//! A point's state starts from the stress it carries the first time the model updates it
//! (its p′_c is 0 until then), so a body given this clay after an elastic geostatic stage
//! starts where that stage left it: p′_c from the overconsolidation ratio times the isotropic
//! pressure of the surface through that stress (or the given p′_c), v on the unloading line
//! from p′_c through the stress.

use super::mohr_coulomb::reduce_angle;
use super::{Material, MaterialState, SceneMaterial};
use crate::error::Refusal;
use crate::tensor::Sym3;
use serde::{Deserialize, Serialize};

/// The mean effective stress (Pa) below which the clay is as stiff as at it: K = v p′/κ has
/// no stiffness at p′ = 0.
pub const MIN_STIFFNESS_PRESSURE: f64 = 1.0e3;

/// The reference pressure of the normal compression line's intercept N (Pa): 1 kPa.
const REFERENCE_PRESSURE: f64 = 1.0e3;

/// How a clay's preconsolidation is given.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Preconsolidation {
    /// The isotropic overconsolidation ratio R = p′_c/p′_y (≥ 1), p′_y the isotropic pressure
    /// of the yield surface through the point's first stress (p′ + q²/(M² p′)): 1 for a
    /// normally consolidated clay.
    Ratio(f64),
    /// p′_c itself (Pa, > 0); a point whose first stress lies outside that surface starts on
    /// the surface through it instead (normally consolidated there).
    Pressure(f64),
    /// A pre-overburden pressure POP (Pa, ≥ 0): the surface through the point's first stress
    /// grown by (σ′_v + POP)/σ′_v, σ′_v read as p′ + 2q/3 (the major effective stress of a
    /// K0 state, the vertical in the ground). The ratio 1 + POP/σ′_v falls with depth, as
    /// in a clay whose crust was loaded, dried or eroded.
    Pop(f64),
}

/// How the water in a clay's pores behaves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Drainage {
    /// The water leaves as the clay deforms: no excess pressure.
    #[default]
    Drained,
    /// The water stays: the clay's volume change compresses it.
    Undrained {
        /// K_f = K_w/n (Pa, > 0): the pore water's bulk modulus over the porosity, the
        /// stiffness against volume change that the water lends the clay.
        bulk_modulus: f64,
    },
}

/// Scene entry `ModifiedCamClay(density, lambda, kappa, critical_state_ratio |
/// critical_state_angle, poisson_ratio, ncl_volume, preconsolidation, max_mean_stress,
/// drainage)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "ModifiedCamClay")]
pub struct ModifiedCamClaySpec {
    /// ρ (kg/m³), > 0: the mass density of the clay as a whole.
    pub density: f64,
    /// λ, the slope of the normal compression line in v–ln p′, > κ.
    pub lambda: f64,
    /// κ, the slope of the unloading line in v–ln p′, > 0.
    pub kappa: f64,
    /// M, the critical state line's q/p′ in triaxial compression, in (0, 3); or give
    /// `critical_state_angle`.
    #[serde(default)]
    pub critical_state_ratio: Option<f64>,
    /// φ_cs (degrees), in (0, 90): M = 6 sin φ_cs/(3 − sin φ_cs); or give
    /// `critical_state_ratio`.
    #[serde(default)]
    pub critical_state_angle: Option<f64>,
    /// ν, in [0, 0.5): G = 3K(1 − 2ν)/(2(1 + ν)).
    pub poisson_ratio: f64,
    /// N, the specific volume on the isotropic normal compression line at p′ = 1 kPa, > 1.
    pub ncl_volume: f64,
    /// The preconsolidation: `Ratio(R)`, `Pressure(p′_c)` or `Pop(POP)`.
    pub preconsolidation: Preconsolidation,
    /// The largest mean effective stress (Pa, > 0) the run will reach: the stiffness
    /// there, N·p′/κ, sets the time step.
    pub max_mean_stress: f64,
    /// `Drained` (the default) or `Undrained(bulk_modulus: K_f)`.
    #[serde(default)]
    pub drainage: Drainage,
}

impl ModifiedCamClaySpec {
    /// M from whichever of `critical_state_ratio` and `critical_state_angle` is given.
    fn m(&self) -> Option<f64> {
        match (self.critical_state_ratio, self.critical_state_angle) {
            (Some(m), None) => Some(m),
            (None, Some(phi)) => {
                let s = phi.to_radians().sin();
                Some(6.0 * s / (3.0 - s))
            }
            _ => None,
        }
    }

    /// φ_cs (degrees) of M in triaxial compression: sin φ = 3M/(6 + M).
    fn angle(&self) -> Option<f64> {
        self.m().map(|m| (3.0 * m / (6.0 + m)).asin().to_degrees())
    }
}

impl SceneMaterial for ModifiedCamClaySpec {
    type Model = ModifiedCamClay;
    fn model(&self, at: &dyn Fn(&str) -> String) -> Result<ModifiedCamClay, Refusal> {
        let bad = |f: &str, rule: String| Err(Refusal::new(at(f), rule));
        let positive = |x: f64| x > 0.0 && x.is_finite();
        if !positive(self.density) {
            return bad("density", format!("must be > 0 kg/m³, found {}", self.density));
        }
        if !positive(self.kappa) {
            return bad("kappa", format!("must be > 0, found {}", self.kappa));
        }
        if !(self.lambda.is_finite() && self.lambda > self.kappa) {
            return bad(
                "lambda",
                format!(
                    "must be above κ = {} (the clay must harden), found {}",
                    self.kappa, self.lambda
                ),
            );
        }
        let Some(m) = self.m() else {
            return bad(
                "critical_state_ratio",
                "give exactly one of critical_state_ratio (M) and critical_state_angle (φ_cs)".into(),
            );
        };
        if let Some(phi) = self.critical_state_angle {
            if !(phi > 0.0 && phi < 90.0) {
                return bad(
                    "critical_state_angle",
                    format!("must be in (0°, 90°), found {phi}°"),
                );
            }
        }
        if !(m > 0.0 && m < 3.0) {
            return bad("critical_state_ratio", format!("must be in (0, 3), found {m}"));
        }
        if !(0.0..0.5).contains(&self.poisson_ratio) {
            return bad(
                "poisson_ratio",
                format!("must be in [0, 0.5), found {}", self.poisson_ratio),
            );
        }
        if !(self.ncl_volume.is_finite() && self.ncl_volume > 1.0) {
            return bad(
                "ncl_volume",
                format!("must be above 1, found {}", self.ncl_volume),
            );
        }
        match self.preconsolidation {
            Preconsolidation::Ratio(r) if !(r.is_finite() && r >= 1.0) => {
                return bad("preconsolidation", format!("a Ratio must be ≥ 1, found {r}"));
            }
            Preconsolidation::Pressure(p) if !positive(p) => {
                return bad(
                    "preconsolidation",
                    format!("a Pressure must be > 0 Pa, found {p}"),
                );
            }
            Preconsolidation::Pop(pop) if !(pop.is_finite() && pop >= 0.0) => {
                return bad("preconsolidation", format!("a Pop must be ≥ 0 Pa, found {pop}"));
            }
            _ => {}
        }
        if !positive(self.max_mean_stress) {
            return bad(
                "max_mean_stress",
                format!("must be > 0 Pa, found {}", self.max_mean_stress),
            );
        }
        // The normal compression line v = N − λ ln(p′/1 kPa) leaves no voids (v = 1) at
        // p′ = exp((N − 1)/λ) kPa: no clay the run reaches lies beyond it.
        let no_voids = REFERENCE_PRESSURE * ((self.ncl_volume - 1.0) / self.lambda).exp();
        if self.max_mean_stress >= no_voids {
            return bad(
                "max_mean_stress",
                format!(
                    "must stay below {no_voids:.4e} Pa, where the normal compression line \
                     N − λ ln(p′/1 kPa) reaches v = 1 (a clay with no voids left), found {:e}",
                    self.max_mean_stress
                ),
            );
        }
        let fluid_bulk = match self.drainage {
            Drainage::Drained => 0.0,
            Drainage::Undrained { bulk_modulus }
                if positive(bulk_modulus) && bulk_modulus <= super::MAX_MODULUS =>
            {
                bulk_modulus
            }
            Drainage::Undrained { bulk_modulus } => {
                return bad(
                    "drainage",
                    format!(
                        "an Undrained bulk_modulus must be > 0 Pa and at most {:e} Pa, found {bulk_modulus}",
                        super::MAX_MODULUS
                    ),
                );
            }
        };
        Ok(ModifiedCamClay {
            fluid_bulk,
            density: self.density,
            lambda: self.lambda,
            kappa: self.kappa,
            m,
            poisson_ratio: self.poisson_ratio,
            ncl_volume: self.ncl_volume,
            preconsolidation: self.preconsolidation,
            max_mean_stress: self.max_mean_stress,
        })
    }
    /// Associated flow: dilatant on the dry side of the critical state, so volumetric
    /// smoothing is refused. φ_cs stands for the largest dilatancy.
    fn dilatancy_angle(&self) -> f64 {
        self.angle().unwrap_or(0.0)
    }
    fn stiffness_field(&self) -> &'static str {
        "max_mean_stress"
    }
    fn holds_water(&self) -> bool {
        matches!(self.drainage, Drainage::Undrained { .. })
    }
    /// tan φ_cs divided by `factor`, M following it.
    fn reduce_strength(&mut self, factor: f64) -> bool {
        let Some(phi) = self.angle() else {
            return false;
        };
        let reduced = reduce_angle(phi, factor);
        if self.critical_state_angle.is_some() {
            self.critical_state_angle = Some(reduced);
        } else {
            let s = reduced.to_radians().sin();
            self.critical_state_ratio = Some(6.0 * s / (3.0 - s));
        }
        true
    }
}

/// A Modified Cam Clay point's state.
#[derive(Clone, Copy, Debug, PartialEq, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct CamClayState {
    /// p′_c (Pa): the yield surface's isotropic size; 0 until the point's first update.
    pub preconsolidation: f64,
    /// v = 1 + e, the specific volume.
    pub specific_volume: f64,
    /// Σ δε_q^p, the accumulated plastic shear strain (dimensionless).
    pub plastic_strain: f64,
    /// u (Pa, compression positive): the excess pore pressure of an undrained clay (0
    /// drained), in a run its cell's (`systems/pore_pressure_field.rs`).
    pub excess_pore_pressure: f64,
}

impl MaterialState for CamClayState {
    fn plastic_strain(&self) -> f64 {
        self.plastic_strain
    }
    fn is_finite(&self) -> bool {
        self.preconsolidation.is_finite()
            && self.specific_volume.is_finite()
            && self.plastic_strain.is_finite()
            && self.excess_pore_pressure.is_finite()
    }
    fn excess_pore_pressure(&self) -> f64 {
        self.excess_pore_pressure
    }
    fn set_excess_pore_pressure(&mut self, u: f64) {
        self.excess_pore_pressure = u;
    }
    fn fields(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("preconsolidation", self.preconsolidation),
            ("specific_volume", self.specific_volume),
            ("excess_pore_pressure", self.excess_pore_pressure),
        ]
    }
    /// A specific volume of at most 1 (a void ratio of at most 0) in a state that has been
    /// set (p′_c > 0).
    fn fault(&self) -> Option<String> {
        (self.preconsolidation > 0.0 && self.specific_volume <= 1.0).then(|| {
            format!(
                "p′_c = {:.4e} Pa and a specific volume of {:.6} (v ≤ 1: no voids left)",
                self.preconsolidation, self.specific_volume
            )
        })
    }
}

/// The Modified Cam Clay model of a checked [`ModifiedCamClaySpec`].
#[derive(Clone, Debug, PartialEq)]
pub struct ModifiedCamClay {
    /// ρ (kg/m³).
    pub density: f64,
    /// λ.
    pub lambda: f64,
    /// κ.
    pub kappa: f64,
    /// M.
    pub m: f64,
    /// ν.
    pub poisson_ratio: f64,
    /// N (at 1 kPa).
    pub ncl_volume: f64,
    /// How p′_c starts.
    pub preconsolidation: Preconsolidation,
    /// The time step's mean effective stress (Pa).
    pub max_mean_stress: f64,
    /// K_f (Pa): the pore water's stiffness when undrained, 0 when drained.
    pub fluid_bulk: f64,
}

/// p′ (Pa, compression positive), the deviator s (Pa) and q = √(3/2 s:s) of a
/// tension-positive stress.
fn invariants(stress: &Sym3) -> (f64, Sym3, f64) {
    let p = -stress.trace() / 3.0;
    let s = *stress + Sym3::IDENTITY * p;
    let q = (1.5 * s.ddot(&s)).sqrt();
    (p, s, q)
}

impl ModifiedCamClay {
    /// Bulk and shear moduli (Pa) at p′ (Pa) and specific volume v.
    fn moduli(&self, p: f64, v: f64) -> (f64, f64) {
        let k = v * p.max(MIN_STIFFNESS_PRESSURE) / self.kappa;
        let nu = self.poisson_ratio;
        (k, 3.0 * k * (1.0 - 2.0 * nu) / (2.0 * (1.0 + nu)))
    }

    /// The elastic trial of `de` from `stress` at specific volume `v`, with the bulk and
    /// shear moduli (Pa) of the stress it starts from.
    fn trial(&self, stress: &Sym3, de: &Sym3, v: f64) -> (Sym3, f64, f64) {
        let (k, g) = self.moduli(invariants(stress).0, v);
        let trial = *stress + Sym3::IDENTITY * ((k - 2.0 / 3.0 * g) * de.trace()) + *de * (2.0 * g);
        (trial, k, g)
    }

    /// f (Pa²) at p′, q and p′_c.
    fn yield_value(&self, p: f64, q: f64, pc: f64) -> f64 {
        q * q / (self.m * self.m) + p * (p - pc)
    }

    /// The state of a point first updated at `stress`.
    pub fn initial_state(&self, stress: &Sym3) -> CamClayState {
        let (p, _, q) = invariants(stress);
        let p = p.max(MIN_STIFFNESS_PRESSURE);
        let through = p + q * q / (self.m * self.m * p);
        let pc = match self.preconsolidation {
            Preconsolidation::Ratio(r) => r * through,
            Preconsolidation::Pressure(pc) => pc.max(through),
            Preconsolidation::Pop(pop) => through * (1.0 + pop / (p + 2.0 * q / 3.0)),
        };
        CamClayState {
            preconsolidation: pc,
            specific_volume: self.ncl_volume - self.lambda * (pc / REFERENCE_PRESSURE).ln()
                + self.kappa * (pc / p).ln(),
            plastic_strain: 0.0,
            excess_pore_pressure: 0.0,
        }
    }

    /// One step of `de` from `stress` and `state`; false (nothing changed) when the return's
    /// Newton solve does not settle.
    fn step(&self, stress: &mut Sym3, de: &Sym3, state: &mut CamClayState) -> bool {
        let v = state.specific_volume;
        let (trial, k, g) = self.trial(stress, de, v);
        let (pt, st, qt) = invariants(&trial);
        let pcn = state.preconsolidation;
        if self.yield_value(pt, qt, pcn) <= 1e-12 * pcn * pcn {
            *stress = trial;
            state.specific_volume = v * de.trace().exp();
            return true;
        }
        let Some((dg, p, q, pc)) = self.return_map(pt, qt, pcn, k, g, v) else {
            return false;
        };
        let ratio = if qt > 0.0 { q / qt } else { 0.0 };
        *stress = st * ratio - Sym3::IDENTITY * p;
        state.preconsolidation = pc;
        state.specific_volume = v * de.trace().exp();
        state.plastic_strain += dg * 2.0 * q / (self.m * self.m);
        true
    }

    /// The closest-point return from a trial (p′_t, q_t) outside the surface of p′_c,n:
    /// δγ ≥ 0 and p′_c with
    ///
    ///   p′ = (p′_t + K δγ p′_c)/(1 + 2K δγ),   q = q_t/(1 + 6G δγ/M²),
    ///   r₁ = q²/M² + p′(p′ − p′_c) = 0,   r₂ = p′_c − p′_c,n exp(θ δγ (2p′ − p′_c)) = 0,
    ///
    /// θ = v/(λ − κ); returns (δγ, p′, q, p′_c), or None when Newton's method does not settle.
    fn return_map(&self, pt: f64, qt: f64, pcn: f64, k: f64, g: f64, v: f64) -> Option<(f64, f64, f64, f64)> {
        let m2 = self.m * self.m;
        let theta = v / (self.lambda - self.kappa);
        let (mut dg, mut pc) = (0.0f64, pcn);
        for _ in 0..60 {
            let a = 1.0 + 2.0 * k * dg;
            let b = 1.0 + 6.0 * g * dg / m2;
            let p = (pt + k * dg * pc) / a;
            let q = qt / b;
            let (dp_dg, dp_dpc) = (k * (pc - 2.0 * p) / a, k * dg / a);
            let dq_dg = -q * (6.0 * g / m2) / b;
            let r1 = q * q / m2 + p * (p - pc);
            let e = pcn * (theta * dg * (2.0 * p - pc)).exp();
            let r2 = pc - e;
            if r1.abs() <= 1e-12 * pcn * pcn && r2.abs() <= 1e-12 * pcn {
                return Some((dg, p, q, pc));
            }
            let j11 = 2.0 * q / m2 * dq_dg + (2.0 * p - pc) * dp_dg;
            let j12 = (2.0 * p - pc) * dp_dpc - p;
            let j21 = -e * theta * ((2.0 * p - pc) + 2.0 * dg * dp_dg);
            let j22 = 1.0 - e * theta * dg * (2.0 * dp_dpc - 1.0);
            let det = j11 * j22 - j12 * j21;
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let ddg = -(r1 * j22 - j12 * r2) / det;
            let dpc = -(j11 * r2 - j21 * r1) / det;
            // Damped: δγ stays ≥ 0 and p′_c > 0.
            let mut t = 1.0;
            while t > 1e-6 && (dg + t * ddg < 0.0 || pc + t * dpc <= 0.0) {
                t *= 0.5;
            }
            dg += t * ddg;
            pc += t * dpc;
            if !(dg.is_finite() && pc.is_finite()) {
                return None;
            }
        }
        None
    }

    /// `de` in `2^depth` equal parts, each a [`Self::step`], halving a part again where its
    /// return does not settle (to 2⁻¹² of the step).
    fn substep(&self, stress: &mut Sym3, de: &Sym3, state: &mut CamClayState, depth: u32) {
        if self.step(stress, de, state) {
            return;
        }
        if depth >= 12 {
            // The last resort: the trial's shear scaled back onto the surface at its p′.
            let (trial, _, _) = self.trial(stress, de, state.specific_volume);
            let (p, s, q) = invariants(&trial);
            let pc = state.preconsolidation;
            let p = p.clamp(0.0, pc);
            let on = self.m * (p * (pc - p)).sqrt();
            *stress = s * if q > on { on / q } else { 1.0 } - Sym3::IDENTITY * p;
            state.specific_volume *= de.trace().exp();
            return;
        }
        let half = *de * 0.5;
        self.substep(stress, &half, state, depth + 1);
        self.substep(stress, &half, state, depth + 1);
    }
}

impl Material for ModifiedCamClay {
    type State = CamClayState;
    fn density(&self) -> f64 {
        self.density
    }
    /// K + 4G/3 at `max_mean_stress` with v = N (v ≤ N above 1 kPa): the stiffest the clay
    /// gets in the run.
    fn p_wave_modulus(&self) -> f64 {
        let (k, g) = self.moduli(self.max_mean_stress, self.ncl_volume);
        k + 4.0 / 3.0 * g + self.fluid_bulk
    }
    /// σ′ = σ + u I through the clay's law; undrained, u grows by K_f times the step's
    /// volume loss and the stress column takes σ′ − u I again.
    fn update(&self, stress: &mut Sym3, de: &Sym3, state: &mut CamClayState) {
        let u = state.excess_pore_pressure;
        let mut effective = *stress + Sym3::IDENTITY * u;
        if state.preconsolidation == 0.0 {
            *state = self.initial_state(&effective);
        }
        self.substep(&mut effective, de, state, 0);
        state.excess_pore_pressure = u - self.fluid_bulk * de.trace();
        *stress = effective - Sym3::IDENTITY * state.excess_pore_pressure;
    }
    fn admits(&self, stress: &Sym3, state: &CamClayState) -> bool {
        if state.preconsolidation == 0.0 {
            return true;
        }
        let (p, _, q) = invariants(&(*stress + Sym3::IDENTITY * state.excess_pore_pressure));
        let pc = state.preconsolidation;
        self.yield_value(p, q, pc) <= 1e-9 * pc * pc
    }
    fn holds_water(&self) -> bool {
        self.fluid_bulk > 0.0
    }
    /// The strength of undrained triaxial compression from the point's state: its volume
    /// stays v, so it ends on the critical state line at p′_f = exp((Γ − v)/λ) (kPa, Γ =
    /// N − (λ − κ) ln 2) with q_f = M p′_f, and s_u = q_f/2 = (M/2) p′_f whatever the path
    /// (Wood 1990, §7.4; from an isotropic p′₀ and R₀ = p′_c/p′₀ this is
    /// (M/2) p′₀ (R₀/2)^Λ). A point not yet updated takes the state its stress gives it.
    fn undrained_strength(&self, stress: &Sym3, state: &CamClayState) -> Option<f64> {
        let state = if state.preconsolidation == 0.0 {
            self.initial_state(&(*stress + Sym3::IDENTITY * state.excess_pore_pressure))
        } else {
            *state
        };
        let gamma = self.ncl_volume - (self.lambda - self.kappa) * std::f64::consts::LN_2;
        let p_f = REFERENCE_PRESSURE * ((gamma - state.specific_volume) / self.lambda).exp();
        Some(0.5 * self.m * p_f)
    }
    /// A point may not start above `max_mean_stress`, the stiffness the time step is set
    /// for, nor where the state its stress gives it has no voids (v ≤ 1: a preconsolidation
    /// past where the normal compression line reaches v = 1).
    fn start_fault(&self, stress: &Sym3) -> Option<String> {
        let (p, _, _) = invariants(stress);
        if p > self.max_mean_stress {
            return Some(format!(
                "the clay starts at p′ = {:.4e} Pa, above its max_mean_stress {:e} Pa, the \
                 stiffness the time step is set for: raise max_mean_stress",
                p, self.max_mean_stress
            ));
        }
        (self.initial_state(stress).fault())
            .map(|why| format!("the clay starts at p′ = {p:.4e} Pa with {why}: lower its preconsolidation"))
    }
    /// Undrained (water in the state): s_u on any plane, [`Material::undrained_strength`].
    /// Drained: the critical state's friction, sin φ_cs = 3M/(6 + M) (triaxial compression,
    /// Wood 1990), without cohesion.
    fn plane_strength(&self, stress: &Sym3, state: &CamClayState) -> Option<(f64, f64)> {
        if self.holds_water() {
            return self.undrained_strength(stress, state).map(|s_u| (s_u, 0.0));
        }
        let sin = 3.0 * self.m / (6.0 + self.m);
        Some((0.0, sin / (1.0 - sin * sin).sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clay(pre: Preconsolidation) -> ModifiedCamClay {
        ModifiedCamClaySpec {
            density: 1800.0,
            lambda: 0.25,
            kappa: 0.05,
            critical_state_ratio: Some(0.9),
            critical_state_angle: None,
            poisson_ratio: 0.25,
            ncl_volume: 3.0,
            preconsolidation: pre,
            max_mean_stress: 1e6,
            drainage: Drainage::Drained,
        }
        .model(&|f| f.to_string())
        .unwrap()
    }

    #[test]
    fn a_returned_stress_lies_on_the_surface_of_its_own_preconsolidation() {
        let m = clay(Preconsolidation::Ratio(1.0));
        let mut stress = Sym3::diagonal(-100e3, -100e3, -100e3);
        let mut state = CamClayState::default();
        // A large shear step from the normally consolidated state.
        m.update(&mut stress, &Sym3::diagonal(0.01, -0.02, 0.01), &mut state);
        let (p, _, q) = invariants(&stress);
        let f = m.yield_value(p, q, state.preconsolidation);
        assert!(f.abs() < 1e-9 * state.preconsolidation.powi(2), "f = {f}");
        assert!(
            state.preconsolidation > 100e3,
            "it hardens: {}",
            state.preconsolidation
        );
    }

    #[test]
    fn the_undrained_strength_is_wood_s_closed_form_from_any_start() {
        // s_u/p′₀ = (M/2)(R₀/2)^Λ, Λ = 0.8 (Wood 1990, §7.4), before and after a first
        // update that leaves the point elastic.
        for r in [1.0, 2.0, 4.0, 8.0] {
            let m = clay(Preconsolidation::Ratio(r));
            let mut stress = Sym3::diagonal(-100e3, -100e3, -100e3);
            let mut state = CamClayState::default();
            let closed = 0.45 * 100e3 * (r / 2.0f64).powf(0.8);
            let before = m.undrained_strength(&stress, &state).unwrap();
            assert!(
                (before / closed - 1.0).abs() < 1e-12,
                "R₀ {r}: {before} vs {closed}"
            );
            m.update(&mut stress, &Sym3::diagonal(1e-6, -1e-6, 0.0), &mut state);
            let after = m.undrained_strength(&stress, &state).unwrap();
            assert!((after / closed - 1.0).abs() < 1e-9, "R₀ {r}: {after} vs {closed}");
        }
    }

    #[test]
    fn an_isotropic_load_follows_the_normal_compression_line() {
        let m = clay(Preconsolidation::Ratio(1.0));
        let mut stress = Sym3::diagonal(-100e3, -100e3, -100e3);
        let mut state = CamClayState::default();
        for _ in 0..2000 {
            m.update(&mut stress, &Sym3::diagonal(-1e-4, -1e-4, -1e-4), &mut state);
        }
        let (p, _, _) = invariants(&stress);
        let on_ncl = m.ncl_volume - m.lambda * (p / REFERENCE_PRESSURE).ln();
        assert!(
            (state.specific_volume - on_ncl).abs() < 1e-3,
            "{} vs {on_ncl}",
            state.specific_volume
        );
        assert!((state.preconsolidation / p - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_ratio_below_one_and_both_strength_fields_are_refused() {
        let mut spec = ModifiedCamClaySpec {
            density: 1800.0,
            lambda: 0.25,
            kappa: 0.05,
            critical_state_ratio: Some(0.9),
            critical_state_angle: Some(25.0),
            poisson_ratio: 0.25,
            ncl_volume: 3.0,
            preconsolidation: Preconsolidation::Ratio(1.0),
            max_mean_stress: 1e6,
            drainage: Drainage::Drained,
        };
        let e = spec.model(&|f| f.to_string()).unwrap_err();
        assert_eq!(e.field, "critical_state_ratio", "{e:?}");
        spec.critical_state_angle = None;
        spec.preconsolidation = Preconsolidation::Ratio(0.5);
        let e = spec.model(&|f| f.to_string()).unwrap_err();
        assert_eq!(e.field, "preconsolidation", "{e:?}");
        spec.preconsolidation = Preconsolidation::Pop(-1.0);
        let e = spec.model(&|f| f.to_string()).unwrap_err();
        assert_eq!(e.field, "preconsolidation", "{e:?}");
        spec.preconsolidation = Preconsolidation::Ratio(1.0);
        spec.lambda = 0.04;
        let e = spec.model(&|f| f.to_string()).unwrap_err();
        assert_eq!(e.field, "lambda", "{e:?}");
    }
}
