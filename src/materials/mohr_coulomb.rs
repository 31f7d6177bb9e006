//! Mohr-Coulomb linear-elastic perfectly-plastic material with a tension cut-off.
//!
//! The return mapping works in principal stress space (tension positive, σ1 ≥ σ2 ≥ σ3),
//! after Clausen, Damkilde & Andersen (2006), "Efficient return algorithms for associated
//! plasticity with multiple yield planes", extended to non-associated flow:
//!
//! * yield function  f = k σ1 − σ3 − σc,   k = (1 + sin φ)/(1 − sin φ),  σc = 2c √k;
//! * plastic potential g = m σ1 − σ3,       m = (1 + sin ψ)/(1 − sin ψ);
//! * return to the plane along D·∂g/∂σ; if that breaks the principal order, to one of the
//!   two edges (σ1 = σ2 or σ2 = σ3) along the span of the two planes' flow directions; if the
//!   edge point lies beyond the apex σ1 = σ2 = σ3 = c·cot φ, to the apex.
//! * tension cut-off σ_i ≤ σt (σt ≤ c·cot φ) as a Rankine return applied afterwards; it
//!   lowers σ1 more than σ3 (k ≥ 1, λ + 2G > λ), so it never re-violates f ≤ 0.
//!
//! In compression-positive terms the plane f = 0 is the classical
//! σ1' = σ3' (1 + sin φ)/(1 − sin φ) + 2c cos φ/(1 − sin φ).

use super::{update_lane_by_lane, Elasticity, Material, MaterialState, SceneMaterial};
use crate::error::Refusal;
use crate::infra::lanes::{gather, F64x4, Lanes, LANES};
use crate::tensor::{Sym, Sym3, Sym3x4};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Scene entry `MohrCoulomb(density, youngs_modulus, poisson_ratio, cohesion,
/// friction_angle, dilatancy_angle, tension_cutoff)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "MohrCoulomb")]
pub struct MohrCoulombSpec {
    /// ρ (kg/m³), > 0.
    pub density: f64,
    /// E (Pa), > 0.
    pub youngs_modulus: f64,
    /// ν, in [0, 0.5).
    pub poisson_ratio: f64,
    /// c (Pa), ≥ 0.
    pub cohesion: f64,
    /// φ (degrees), in [0, 90).
    pub friction_angle: f64,
    /// ψ (degrees), in [0, φ].
    #[serde(default)]
    pub dilatancy_angle: f64,
    /// Largest tensile principal stress (Pa); default and upper bound c·cot φ.
    #[serde(default)]
    pub tension_cutoff: Option<f64>,
}

/// Checks the strength of a Mohr-Coulomb entry: c (Pa) ≥ 0, φ in [0°, 90°), ψ in [0°, φ],
/// a cut-off (Pa) ≥ 0, and some strength (c > 0 when φ = 0); fields named through `at`.
pub(super) fn check_strength(
    at: &dyn Fn(&str) -> String,
    (c, phi, psi): (f64, f64, f64),
    tension_cutoff: Option<f64>,
) -> Result<(), Refusal> {
    let non_negative = |x: f64| x >= 0.0 && x.is_finite();
    if !non_negative(c) {
        return Err(Refusal::new(at("cohesion"), format!("must be ≥ 0 Pa, found {c}")));
    }
    if !(0.0..90.0).contains(&phi) {
        return Err(Refusal::new(
            at("friction_angle"),
            format!("must be in [0°, 90°), found {phi}°"),
        ));
    }
    if !(non_negative(psi) && psi <= phi) {
        return Err(Refusal::new(
            at("dilatancy_angle"),
            format!("must be in [0°, φ = {phi}°], found {psi}°"),
        ));
    }
    if let Some(t) = tension_cutoff {
        if !non_negative(t) {
            return Err(Refusal::new(
                at("tension_cutoff"),
                format!("must be a finite stress ≥ 0 Pa (at most c·cot φ), found {t}"),
            ));
        }
    }
    if phi == 0.0 && c == 0.0 {
        return Err(Refusal::new(
            at("cohesion"),
            "with φ = 0 the cohesion must be > 0 (no strength at all)".into(),
        ));
    }
    Ok(())
}

/// An angle (degrees) whose tangent is divided by `factor`.
pub(super) fn reduce_angle(deg: f64, factor: f64) -> f64 {
    (deg.to_radians().tan() / factor).atan().to_degrees()
}

impl SceneMaterial for MohrCoulombSpec {
    type Model = MohrCoulomb;
    fn model(&self, at: &dyn Fn(&str) -> String) -> Result<MohrCoulomb, Refusal> {
        Elasticity::checked(at, self.density, self.youngs_modulus, self.poisson_ratio)?;
        let strength = (self.cohesion, self.friction_angle, self.dilatancy_angle);
        check_strength(at, strength, self.tension_cutoff)?;
        Ok(MohrCoulomb::new(
            self.density,
            self.youngs_modulus,
            self.poisson_ratio,
            self.cohesion,
            self.friction_angle,
            self.dilatancy_angle,
            self.tension_cutoff,
        ))
    }
    fn dilatancy_angle(&self) -> f64 {
        self.dilatancy_angle
    }
    /// c, tan φ, tan ψ and an explicit cut-off, each divided by `factor`.
    fn reduce_strength(&mut self, factor: f64) -> bool {
        self.cohesion /= factor;
        self.friction_angle = reduce_angle(self.friction_angle, factor);
        self.dilatancy_angle = reduce_angle(self.dilatancy_angle, factor);
        if let Some(t) = &mut self.tension_cutoff {
            *t /= factor;
        }
        true
    }
}

/// Accumulated equivalent plastic strain sqrt(2/3 Δεp_dev : Δεp_dev) summed over the steps
/// (dimensionless): the state of a Mohr-Coulomb point.
#[derive(Clone, Copy, Debug, PartialEq, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub struct PlasticStrain(pub f64);

impl MaterialState for PlasticStrain {
    fn plastic_strain(&self) -> f64 {
        self.0
    }
    fn is_finite(&self) -> bool {
        self.0.is_finite()
    }
}

/// Every lane's bit of a four-lane mask.
const ALL_LANES: u32 = (1 << LANES) - 1;

/// Mohr-Coulomb perfectly plastic material.
#[derive(Clone, Debug, PartialEq)]
pub struct MohrCoulomb {
    /// Mass density ρ (kg/m³).
    pub density: f64,
    /// Elastic constants.
    pub elasticity: Elasticity,
    /// Cohesion c (Pa).
    pub cohesion: f64,
    /// Friction angle φ (rad).
    pub friction: f64,
    /// Dilatancy angle ψ (rad).
    pub dilatancy: f64,
    /// Largest principal stress allowed (Pa, tension positive).
    pub tension_cutoff: f64,
    // Derived constants.
    k: f64,
    sigma_c: f64,
    apex: Option<f64>,
    /// D·∂g/∂σ for the plane σ1 ≥ σ2 ≥ σ3 and its two neighbours.
    flow_main: DVec3,
    flow_12: DVec3,
    flow_23: DVec3,
    grad_f: DVec3,
}

/// How a trial stress was returned (for tests and diagnostics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Return {
    /// Inside the yield surface: unchanged.
    Elastic,
    /// Onto the main plane.
    Plane,
    /// Onto the edge σ1 = σ2.
    EdgeOneTwo,
    /// Onto the edge σ2 = σ3.
    EdgeTwoThree,
    /// Onto the apex.
    Apex,
}

impl MohrCoulomb {
    /// From density (kg/m³), E (Pa), ν, c (Pa), φ and ψ (degrees) and an optional tension
    /// cut-off (Pa); the cut-off is never above the apex c·cot φ.
    pub fn new(
        density: f64,
        youngs_modulus: f64,
        poisson_ratio: f64,
        cohesion: f64,
        friction_deg: f64,
        dilatancy_deg: f64,
        tension_cutoff: Option<f64>,
    ) -> Self {
        let elasticity = Elasticity::new(youngs_modulus, poisson_ratio);
        let (phi, psi) = (friction_deg.to_radians(), dilatancy_deg.to_radians());
        let k = (1.0 + phi.sin()) / (1.0 - phi.sin());
        let m = (1.0 + psi.sin()) / (1.0 - psi.sin());
        let sigma_c = 2.0 * cohesion * k.sqrt();
        let apex = (phi > 0.0).then(|| sigma_c / (k - 1.0));
        let limit = apex.unwrap_or(f64::INFINITY);
        let tension_cutoff = tension_cutoff.map_or(limit, |t| t.min(limit));
        let d = |g: DVec3| {
            let vol = elasticity.lambda * (g.x + g.y + g.z);
            DVec3::splat(vol) + g * (2.0 * elasticity.shear)
        };
        MohrCoulomb {
            density,
            elasticity,
            cohesion,
            friction: phi,
            dilatancy: psi,
            tension_cutoff,
            k,
            sigma_c,
            apex,
            flow_main: d(DVec3::new(m, 0.0, -1.0)),
            flow_12: d(DVec3::new(0.0, m, -1.0)),
            flow_23: d(DVec3::new(m, -1.0, 0.0)),
            grad_f: DVec3::new(k, 0.0, -1.0),
        }
    }

    /// Yield function f for principal stresses sorted σ1 ≥ σ2 ≥ σ3 (Pa; ≤ 0 is admissible),
    /// of one point or four in lanes.
    #[inline(always)]
    pub fn yield_function<T: Lanes>(&self, p: [T; 3]) -> T {
        T::splat(self.k) * p[0] - p[2] - T::splat(self.sigma_c)
    }

    /// True when principal stresses sorted σ1 ≥ σ2 ≥ σ3 (Pa) are inside the yield surface and
    /// at or below the tension cut-off.
    #[inline(always)]
    pub fn admissible(&self, p: [f64; 3]) -> bool {
        self.within((self.yield_function(p), p[0]))
    }

    /// True when a value (or upper bound) of the yield function f and of σ1 (Pa) admit the
    /// stress: f ≤ 0 and σ1 at or below the tension cut-off.
    #[inline(always)]
    fn within(&self, (f, sigma_1): (f64, f64)) -> bool {
        f <= 0.0 && sigma_1 <= self.tension_cutoff
    }

    /// True when the stress is inside the yield surface and below the tension cut-off by a
    /// bound, so most elastic points skip the eigen-decomposition: the bound from the
    /// invariants (`MohrCoulomb::invariant_bound`) or, for nearly planar states, the one
    /// from the x-y block (`MohrCoulomb::near_planar_bound`). A stress it passes is one the
    /// exact test on the eigen-decomposition's values passes too.
    #[inline(always)]
    pub fn surely_elastic(&self, stress: &Sym3) -> bool {
        self.within(self.invariant_bound(stress)) || self.within(self.near_planar_bound(stress))
    }

    /// Upper bounds on f and σ1 (Pa) from the invariants, of one point or four in lanes.
    ///
    /// The deviatoric principal values lie within ±sqrt(2/3)|s|, so
    /// f = (k − 1) p + k s1 − s3 − σc ≤ (k − 1) p + (k + 1) sqrt(2/3) |s| − σc and
    /// σ1 ≤ p + sqrt(2/3) |s|. Loose only near the surface, where the exact test runs anyway.
    #[inline(always)]
    fn invariant_bound<T: Lanes>(&self, stress: &Sym<T>) -> (T, T) {
        let (p, s) = stress.mean_and_deviatoric_norm();
        let r = T::splat((2.0f64 / 3.0).sqrt()) * s;
        let f = T::splat(self.k - 1.0) * p + T::splat(self.k + 1.0) * r - T::splat(self.sigma_c);
        (f, p + r)
    }

    /// Upper bounds on f and σ1 (Pa) from the principal values of the stress without its yz
    /// and zx, of one point or four in lanes. Leaving out a symmetric part E moves each sorted
    /// principal value by at most E's spectral norm, here sqrt(yz² + zx²) (Weyl's
    /// inequality), so f by at most (k + 1) times that; a margin of 1e-10 |σ| and 1e-10 σc
    /// covers the rounding of this test and of the eigen-decomposition's values (a few
    /// ε |σ| each, ε = 2.2e-16). Tight where the invariant bound is loose: near the surface in
    /// a nearly planar state, such as a 3D body in plane strain, whose yz and zx are round-off.
    #[inline(always)]
    fn near_planar_bound<T: Lanes>(&self, stress: &Sym<T>) -> (T, T) {
        const MARGIN: f64 = 1e-10;
        let p = stress.planar_principal_values();
        let out_of_plane = (stress.yz * stress.yz + stress.zx * stress.zx).sqrt();
        let shift = T::madd(T::splat(MARGIN), stress.norm(), out_of_plane);
        let f =
            T::madd(T::splat(self.k + 1.0), shift, self.yield_function(p)) + T::splat(MARGIN * self.sigma_c);
        (f, p[0] + shift)
    }

    /// The test of [`Material::update`] that lets a trial stress stand, for four points in
    /// lanes: bit l is set when lane l passes it (or, for a general state, a bound that
    /// passes only stresses the exact test passes). When the lanes disagree on whether z is a
    /// principal axis (which selects the test) none is set, and each point is tested alone.
    #[inline(always)]
    fn elastic_lanes(&self, trial: &Sym3x4) -> u32 {
        let (zero, cutoff) = (F64x4::splat(0.0), F64x4::splat(self.tension_cutoff));
        let passes = |(f, sigma_1): (F64x4, F64x4)| (f.simd_le(zero) & sigma_1.simd_le(cutoff)).to_bitmask();
        match trial.principal_z_lanes() {
            ALL_LANES => {
                let p = trial.planar_principal_values();
                passes((self.yield_function(p), p[0]))
            }
            0 => passes(self.invariant_bound(trial)) | passes(self.near_planar_bound(trial)),
            _ => 0,
        }
    }

    /// Where a trial stress (Pa) ends: itself when admissible, else returned to the yield
    /// surface, with the principal stress correction of the return (Pa).
    #[inline(always)]
    fn settle(&self, trial: Sym3) -> (Sym3, Option<[f64; 3]>) {
        // With z principal (all of plane strain) the exact principal values cost one square
        // root, as much as the invariant bound, and also settle the states the bound cannot
        // (most of a failing slope); the eigenvectors are then found only for yielding points.
        let planar = trial.has_principal_z();
        let elastic = if planar {
            self.admissible(trial.principal_values())
        } else {
            self.surely_elastic(&trial)
        };
        if elastic {
            return (trial, None);
        }
        let (p, r) = trial.eigen();
        // The bound is loose near the surface: a general state it did not pass may be inside.
        if !planar && self.admissible(p) {
            return (trial, None);
        }
        let (ret, _) = self.return_principal(p);
        let correction = std::array::from_fn(|i| p[i] - ret[i]);
        (Sym3::from_principal(ret, &r), Some(correction))
    }

    /// Returns sorted principal trial stresses to the yield surface.
    pub fn return_principal(&self, trial: [f64; 3]) -> ([f64; 3], Return) {
        let t = DVec3::from_array(trial);
        let f = self.yield_function(trial);
        let (mut s, mut kind) = (t, Return::Elastic);
        if f > 0.0 {
            (s, kind) = self.return_mohr_coulomb(t, f);
        }
        if s.x > self.tension_cutoff {
            s = self.return_tension(s);
        }
        (s.to_array(), kind)
    }

    fn return_mohr_coulomb(&self, t: DVec3, f: f64) -> (DVec3, Return) {
        let scale = t.abs().max_element().max(self.sigma_c).max(1.0);
        let tol = 1e-12 * scale;
        // Plane.
        let s = t - self.flow_main * (f / self.grad_f.dot(self.flow_main));
        if s.x + tol >= s.y && s.y + tol >= s.z {
            return (s, Return::Plane);
        }
        // Edges: the line through a point on both planes, along their intersection.
        let edges = [
            (DVec3::new(1.0, 1.0, self.k), self.flow_12, Return::EdgeOneTwo),
            (
                DVec3::new(1.0, self.k, self.k),
                self.flow_23,
                Return::EdgeTwoThree,
            ),
        ];
        for (dir, flow_b, kind) in edges {
            let p0 = match self.apex {
                Some(a) => DVec3::splat(a),
                // φ = 0 (Tresca): no apex; a point with σ1 − σ3 = σc on this edge.
                None if kind == Return::EdgeOneTwo => DVec3::new(0.5, 0.5, -0.5) * self.sigma_c,
                None => DVec3::new(0.5, -0.5, -0.5) * self.sigma_c,
            };
            let n = self.flow_main.cross(flow_b);
            let u = n.dot(t - p0) / n.dot(dir);
            if self.apex.is_some() && u > 0.0 {
                continue; // beyond the apex
            }
            let s = p0 + dir * u;
            // Multipliers of the two flow directions: t − s = λa·flow_main + λb·flow_b.
            let d = t - s;
            let ca = flow_b.cross(n);
            let cb = self.flow_main.cross(n);
            let la = d.dot(ca) / self.flow_main.dot(ca);
            let lb = d.dot(cb) / flow_b.dot(cb);
            let ordered = s.x + tol >= s.y && s.y + tol >= s.z;
            if la >= -1e-12 && lb >= -1e-12 && ordered {
                return (s, kind);
            }
        }
        // A Tresca surface has no apex: only a trial stress that is not a finite number
        // (moduli or strains that overflow) misses all its planes and edges. The NaN it
        // gets back stops the run, as a non-finite state, at the next energy check.
        let apex = self.apex.unwrap_or(f64::NAN);
        (DVec3::splat(apex), Return::Apex)
    }

    /// Rankine return σ_i ≤ σt for the principal stresses above the cut-off.
    fn return_tension(&self, s: DVec3) -> DVec3 {
        let (l, g2) = (self.elasticity.lambda, 2.0 * self.elasticity.shear);
        let st = self.tension_cutoff;
        let s = s.to_array();
        // Active set grows from the largest value; at most three passes.
        for active in 1..=3 {
            if s[active - 1] <= st {
                break;
            }
            // Solve (λ 11ᵀ + 2G I) Δλ = s_J − σt on the first `active` components:
            // Δλ_j = (e_j − λ Σe/(2G + nλ)) / 2G with e_j = s_j − σt.
            // Fixed arrays, zero outside the active set: this runs per point per step.
            let excess: [f64; 3] = std::array::from_fn(|i| if i < active { s[i] - st } else { 0.0 });
            let sum: f64 = excess[..active].iter().sum();
            let common = l * sum / (g2 + active as f64 * l);
            let dl: [f64; 3] = std::array::from_fn(|i| {
                if i < active {
                    (excess[i] - common) / g2
                } else {
                    0.0
                }
            });
            let trace: f64 = dl[..active].iter().sum();
            let out: [f64; 3] = std::array::from_fn(|i| s[i] - l * trace - g2 * dl[i]);
            if active == 3 || out[active] <= st {
                return DVec3::from_array(out);
            }
        }
        DVec3::from_array(s)
    }

    /// Equivalent plastic strain of the principal stress correction Δσ (Pa):
    /// sqrt(2/3 · dev(Δεp) : dev(Δεp)) with Δεp = D⁻¹ Δσ; of one point or four in lanes.
    #[inline(always)]
    fn plastic_strain_increment<T: Lanes>(&self, ds: [T; 3]) -> T {
        // dev(D⁻¹ Δσ) = dev(Δσ) / 2G for isotropic elasticity.
        let mean = (ds[0] + ds[1] + ds[2]) / T::splat(3.0);
        let g2 = T::splat(2.0 * self.elasticity.shear);
        let dev = ds.map(|d| (d - mean) / g2);
        (T::splat(2.0 / 3.0) * (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2])).sqrt()
    }
}

impl Material for MohrCoulomb {
    type State = PlasticStrain;
    fn density(&self) -> f64 {
        self.density
    }
    /// Tresca (φ = 0): c, whatever the stress. A frictional soil has none.
    fn undrained_strength(&self, _: &Sym3, _: &PlasticStrain) -> Option<f64> {
        (self.friction == 0.0).then_some(self.cohesion)
    }
    /// Coulomb's line: c and tan φ whatever the stress (the tension cut-off aside: an
    /// interface that the soil presses is not in tension).
    fn plane_strength(&self, _: &Sym3, _: &PlasticStrain) -> Option<(f64, f64)> {
        self.constant_strength()
    }
    fn constant_strength(&self) -> Option<(f64, f64)> {
        Some((self.cohesion, self.friction.tan()))
    }
    fn p_wave_modulus(&self) -> f64 {
        self.elasticity.p_wave()
    }
    // Always: with a hint alone the one-point update was not inlined into its callers,
    // which costs a plastic point time (docs/performance.md).
    #[inline(always)]
    /// As `settle` tests a trial stress: exactly, at the cost of one square root, with z
    /// principal; otherwise the invariant bound first, which most points inside pass.
    fn admits(&self, stress: &Sym3, _: &PlasticStrain) -> bool {
        if stress.has_principal_z() {
            self.admissible(stress.principal_values())
        } else {
            self.surely_elastic(stress) || self.admissible(stress.eigen().0)
        }
    }
    #[inline(always)]
    fn update(&self, stress: &mut Sym3, de: &Sym3, plastic: &mut PlasticStrain) {
        let (settled, correction) = self.settle(*stress + self.elasticity.stress_increment(de));
        *stress = settled;
        if let Some(ds) = correction {
            plastic.0 += self.plastic_strain_increment(ds);
        }
    }

    /// The elastic trial and its test in lanes; when all four pass (most points of a slope
    /// at rest) that is all. Else each point that did not pass settles alone, and the
    /// plastic strains of those that yielded are found together in lanes (a chain of two
    /// divisions and a square root each). Every point gets the bits `update` gives it.
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, plastic: [&mut PlasticStrain; LANES]) {
        *stress += self.elasticity.stress_increment(de);
        let elastic = self.elastic_lanes(stress);
        if elastic == ALL_LANES {
            return;
        }
        let (mut ds, mut yielded) = ([[0.0; 3]; LANES], 0u32);
        update_lane_by_lane(stress, de, [(); LANES].each_mut(), |lane, s, _, _| {
            if elastic & (1 << lane) == 0 {
                let (settled, correction) = self.settle(*s);
                *s = settled;
                if let Some(c) = correction {
                    (ds[lane], yielded) = (c, yielded | 1 << lane);
                }
            }
        });
        if yielded != 0 {
            let inc = self
                .plastic_strain_increment(std::array::from_fn(|i| gather(|lane| ds[lane][i])))
                .to_array();
            for (lane, eps) in plastic.into_iter().enumerate() {
                if yielded & (1 << lane) != 0 {
                    eps.0 += inc[lane];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform;
    use proptest::prelude::*;

    fn soil(c: f64, phi: f64, psi: f64) -> MohrCoulomb {
        MohrCoulomb::new(2000.0, 20e6, 0.3, c, phi, psi, None)
    }

    fn sorted(mut v: [f64; 3]) -> [f64; 3] {
        v.sort_by(|a, b| b.total_cmp(a));
        v
    }

    #[test]
    fn an_at_rest_stress_passes_the_invariant_bound_and_a_yielding_one_does_not() {
        let mc = soil(0.0, 20.0, 0.0);
        // K0 = ν/(1 − ν) = 0.667 at 100 kPa vertical: far inside the surface.
        let at_rest = Sym3 {
            xx: -66.7e3,
            yy: -100e3,
            zz: -66.7e3,
            xy: 0.0,
            yz: 0.0,
            zx: 0.0,
        };
        assert!(mc.surely_elastic(&at_rest));
        // σ1 = σ3/k lies on the surface (c = 0).
        let on = Sym3 {
            xx: -100e3 / mc.k,
            yy: -100e3,
            zz: -100e3 / mc.k,
            ..at_rest
        };
        assert!(!mc.surely_elastic(&on));
    }

    proptest! {
        #[test]
        fn returned_stress_lies_on_or_inside_the_yield_surface(
            a in -1e6f64..3e5, b in -1e6f64..3e5, c_ in -1e6f64..3e5,
            coh in 0.0f64..5e4, phi in 0.0f64..45.0, psi_frac in 0.0f64..1.0,
        ) {
            let mc = soil(coh, phi, psi_frac * phi);
            let trial = sorted([a, b, c_]);
            let (s, kind) = mc.return_principal(trial);
            let scale = trial.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(coh).max(1.0);
            let f = mc.yield_function(sorted(s));
            prop_assert!(f <= 1e-9 * scale, "f = {f} for {trial:?} -> {s:?} ({kind:?})");
            if kind != Return::Elastic {
                prop_assert!(f.abs() <= 1e-9 * scale, "not on the surface: f = {f} ({kind:?})");
            }
            prop_assert!(sorted(s)[0] <= mc.tension_cutoff + 1e-9 * scale);
        }

        #[test]
        fn the_invariant_bound_never_passes_a_stress_that_yields(
            xx in -1e6f64..3e5, yy in -1e6f64..3e5, zz in -1e6f64..3e5,
            xy in -3e5f64..3e5, yz in -3e5f64..3e5, zx in -3e5f64..3e5,
            coh in 0.0f64..5e4, phi in 0.0f64..45.0,
        ) {
            let mc = soil(coh, phi, 0.0);
            let s = Sym3 { xx, yy, zz, xy, yz, zx };
            if mc.surely_elastic(&s) {
                let p = s.principal_values();
                let scale = p.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1.0);
                prop_assert!(mc.yield_function(p) <= 1e-12 * scale, "{s:?}");
                prop_assert!(p[0] <= mc.tension_cutoff + 1e-12 * scale);
            }
        }

        #[test]
        fn the_near_planar_bound_passes_no_stress_the_exact_test_fails(
            s3 in -1e6f64..-1e3, mid in 0.0f64..1.0, rel in -1e-8f64..1e-8,
            angle in 0.0f64..3.2, magnitude in -12.0f64..3.0, a in -1.0f64..1.0, b in -1.0f64..1.0,
            coh in 0.0f64..5e4, phi in 5.0f64..45.0,
        ) {
            // Principal values σ1 within 1e-8 (relative) of the surface and σ3 in the x-y plane,
            // turned by `angle`, σ2 along z, and out-of-plane shear of about 10^magnitude Pa:
            // where the bound's margin is all that stands between a pass and a wrong pass.
            let mc = soil(coh, phi, 0.0);
            let s1 = (s3 + mc.sigma_c) / mc.k * (1.0 + rel);
            let (c, d) = (0.5 * (s1 + s3), 0.5 * (s1 - s3));
            let out = 10f64.powf(magnitude);
            let s = Sym3 {
                xx: c + d * (2.0 * angle).cos(),
                yy: c - d * (2.0 * angle).cos(),
                zz: s3 + mid * (s1 - s3),
                xy: d * (2.0 * angle).sin(),
                yz: a * out,
                zx: b * out,
            };
            if mc.within(mc.near_planar_bound(&s)) {
                // Exactly the test `update` makes after the eigen-decomposition: the bound
                // standing in for it must not change a single decision.
                prop_assert!(mc.admissible(s.eigen().0), "{s:?}");
            }
        }

        #[test]
        fn stresses_inside_the_surface_return_unchanged(
            s3 in -1e6f64..-1e3, f1 in 0.0f64..1.0, f2 in 0.0f64..1.0,
        ) {
            let mc = soil(1e4, 30.0, 0.0);
            // σ1 between σ3 and the limit (σ3 + σc)/k, σ2 in between.
            let s1 = s3 + f1 * ((s3 + mc.sigma_c) / mc.k - s3) * 0.999;
            let s2 = s3 + f2 * (s1 - s3);
            let (s, kind) = mc.return_principal([s1, s2, s3]);
            prop_assert_eq!(kind, Return::Elastic);
            prop_assert_eq!(s, [s1, s2, s3]);
        }
    }

    #[test]
    fn a_nearly_planar_stress_just_inside_the_surface_skips_the_eigen_decomposition() {
        // A 3D body in plane strain: yz and zx of round-off size. 1e-6 inside the surface the
        // invariant bound cannot tell, the near-planar bound can; 1e-6 outside, neither passes.
        let mc = soil(2e3, 20.0, 0.0);
        let s3 = -2e5;
        for (rel, inside) in [(-1e-6, true), (1e-6, false)] {
            let s1 = (s3 + mc.sigma_c) / mc.k * (1.0 - rel);
            let s = Sym3 {
                xx: s1,
                yy: s3,
                zz: 0.5 * (s1 + s3),
                xy: 0.0,
                yz: 2e-9,
                zx: -1e-9,
            };
            assert_eq!(mc.admissible(s.eigen().0), inside, "{s:?}");
            assert!(!mc.within(mc.invariant_bound(&s)), "invariant bound passed {s:?}");
            assert_eq!(mc.surely_elastic(&s), inside, "{s:?}");
        }
    }

    #[test]
    fn apex_return_of_a_cohesionless_soil_gives_zero_stress() {
        let mc = soil(0.0, 20.0, 0.0);
        let (s, kind) = mc.return_principal([2e4, 1e4, 5e3]);
        assert_eq!(kind, Return::Apex);
        assert_eq!(s, [0.0; 3]);
    }

    #[test]
    fn plastic_flow_with_zero_dilatancy_keeps_the_volume_on_the_plane() {
        // Plane return: Δε_p ∝ ∂g/∂σ = (m, 0, −1) with m = 1 for ψ = 0 has zero trace, so the
        // correction Δσ = D Δε_p = 2G Δε_p leaves the mean stress unchanged.
        let mc = soil(1e4, 30.0, 0.0);
        let trial = [-1e5, -2e5, -6e5];
        let (s, kind) = mc.return_principal(trial);
        assert_eq!(kind, Return::Plane);
        let ds: f64 = (0..3).map(|i| trial[i] - s[i]).sum();
        assert!(ds.abs() < 1e-9 * 6e5, "mean stress changed by {ds}");
        // With ψ = φ the same return dilates, which shows up as a change of mean stress.
        let assoc = soil(1e4, 30.0, 30.0);
        let (sa, _) = assoc.return_principal(trial);
        let dsa: f64 = (0..3).map(|i| trial[i] - sa[i]).sum();
        assert!(dsa > 1e3, "associated flow must change the mean stress: {dsa}");
    }

    #[test]
    fn flow_direction_follows_the_dilatancy_angle() {
        // Plastic strain Δε_p = D⁻¹(σ_trial − σ): its principal ratio ε1/ε3 = −m.
        for psi in [0.0, 10.0, 20.0] {
            let mc = soil(5e3, 30.0, psi);
            let trial = [-1e5, -2e5, -6e5];
            let (s, kind) = mc.return_principal(trial);
            assert_eq!(kind, Return::Plane);
            let e = mc.elasticity;
            let ym = e.shear * (3.0 * e.lambda + 2.0 * e.shear) / (e.lambda + e.shear);
            let nu = e.lambda / (2.0 * (e.lambda + e.shear));
            let ds: Vec<f64> = (0..3).map(|i| trial[i] - s[i]).collect();
            let eps = |i: usize, j: usize, k: usize| (ds[i] - nu * (ds[j] + ds[k])) / ym;
            let (e1, e2, e3) = (eps(0, 1, 2), eps(1, 0, 2), eps(2, 0, 1));
            let m = (1.0 + psi.to_radians().sin()) / (1.0 - psi.to_radians().sin());
            assert!(e2.abs() < 1e-12, "no flow along σ2: {e2}");
            assert!((e1 / e3 + m).abs() < 1e-9, "ψ = {psi}: ε1/ε3 = {}", e1 / e3);
        }
    }

    /// The principal stresses at the end of a triaxial test ([`crate::testing::triaxial`]).
    fn triaxial(mc: &MohrCoulomb, confinement: f64, de_axial: f64, steps: usize) -> [f64; 3] {
        let path = crate::testing::triaxial(mc, confinement, de_axial, steps);
        path.last().expect("steps > 0").0.principal_values()
    }

    #[test]
    fn triaxial_compression_reaches_the_analytic_mohr_coulomb_peak() {
        // Confined at σ3' = 100 kPa (compression positive), axial strain until failure.
        // Analytic peak: σ1' = σ3' (1 + sin φ)/(1 − sin φ) + 2c cos φ/(1 − sin φ).
        let (c, phi) = (10e3, 30.0f64);
        let mc = MohrCoulomb::new(2000.0, 20e6, 0.3, c, phi, 0.0, None);
        let p = triaxial(&mc, -100e3, -1e-4, 300);
        let sp = phi.to_radians().sin();
        let peak = 100e3 * (1.0 + sp) / (1.0 - sp) + 2.0 * c * phi.to_radians().cos() / (1.0 - sp);
        assert!((-p[2] / peak - 1.0).abs() < 1e-6, "σ1' = {} vs {}", -p[2], peak);
        assert!((-p[0] / 100e3 - 1.0).abs() < 1e-6, "σ3' = {}", -p[0]);
    }

    #[test]
    fn uniaxial_compression_reaches_the_unconfined_strength() {
        // Unconfined (σ3' = 0): σ1' = 2c cos φ/(1 − sin φ).
        let (c, phi) = (25e3, 25.0f64);
        let mc = MohrCoulomb::new(2000.0, 20e6, 0.25, c, phi, 5.0, None);
        let p = triaxial(&mc, 0.0, -1e-4, 300);
        let ucs = 2.0 * c * phi.to_radians().cos() / (1.0 - phi.to_radians().sin());
        assert!((-p[2] / ucs - 1.0).abs() < 1e-6, "σ1' = {} vs {}", -p[2], ucs);
    }

    #[test]
    fn tension_cut_off_caps_the_largest_principal_stress() {
        let mc = MohrCoulomb::new(2000.0, 20e6, 0.3, 50e3, 30.0, 0.0, Some(10e3));
        let (s, _) = mc.return_principal([40e3, -20e3, -50e3]);
        assert!(s[0] <= 10e3 + 1e-6, "{s:?}");
        assert!(mc.yield_function(sorted(s)) <= 1e-6);
    }

    #[test]
    fn four_points_in_lanes_get_the_bits_each_gets_alone_elastic_or_yielding_planar_or_not() {
        // Soil stresses about an at-rest state (σv = −200 kPa, K0 = 0.6) with shear noise, and
        // strain increments of 0.2 % or 1 %: groups all elastic (the lanes' fast path), groups
        // where some lanes yield, and groups mixing planar and general states.
        let mc = MohrCoulomb::new(2000.0, 20e6, 0.3, 5e3, 30.0, 5.0, Some(2e3));
        let mut seed = 11;
        let (mut all_elastic, mut some_yield, mut mixed_planes) = (0, 0, 0);
        for group in 0..4000 {
            let planar: [bool; LANES] = std::array::from_fn(|q| match group % 3 {
                0 => true,
                1 => false,
                _ => q % 2 == 0,
            });
            let strain = if group % 2 == 0 { 2e-3 } else { 1e-2 };
            let mut tensor = |scale: f64, base: [f64; 3], planar: bool| {
                let mut t = Sym3 {
                    xx: base[0] + scale * uniform(&mut seed),
                    yy: base[1] + scale * uniform(&mut seed),
                    zz: base[2] + scale * uniform(&mut seed),
                    xy: scale * uniform(&mut seed),
                    yz: scale * uniform(&mut seed),
                    zx: scale * uniform(&mut seed),
                };
                if planar {
                    (t.yz, t.zx) = (0.0, 0.0);
                }
                t
            };
            let stress: [Sym3; LANES] =
                std::array::from_fn(|q| tensor(30e3, [-120e3, -200e3, -120e3], planar[q]));
            let de: [Sym3; LANES] = std::array::from_fn(|q| tensor(strain, [0.0; 3], planar[q]));
            let eps0: [PlasticStrain; LANES] = std::array::from_fn(|q| PlasticStrain(q as f64 * 1e-3));
            let mut alone = stress;
            let mut eps_alone = eps0;
            for q in 0..LANES {
                mc.update(&mut alone[q], &de[q], &mut eps_alone[q]);
            }
            let mut lanes = Sym3x4::gather(|q| stress[q]);
            let mut eps_lanes = eps0;
            let trial = lanes + mc.elasticity.stress_increment(&Sym3x4::gather(|q| de[q]));
            match mc.elastic_lanes(&trial) {
                ALL_LANES => all_elastic += 1,
                0 if group % 3 == 2 => mixed_planes += 1,
                _ => some_yield += 1,
            }
            mc.update4(&mut lanes, &Sym3x4::gather(|q| de[q]), eps_lanes.each_mut());
            let bits = |s: &[Sym3], e: &[PlasticStrain]| -> Vec<u64> {
                s.iter()
                    .flat_map(|s| s.to_array())
                    .chain(e.iter().map(|e| e.0))
                    .map(f64::to_bits)
                    .collect()
            };
            assert_eq!(
                bits(&lanes.lanes(), &eps_lanes),
                bits(&alone, &eps_alone),
                "group {group}: {stress:?} + {de:?}"
            );
        }
        // Each path ran often enough to count: the test is void if the mix drifts.
        for (what, n) in [
            ("all elastic", all_elastic),
            ("some yield", some_yield),
            ("mixed planes", mixed_planes),
        ] {
            assert!(n >= 300, "{what}: {n} groups of 4000");
        }
    }
}
