//! Dynamic-relaxation mass scaling: fictitious nodal inertia so that every node takes the
//! same stable step. Scheduled only with `solver.mass_scaling`.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::parallel::{for_each_box_node, Disjoint};
use crate::schedule::System;
use crate::shape::Shape;
use crate::systems::node_pairs::NodePairs;
use std::marker::PhantomData;

/// The paper's eq. (2) mass only sets the path to a static answer, not the answer. With
/// mass scaling the time step comes from the *slowest* P-wave speed c_ref of the materials
/// in use, and a point of material m accelerates as if it weighed m_p s_m, with
/// s_m = max(1, (c_m / c_ref)²): its wave then travels a cell in no less than the step,
/// whatever its stiffness. Gravity, point loads and momentum keep the real mass.
///
/// Runs after `integrate`: with m̃_i = Σ_p w_ip m_p s_p (at least the integrate's inertia,
/// floor included) the nodal acceleration becomes a m_i'/m̃_i, where m_i' is the inertia
/// integrate used, and the velocity v ← v + (a_new − a) Δt. A node that only soft points
/// reach is untouched; so is a one-material scene (every s_m = 1), which needs none of it.
#[derive(Debug)]
pub struct MassScaling<D: Dim, S> {
    /// Per node: Σ_p w_ip m_p s_p (kg) and the largest s_p of the points that reach it.
    inertia: NodePairs,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for MassScaling<D, S> {
    fn default() -> Self {
        MassScaling {
            inertia: NodePairs::default(),
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for MassScaling<D, S> {
    fn name(&self) -> &str {
        "mass_scaling"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let grid = &ctx.grid;
        let factors = &ctx.model.inertia_factors;
        let sums = &mut self.inertia;
        // Material points only: a point load's carrier has no material and no mass.
        for arch in points_with::<MaterialId>(&ctx.world) {
            let (xg, mg, idg) = (
                col::<Position<D::Vec>>(arch),
                col::<Mass>(arch),
                col::<MaterialId>(arch),
            );
            let (m, id): (&[Mass], &[MaterialId]) = (&mg, &idg);
            sums.scatter::<D, S, _>(
                &mut ctx.slabs,
                grid,
                &xg,
                |p| {
                    let s = factors.get(id[p].0 as usize).copied().unwrap_or(1.0);
                    (m[p].0 * s, s)
                },
                |node, w, &(scaled, s)| {
                    node[0] += w * scaled;
                    node[1] = node[1].max(s);
                },
            );
        }
        // Over MPI: the shared nodes' scaled mass summed, their largest factor kept.
        sums.combine_over_ranks(grid, &ctx.comm, &ctx.decomposition, |l, u| {
            [l[0] + u[0], l[1].max(u[1])]
        });
        let (dt, min_mass, floor) = (
            ctx.numerics.dt,
            ctx.numerics.min_node_mass,
            ctx.numerics.virtual_mass_floor,
        );
        let n = nodes(&ctx.world);
        let nm = col::<NodeMass>(n);
        let nm = &*nm;
        let scaled = sums.pairs();
        let mut na = col_mut::<NodeAcceleration<D::Vec>>(n);
        let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
        let target = (Disjoint::new(&mut na), Disjoint::new(&mut nv));
        for_each_box_node(grid, ctx.state.active_nodes, &target, |i, k, (na, nv)| {
            let m = nm[i].0;
            if grid.carries(i, m, min_mass) {
                let used = grid.inertia(i, m, floor);
                // The virtual floor scaled as the stiffest point that reaches the node: a
                // node on the far tail of a stiff point's support has almost none of its
                // mass but takes its full stress-gradient force.
                let [sum, s_max] = scaled[i];
                let ratio = used / sum.max(grid.inertia(i, m, floor * s_max)).max(used);
                if ratio < 1.0 {
                    let a = na[k].0;
                    let new = a * ratio;
                    nv[k].0 += (new - a) * dt;
                    na[k].0 = new;
                }
            }
        });
        sums.clear(grid);
        Ok(())
    }
}
