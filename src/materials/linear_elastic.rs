//! Linear isotropic elasticity (Hooke's law in rate form).

use super::{Elasticity, Material};
use crate::lanes::LANES;
use crate::tensor::{Sym3, Sym3x4};

/// Linear elastic material: Δσ = λ tr(Δε) I + 2G Δε.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearElastic {
    /// Mass density ρ (kg/m³).
    pub density: f64,
    /// Elastic constants.
    pub elasticity: Elasticity,
}

impl LinearElastic {
    /// From density (kg/m³), Young's modulus (Pa) and Poisson's ratio.
    pub fn new(density: f64, youngs_modulus: f64, poisson_ratio: f64) -> Self {
        LinearElastic {
            density,
            elasticity: Elasticity::new(youngs_modulus, poisson_ratio),
        }
    }
}

impl Material for LinearElastic {
    fn density(&self) -> f64 {
        self.density
    }
    fn p_wave_modulus(&self) -> f64 {
        self.elasticity.p_wave()
    }
    fn is_plastic(&self) -> bool {
        false
    }
    #[inline(always)]
    fn update(&self, stress: &mut Sym3, de: &Sym3, _plastic: Option<&mut f64>) {
        *stress += self.elasticity.stress_increment(de);
    }
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, _plastic: Option<[&mut f64; LANES]>) {
        *stress += self.elasticity.stress_increment(de);
    }
}
