//! Linear isotropic elasticity (Hooke's law in rate form).

use super::{Elasticity, Material, SceneMaterial};
use crate::error::Refusal;
use crate::infra::lanes::LANES;
use crate::tensor::{Sym3, Sym3x4};
use serde::{Deserialize, Serialize};

/// Scene entry `LinearElastic(density, youngs_modulus, poisson_ratio)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "LinearElastic")]
pub struct LinearElasticSpec {
    /// ρ (kg/m³), > 0.
    pub density: f64,
    /// E (Pa), > 0.
    pub youngs_modulus: f64,
    /// ν, in [0, 0.5).
    pub poisson_ratio: f64,
}

impl SceneMaterial for LinearElasticSpec {
    type Model = LinearElastic;
    fn model(&self, at: &dyn Fn(&str) -> String) -> Result<LinearElastic, Refusal> {
        let elasticity = Elasticity::checked(at, self.density, self.youngs_modulus, self.poisson_ratio)?;
        Ok(LinearElastic {
            density: self.density,
            elasticity,
        })
    }
}

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
    type State = ();
    fn density(&self) -> f64 {
        self.density
    }
    fn p_wave_modulus(&self) -> f64 {
        self.elasticity.p_wave()
    }
    #[inline(always)]
    fn update(&self, stress: &mut Sym3, de: &Sym3, _state: &mut ()) {
        *stress += self.elasticity.stress_increment(de);
    }
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, _state: [&mut (); LANES]) {
        *stress += self.elasticity.stress_increment(de);
    }
}
