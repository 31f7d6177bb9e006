//! Nodal integration of the equations of motion, eq. (2) (paper step 3).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes};
use crate::infra::traffic::Traffic;
use crate::parallel::{for_each_box_node, Disjoint};
use crate::schedule::System;
use crate::state::Damping;
use crate::systems::shared::constrain;

/// a_i = (f_i + f_damp)/max(m_i, m_floor) and v_i ← p_i/m_i + a_i Δt (explicit Euler on the
/// grid). Viscous damping f_damp = −2β m_i v_i and local damping f_damp,a = −α |f_a| sign(v_a)
/// enter here; massless nodes get no motion.
///
/// m_floor ([`crate::state::Numerics::virtual_mass_floor`]) is a virtual mass for nodes that
/// only the far tail of a point's support reaches: such a node has almost no mass but takes
/// that point's full stress-gradient force, so its acceleration (and the point's, through
/// it) would be that of the point pushed by its own stress.
#[derive(Debug, Default)]
pub struct Integrate;

impl<D: Dim> System<D> for Integrate {
    fn name(&self) -> &str {
        "integrate"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let dt = ctx.numerics.dt;
        let beta2 = match ctx.numerics.damping {
            Damping::Viscous { beta } => 2.0 * beta,
            _ => 0.0,
        };
        let alpha = match ctx.numerics.damping {
            Damping::Local { alpha } => alpha,
            _ => 0.0,
        };
        let min_mass = ctx.numerics.min_node_mass;
        let floor = ctx.numerics.virtual_mass_floor;
        let n = nodes(&ctx.world);
        let nm = col::<NodeMass>(n);
        let np = col::<NodeMomentum<D::Vec>>(n);
        let nf = col::<NodeForce<D::Vec>>(n);
        let fix = col::<NodeFixity>(n);
        // Plain slices: the column guards cannot be shared with the pool.
        let (nm, np, nf, fix) = (&*nm, &*np, &*nf, &*fix);
        let drives = &ctx.state.control.drives[..];
        let driven = !drives.is_empty();
        let mut na = col_mut::<NodeAcceleration<D::Vec>>(n);
        let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
        let grid = &ctx.grid;
        let target = (Disjoint::new(&mut na), Disjoint::new(&mut nv));
        for_each_box_node(grid, ctx.state.active_nodes, &target, |i, k, (na, nv)| {
            let m = nm[i].0;
            if grid.carries(i, m, min_mass) {
                // Dynamic relaxation's mass matrix is fictitious: a floor on the mass that
                // accelerates a light node changes the path, never the static answer.
                let mut f = nf[i].0 - np[i].0 * beta2;
                if alpha > 0.0 {
                    // Local damping: −α |F_a| sign(v_a) per component; none at rest.
                    for a in 0..D::N {
                        let (fa, pa) = (f.get(a), np[i].0.get(a));
                        if pa != 0.0 {
                            f.set(a, fa - alpha * fa.abs() * pa.signum());
                        }
                    }
                }
                let mut a = f * (1.0 / grid.inertia(i, m, floor));
                let mut v = np[i].0 * (1.0 / m) + a * dt;
                if driven && fix[i].0 != 0 {
                    // A driven component's momentum is m·v̄, so viscous damping would pull
                    // it off v̄: held components stay held. (A fixed component has no
                    // momentum and no force here, so it stays at zero without this.)
                    constrain(&mut v, fix[i], D::N, drives);
                    constrain(&mut a, NodeFixity(fix[i].0 & 0b111), D::N, drives);
                }
                na[k].0 = a;
                nv[k].0 = v;
            } else {
                na[k].0 = D::Vec::ZERO;
                nv[k].0 = D::Vec::ZERO;
            }
        });
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let n = ctx.state.active_nodes.len();
        Some(
            Traffic::NONE
                .read_nodes::<NodeMass>(n)
                .read_nodes::<NodeMomentum<D::Vec>>(n)
                .read_nodes::<NodeForce<D::Vec>>(n)
                .read_nodes::<NodeFixity>(n)
                .write_nodes::<NodeAcceleration<D::Vec>>(n)
                .write_nodes::<NodeVelocity<D::Vec>>(n),
        )
    }
}
