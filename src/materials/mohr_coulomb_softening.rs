//! Mohr-Coulomb with strain softening: c, φ and ψ fall linearly with the accumulated
//! equivalent plastic strain κ from their peak values to residual ones, reached at
//! κ = `softening_strain`, and stay there:
//!
//!   x(κ) = x_peak + (x_residual − x_peak) · min(κ / κ_r, 1)   for x in c, φ, ψ.
//!
//! Each step returns the stress with the strength of κ at the start of the step (explicit
//! in κ, as the step is in time) and then adds the step's plastic strain to κ, with the
//! return mapping and the plastic strain measure of [`MohrCoulomb`]. A point that never
//! yielded (κ = 0) and one past the residual use constants built once; only points on the
//! way down build theirs.

use super::mohr_coulomb::{check_strength, reduce_angle};
use super::{
    update_lane_by_lane, Elasticity, Material, MaterialState, MohrCoulomb, PlasticStrain, SceneMaterial,
};
use crate::error::Refusal;
use crate::infra::lanes::LANES;
use crate::tensor::{Sym3, Sym3x4};
use serde::{Deserialize, Serialize};

/// Scene entry `MohrCoulombSoftening(density, youngs_modulus, poisson_ratio, cohesion,
/// friction_angle, dilatancy_angle, residual_cohesion, residual_friction_angle,
/// residual_dilatancy_angle, softening_strain, tension_cutoff)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "MohrCoulombSoftening")]
pub struct MohrCoulombSofteningSpec {
    /// ρ (kg/m³), > 0.
    pub density: f64,
    /// E (Pa), > 0.
    pub youngs_modulus: f64,
    /// ν, in [0, 0.5).
    pub poisson_ratio: f64,
    /// Peak c (Pa), ≥ 0.
    pub cohesion: f64,
    /// Peak φ (degrees), in [0, 90).
    pub friction_angle: f64,
    /// Peak ψ (degrees), in [0, φ].
    #[serde(default)]
    pub dilatancy_angle: f64,
    /// Residual c (Pa), in [0, peak c].
    pub residual_cohesion: f64,
    /// Residual φ (degrees), in [0, peak φ].
    pub residual_friction_angle: f64,
    /// Residual ψ (degrees), in [0, residual φ].
    #[serde(default)]
    pub residual_dilatancy_angle: f64,
    /// κ_r: the accumulated equivalent plastic strain at which the residual strength is
    /// reached (dimensionless), > 0.
    pub softening_strain: f64,
    /// Largest tensile principal stress (Pa); at most, and by default, c·cot φ of the
    /// current strength.
    #[serde(default)]
    pub tension_cutoff: Option<f64>,
}

impl SceneMaterial for MohrCoulombSofteningSpec {
    type Model = MohrCoulombSoftening;
    fn model(&self, at: &dyn Fn(&str) -> String) -> Result<MohrCoulombSoftening, Refusal> {
        let elasticity = Elasticity::checked(at, self.density, self.youngs_modulus, self.poisson_ratio)?;
        let peak = (self.cohesion, self.friction_angle, self.dilatancy_angle);
        check_strength(at, peak, self.tension_cutoff)?;
        let residual = (
            self.residual_cohesion,
            self.residual_friction_angle,
            self.residual_dilatancy_angle,
        );
        let residual_at = |f: &str| at(&format!("residual_{f}"));
        check_strength(&residual_at, residual, None)?;
        if residual.0 > peak.0 {
            return Err(Refusal::new(
                at("residual_cohesion"),
                format!("must be at most the peak c = {} Pa, found {}", peak.0, residual.0),
            ));
        }
        if residual.1 > peak.1 {
            return Err(Refusal::new(
                at("residual_friction_angle"),
                format!("must be at most the peak φ = {}°, found {}°", peak.1, residual.1),
            ));
        }
        let k = self.softening_strain;
        if !(k > 0.0 && k.is_finite()) {
            return Err(Refusal::new(
                at("softening_strain"),
                format!("must be > 0, found {k}"),
            ));
        }
        Ok(MohrCoulombSoftening {
            density: self.density,
            elasticity,
            youngs_modulus: self.youngs_modulus,
            poisson_ratio: self.poisson_ratio,
            peak,
            residual,
            softening_strain: k,
            tension_cutoff: self.tension_cutoff,
            at_peak: Box::new(self.at(peak)),
            at_residual: Box::new(self.at(residual)),
        })
    }
    fn dilatancy_angle(&self) -> f64 {
        self.dilatancy_angle.max(self.residual_dilatancy_angle)
    }
    /// Peak and residual c, tan φ, tan ψ and an explicit cut-off, each divided by `factor`.
    fn reduce_strength(&mut self, factor: f64) -> bool {
        self.cohesion /= factor;
        self.friction_angle = reduce_angle(self.friction_angle, factor);
        self.dilatancy_angle = reduce_angle(self.dilatancy_angle, factor);
        self.residual_cohesion /= factor;
        self.residual_friction_angle = reduce_angle(self.residual_friction_angle, factor);
        self.residual_dilatancy_angle = reduce_angle(self.residual_dilatancy_angle, factor);
        if let Some(t) = &mut self.tension_cutoff {
            *t /= factor;
        }
        true
    }
}

impl MohrCoulombSofteningSpec {
    /// The perfectly plastic model of one strength (c in Pa, φ and ψ in degrees).
    fn at(&self, (c, phi, psi): (f64, f64, f64)) -> MohrCoulomb {
        let (rho, e, nu) = (self.density, self.youngs_modulus, self.poisson_ratio);
        MohrCoulomb::new(rho, e, nu, c, phi, psi, self.tension_cutoff)
    }
}

/// The accumulated equivalent plastic strain κ of a softening point (dimensionless), the
/// measure of [`PlasticStrain`]; the strength follows from it.
#[derive(Clone, Copy, Debug, PartialEq, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(transparent)]
pub struct SofteningStrain(pub f64);

impl MaterialState for SofteningStrain {
    fn plastic_strain(&self) -> f64 {
        self.0
    }
    fn is_finite(&self) -> bool {
        self.0.is_finite()
    }
}

/// Mohr-Coulomb with linear strain softening (see the module's documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct MohrCoulombSoftening {
    /// Mass density ρ (kg/m³).
    pub density: f64,
    /// Elastic constants.
    pub elasticity: Elasticity,
    /// E (Pa), as given.
    pub youngs_modulus: f64,
    /// ν, as given.
    pub poisson_ratio: f64,
    /// Peak (c in Pa, φ, ψ in degrees).
    pub peak: (f64, f64, f64),
    /// Residual (c in Pa, φ, ψ in degrees).
    pub residual: (f64, f64, f64),
    /// κ_r (dimensionless).
    pub softening_strain: f64,
    /// An explicit tension cut-off (Pa).
    pub tension_cutoff: Option<f64>,
    // Boxed: the model table's enum stays as small as its other models.
    at_peak: Box<MohrCoulomb>,
    at_residual: Box<MohrCoulomb>,
}

impl MohrCoulombSoftening {
    /// The fraction of the way from peak to residual strength at κ, in [0, 1].
    pub fn softened(&self, kappa: f64) -> f64 {
        (kappa / self.softening_strain).clamp(0.0, 1.0)
    }

    /// Calls `f` with the perfectly plastic model of the strength at κ.
    #[inline(always)]
    fn with_strength<R>(&self, kappa: f64, f: impl FnOnce(&MohrCoulomb) -> R) -> R {
        let s = self.softened(kappa);
        if s == 0.0 {
            return f(&self.at_peak);
        }
        if s == 1.0 {
            return f(&self.at_residual);
        }
        let mix = |p: f64, r: f64| p + (r - p) * s;
        let (p, r) = (self.peak, self.residual);
        f(&MohrCoulomb::new(
            self.density,
            self.youngs_modulus,
            self.poisson_ratio,
            mix(p.0, r.0),
            mix(p.1, r.1),
            mix(p.2, r.2),
            self.tension_cutoff,
        ))
    }
}

impl Material for MohrCoulombSoftening {
    type State = SofteningStrain;
    fn density(&self) -> f64 {
        self.density
    }
    fn p_wave_modulus(&self) -> f64 {
        self.elasticity.p_wave()
    }
    fn admits(&self, stress: &Sym3, state: &SofteningStrain) -> bool {
        self.with_strength(state.0, |mc| mc.admits(stress, &PlasticStrain(state.0)))
    }
    /// Tresca at the point's softened strength (c at κ when φ there is 0).
    fn undrained_strength(&self, stress: &Sym3, state: &SofteningStrain) -> Option<f64> {
        self.with_strength(state.0, |mc| {
            mc.undrained_strength(stress, &PlasticStrain(state.0))
        })
    }
    /// Coulomb's line at the point's softened c and φ.
    fn plane_strength(&self, stress: &Sym3, state: &SofteningStrain) -> Option<(f64, f64)> {
        self.with_strength(state.0, |mc| mc.plane_strength(stress, &PlasticStrain(state.0)))
    }
    #[inline(always)]
    fn update(&self, stress: &mut Sym3, de: &Sym3, state: &mut SofteningStrain) {
        self.with_strength(state.0, |mc| {
            let mut eps = PlasticStrain(state.0);
            mc.update(stress, de, &mut eps);
            state.0 = eps.0;
        });
    }
    /// In lanes when the four points share a strength (all intact or all residual), else
    /// one by one.
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, state: [&mut SofteningStrain; LANES]) {
        let s: [f64; LANES] = std::array::from_fn(|q| self.softened(state[q].0));
        if s.iter().all(|&x| x == s[0]) && (s[0] == 0.0 || s[0] == 1.0) {
            let mc = if s[0] == 0.0 {
                &self.at_peak
            } else {
                &self.at_residual
            };
            let mut eps: [PlasticStrain; LANES] = std::array::from_fn(|q| PlasticStrain(state[q].0));
            mc.update4(stress, de, eps.each_mut());
            for (st, e) in state.into_iter().zip(eps) {
                st.0 = e.0;
            }
        } else {
            update_lane_by_lane(stress, de, state, |_, s, de, st| self.update(s, de, st));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec() -> MohrCoulombSofteningSpec {
        MohrCoulombSofteningSpec {
            density: 2000.0,
            youngs_modulus: 20e6,
            poisson_ratio: 0.3,
            cohesion: 20e3,
            friction_angle: 30.0,
            dilatancy_angle: 0.0,
            residual_cohesion: 2e3,
            residual_friction_angle: 20.0,
            residual_dilatancy_angle: 0.0,
            softening_strain: 0.02,
            tension_cutoff: None,
        }
    }

    /// A triaxial compression test ([`crate::testing::triaxial`]): the largest axial
    /// stress reached (Pa, compression positive), the last principal stresses and κ.
    fn triaxial(
        m: &MohrCoulombSoftening,
        confinement: f64,
        de_axial: f64,
        steps: usize,
    ) -> (f64, [f64; 3], f64) {
        let path = crate::testing::triaxial(m, confinement, de_axial, steps);
        let largest = path.iter().map(|(s, _)| -s.zz).fold(0.0, f64::max);
        let (s, kappa) = path.last().expect("steps > 0");
        (largest, s.principal_values(), kappa.0)
    }

    /// σ1' at failure under σ3' (compression positive): σ3' (1 + sin φ)/(1 − sin φ) +
    /// 2c cos φ/(1 − sin φ), the Mohr-Coulomb criterion.
    fn strength(c: f64, phi_deg: f64, sigma_3: f64) -> f64 {
        let (s, co) = (phi_deg.to_radians().sin(), phi_deg.to_radians().cos());
        sigma_3 * (1.0 + s) / (1.0 - s) + 2.0 * c * co / (1.0 - s)
    }

    #[test]
    fn triaxial_compression_peaks_at_the_peak_strength_and_ends_at_the_residual() {
        let m = spec().model(&|f| f.to_string()).unwrap();
        // Confined at σ3' = 100 kPa; 6 % of axial strain, three times κ_r = 2 %.
        let (largest, p, kappa) = triaxial(&m, -100e3, -1e-4, 600);
        // The first step that yields returns to the peak surface (κ = 0 at its start).
        let peak = strength(20e3, 30.0, 100e3);
        assert!(
            (largest / peak - 1.0).abs() < 1e-6,
            "largest σ1' = {largest} against the peak {peak}"
        );
        // Past κ_r: the residual strength, under the same confinement.
        let residual = strength(2e3, 20.0, 100e3);
        assert!(kappa > 0.02, "κ = {kappa}");
        assert!(
            (-p[2] / residual - 1.0).abs() < 1e-6,
            "σ1' = {} against the residual {residual}",
            -p[2]
        );
        assert!((-p[0] / 100e3 - 1.0).abs() < 1e-6, "σ3' = {}", -p[0]);
    }

    #[test]
    fn without_softening_it_is_mohr_coulomb_bit_for_bit() {
        let mut s = spec();
        (s.residual_cohesion, s.residual_friction_angle) = (s.cohesion, s.friction_angle);
        let soft = s.model(&|f| f.to_string()).unwrap();
        let mc = MohrCoulomb::new(2000.0, 20e6, 0.3, 20e3, 30.0, 0.0, None);
        let (mut a, mut b) = (
            Sym3::diagonal(-50e3, -50e3, -50e3),
            Sym3::diagonal(-50e3, -50e3, -50e3),
        );
        let (mut ka, mut kb) = (SofteningStrain(0.0), PlasticStrain(0.0));
        for step in 0..400 {
            let de = Sym3 {
                xx: 1e-4,
                yy: -2e-4,
                xy: 3e-5 * (step % 7) as f64,
                ..Sym3::ZERO
            };
            soft.update(&mut a, &de, &mut ka);
            mc.update(&mut b, &de, &mut kb);
            assert_eq!(
                a.to_array().map(f64::to_bits),
                b.to_array().map(f64::to_bits),
                "step {step}"
            );
            assert_eq!(ka.0.to_bits(), kb.0.to_bits());
        }
        assert!(ka.0 > 0.0, "the points yielded");
    }

    #[test]
    fn four_points_in_lanes_get_the_bits_each_gets_alone() {
        let m = spec().model(&|f| f.to_string()).unwrap();
        // Intact, on the way down, residual, and intact again: both paths of update4.
        for kappas in [[0.0; 4], [0.0, 0.01, 0.05, 0.0], [0.03; 4]] {
            let stress: [Sym3; LANES] =
                std::array::from_fn(|q| Sym3::diagonal(-60e3, -100e3 - 1e4 * q as f64, -60e3));
            let de = Sym3::diagonal(5e-3, -8e-3, 0.0);
            let mut alone = stress;
            let mut k_alone = kappas.map(SofteningStrain);
            for q in 0..LANES {
                m.update(&mut alone[q], &de, &mut k_alone[q]);
            }
            let mut lanes = Sym3x4::gather(|q| stress[q]);
            let mut k_lanes = kappas.map(SofteningStrain);
            m.update4(&mut lanes, &Sym3x4::gather(|_| de), k_lanes.each_mut());
            assert_eq!(lanes.lanes(), alone);
            assert_eq!(k_lanes, k_alone);
            assert!(
                k_alone.iter().zip(kappas).all(|(k, k0)| k.0 > k0),
                "every point yielded"
            );
        }
    }

    #[test]
    fn a_residual_above_the_peak_is_refused_by_field() {
        let mut s = spec();
        s.residual_friction_angle = 35.0;
        let crate::error::Refusal { field, rule } = s.model(&|f| format!("materials.soil.{f}")).unwrap_err();
        assert_eq!(field, "materials.soil.residual_friction_angle");
        assert!(rule.contains("peak φ = 30°"), "{rule}");
        let mut s = spec();
        s.softening_strain = 0.0;
        assert_eq!(s.model(&|f| f.to_string()).unwrap_err().field, "softening_strain");
    }
}
