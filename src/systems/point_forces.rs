//! Forces on a point besides its stress's divergence, which particle-to-grid maps with the
//! internal force. Each source is its own type here; [`PointForces`] holds those that act
//! in a step and [`crate::systems::p2g`] asks it point by point, knowing none of them. A
//! new source is its own type, a field of [`PointForces`] (unless the dimension decides
//! it, as the hoop stress's) and its term in [`OnColumns::at`].
//!
//! - [`PoreWater`]: the pore water's load V_p (−∇u_p) on a point below its piezometric
//!   surface ([`crate::water::Water::body_force`]: buoyancy, seepage, and with them the
//!   pressure of open water on a submerged surface); applied load.
//! - [`Hoop`]: in axisymmetry (per radian, x = r) the hoop stress's −V_p σ_θθ w_ip / r_p
//!   along r: the weak form of ∂σ_rr/∂r + ∂σ_rz/∂z + (σ_rr − σ_θθ)/r = 0 with volumes
//!   r dr dz, whose σ_rr/r term the in-plane divergence of V σ already holds; internal.
//!
//! The sources are called directly, not through a table of pointers, so that the point
//! loop inlines them (docs/tried-and-dropped.md); a dry plane scene asks
//! nothing and pays nothing.

use crate::components::MaterialId;
use crate::dim::{Dim, Vector};
use crate::model::Model;
use crate::tensor::StoredSym;
use crate::water::Water;

/// The sources that act in one step. The hoop source is no field: it acts exactly when
/// the dimension is axisymmetric, which [`OnColumns::at`] asks of `D`.
pub struct PointForces<'a> {
    water: Option<PoreWater<'a>>,
}

impl<'a> PointForces<'a> {
    /// The sources of a `model` solved in steps of `dt` (s), in the step that ends at
    /// `time` (s).
    pub fn of(model: &'a Model, dt: f64, time: f64) -> Self {
        PointForces {
            water: model.water.as_ref().map(|water| PoreWater {
                water,
                // The pore water's load rises with gravity's ramp, as the weight it buoys does.
                ramp: model.gravity.map_or(1.0, |g| g.step_factor(time, dt)),
            }),
        }
    }

    /// Whether a source reads the points' materials (the archetype's `MaterialId` column).
    pub fn need_materials(&self) -> bool {
        self.water.is_some()
    }

    /// The sources over one archetype's points, of materials `ids` where it has them.
    pub fn on<'b>(&'b self, ids: Option<&'b [MaterialId]>) -> OnColumns<'b> {
        OnColumns {
            water: self.water.as_ref().zip(ids).map(|(w, ids)| (*w, ids)),
        }
    }
}

/// [`PointForces`] bound to one archetype's columns: a few words, copied into the point
/// loop (reached through fewer pointers there, the loop keeps them in registers).
#[derive(Clone, Copy)]
pub struct OnColumns<'b> {
    water: Option<(PoreWater<'b>, &'b [MaterialId])>,
}

impl OnColumns<'_> {
    /// The sum of the sources' forces per unit mass (N/kg) on point `p` at `x` (m), of mass
    /// `mass` (kg), volume `volume` and stress `stress`, and its applied part: `None` when
    /// none acts there. In a fixed order, so that the sum is the same on every run.
    #[inline(always)]
    pub fn at<D: Dim>(
        &self,
        p: usize,
        x: D::Vec,
        mass: f64,
        volume: f64,
        stress: &D::Stress,
    ) -> Option<(D::Vec, D::Vec)> {
        let pore = self
            .water
            .and_then(|(w, ids)| w.force::<D>(ids[p], x, mass, volume));
        // The hoop source acts exactly when `D` is axisymmetric: asked of `D`, the branch is
        // settled when the loop is compiled.
        if !D::AXISYMMETRIC {
            return pore.map(|a| (a, a));
        }
        let hoop = Hoop::force::<D>(x, mass, volume, stress);
        Some(match pore {
            Some(a) => (a + hoop, a),
            None => (hoop, D::Vec::ZERO),
        })
    }
}

/// The pore water's load on a point below its surface, V_p (−∇u_p) / m_p, times the
/// gravity ramp's factor this step.
#[derive(Clone, Copy)]
pub struct PoreWater<'a> {
    water: &'a Water,
    ramp: f64,
}

impl PoreWater<'_> {
    /// The force per unit mass (N/kg) on a point of material `id` at `x` (m), of mass
    /// `mass` (kg) and volume `volume`; `None` above its surface.
    #[inline(always)]
    fn force<D: Dim>(&self, id: MaterialId, x: D::Vec, mass: f64, volume: f64) -> Option<D::Vec> {
        let b = self.water.body_force(id.0, D::vec_to3(x), volume);
        (b != [0.0; 3]).then(|| D::vec_from(b) * (volume * self.ramp / mass))
    }
}

/// The hoop stress's force along r per unit mass, −V_p σ_θθ / (r_p m_p) (internal).
pub struct Hoop;

impl Hoop {
    #[inline(always)]
    fn force<D: Dim>(x: D::Vec, mass: f64, volume: f64, stress: &D::Stress) -> D::Vec {
        let (r, neg_vol) = (x.get(0), -volume);
        D::vec_from([neg_vol * stress.to_sym3().zz / (r * mass), 0.0, 0.0])
    }
}
