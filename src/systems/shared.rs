//! What several systems share, kept here so that no system reaches into another's file:
//! how a node holds each axis of its velocity (a face condition or a prescribed motion),
//! and the points' loads set from a list.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::infra::columns::{col, col_mut, points_with};
use crate::model::Drive;
use hecs::{Archetype, World};

/// How a node holds one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// Not at all.
    Free,
    /// At zero (a face condition).
    Fixed,
    /// At the velocity of this prescribed motion.
    Driven(usize),
}

/// How `fixity` holds axis `axis`, given the scene's motions.
#[inline(always)]
pub fn hold(fixity: NodeFixity, axis: usize, drives: &[Drive]) -> Hold {
    if !fixity.is_fixed(axis) {
        return Hold::Free;
    }
    match fixity.driver() {
        Some(d) if drives[d].axes & (1 << axis) != 0 => Hold::Driven(d),
        _ => Hold::Fixed,
    }
}

/// Sets the held components of a nodal velocity: zero, or the driving motion's velocity.
#[inline(always)]
pub fn constrain<V: Vector>(v: &mut V, fixity: NodeFixity, dims: usize, drives: &[Drive]) {
    if fixity.0 != 0 {
        for a in 0..dims {
            match hold(fixity, a, drives) {
                Hold::Free => {}
                Hold::Fixed => v.set(a, 0.0),
                Hold::Driven(d) => v.set(a, drives[d].velocity[a]),
            }
        }
    }
}

/// Sets the point load of every point named in `loads` (point id, force: N; N/m in 2D,
/// x y z; sorted by id) to `scale` times its force. Loading stages and load control use it.
pub fn set_point_loads<D: Dim>(ctx: &Context<D>, loads: &[(u32, [f64; 3])], scale: f64) {
    for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
        let ids = col::<PointId>(arch);
        let mut f = col_mut::<PointLoad<D::Vec>>(arch);
        for (id, f) in ids.iter().zip(f.iter_mut()) {
            if let Ok(k) = loads.binary_search_by_key(&id.0, |l| l.0) {
                f.0 = D::vec_from(loads[k].1.map(|c| c * scale));
            }
        }
    }
}

/// The points that the cell means and the undrained clay's cell pore pressure average:
/// every point with a volume except those that carry a traction. A traction's points pass
/// it to the grid as point forces inside their cells, so the soil's stress jumps across
/// them, from the load below to none above: their own volumetric rate, mean stress and pore
/// pressure sample that jump, not the soil, and each keeps its own. Averaged with the rest,
/// they let an oedometer pressed at its top settle 12–40 % further (docs/verification.md,
/// "A pressed surface under the volumetric treatments").
pub fn averaged_points<D: Dim>(world: &World) -> impl Iterator<Item = &Archetype> {
    points_with::<Volume>(world).filter(|a| !a.has::<PointLoad<D::Vec>>())
}
