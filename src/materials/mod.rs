//! Constitutive models, one per file, behind the [`Material`] trait.
//!
//! The stress update system applies the Jaumann rotation first and then hands each point's
//! strain increment to its material, so a material only integrates σ̇ = C : ε̇ (eq. 7) in a
//! fixed frame.

mod linear_elastic;
mod mohr_coulomb;

pub use linear_elastic::LinearElastic;
pub use mohr_coulomb::MohrCoulomb;

use crate::lanes::{Lanes, LANES};
use crate::tensor::{Sym, Sym3, Sym3x4};

/// A constitutive model.
pub trait Material: Send + Sync {
    /// Mass density ρ (kg/m³).
    fn density(&self) -> f64;
    /// P-wave (constrained) modulus M = K + 4G/3 (Pa), for the wave speed and time step.
    fn p_wave_modulus(&self) -> f64;
    /// True when the model carries plastic state ([`crate::components::PlasticStrain`]).
    fn is_plastic(&self) -> bool;
    /// Integrates the stress over one strain increment `de` (dimensionless, already in the
    /// rotated frame). `plastic` is the point's accumulated plastic strain when the model is
    /// plastic.
    fn update(&self, stress: &mut Sym3, de: &Sym3, plastic: Option<&mut f64>);
    /// [`Material::update`] for four points of this material side by side, one per lane,
    /// with the same bits for each as `update` would give it. By default lane by lane; linear
    /// elasticity does all four at once; Mohr-Coulomb tests all four for yield in lanes and
    /// returns one by one only the points that fail the test.
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, plastic: Option<[&mut f64; LANES]>) {
        update_lane_by_lane(stress, de, plastic, |_, s, de, eps| self.update(s, de, eps));
    }
}

/// Calls `update(lane, stress, de, plastic)` with each lane's stress, strain increment and
/// plastic strain in turn, and puts the stresses back into their lanes.
#[inline(always)]
pub fn update_lane_by_lane(
    stress: &mut Sym3x4,
    de: &Sym3x4,
    plastic: Option<[&mut f64; LANES]>,
    mut update: impl FnMut(usize, &mut Sym3, &Sym3, Option<&mut f64>),
) {
    let (mut s, de) = (stress.lanes(), de.lanes());
    // One loop each, so that an elastic material's loop carries no plastic strain.
    match plastic {
        Some(eps) => {
            for (lane, ((s, de), eps)) in s.iter_mut().zip(&de).zip(eps).enumerate() {
                update(lane, s, de, Some(eps));
            }
        }
        None => {
            for (lane, (s, de)) in s.iter_mut().zip(&de).enumerate() {
                update(lane, s, de, None);
            }
        }
    }
    *stress = Sym3x4::gather(|l| s[l]);
}

/// Isotropic elastic stiffness from Young's modulus and Poisson's ratio.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    /// Shear modulus G (Pa).
    pub shear: f64,
    /// Lamé's first parameter λ (Pa).
    pub lambda: f64,
}

impl Elasticity {
    /// From Young's modulus E (Pa) and Poisson's ratio ν.
    pub fn new(youngs_modulus: f64, poisson_ratio: f64) -> Self {
        let (e, nu) = (youngs_modulus, poisson_ratio);
        Elasticity {
            shear: e / (2.0 * (1.0 + nu)),
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        }
    }

    /// Bulk modulus K (Pa).
    pub fn bulk(&self) -> f64 {
        self.lambda + 2.0 / 3.0 * self.shear
    }

    /// P-wave modulus M = λ + 2G (Pa).
    pub fn p_wave(&self) -> f64 {
        self.lambda + 2.0 * self.shear
    }

    /// Stress increment C : de, of one point or four in lanes.
    #[inline(always)]
    pub fn stress_increment<T: Lanes>(&self, de: &Sym<T>) -> Sym<T> {
        let vol = T::splat(self.lambda) * de.trace();
        let g2 = T::splat(2.0 * self.shear);
        Sym {
            xx: vol + g2 * de.xx,
            yy: vol + g2 * de.yy,
            zz: vol + g2 * de.zz,
            xy: g2 * de.xy,
            yz: g2 * de.yz,
            zx: g2 * de.zx,
        }
    }
}

/// The materials a scene can name.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialModel {
    /// Linear elastic.
    LinearElastic(LinearElastic),
    /// Mohr-Coulomb elastic perfectly plastic.
    MohrCoulomb(MohrCoulomb),
}

impl MaterialModel {
    fn inner(&self) -> &dyn Material {
        match self {
            MaterialModel::LinearElastic(m) => m,
            MaterialModel::MohrCoulomb(m) => m,
        }
    }
}

impl Material for MaterialModel {
    fn density(&self) -> f64 {
        self.inner().density()
    }
    fn p_wave_modulus(&self) -> f64 {
        self.inner().p_wave_modulus()
    }
    fn is_plastic(&self) -> bool {
        self.inner().is_plastic()
    }
    #[inline]
    fn update(&self, stress: &mut Sym3, de: &Sym3, plastic: Option<&mut f64>) {
        // Static dispatch on the enum keeps the per-point call inlinable.
        match self {
            MaterialModel::LinearElastic(m) => m.update(stress, de, plastic),
            MaterialModel::MohrCoulomb(m) => m.update(stress, de, plastic),
        }
    }
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, plastic: Option<[&mut f64; LANES]>) {
        match self {
            MaterialModel::LinearElastic(m) => m.update4(stress, de, plastic),
            MaterialModel::MohrCoulomb(m) => m.update4(stress, de, plastic),
        }
    }
}
