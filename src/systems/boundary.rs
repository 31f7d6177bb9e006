//! Essential boundary conditions on the grid (paper step 2): fixed components held at zero,
//! driven ones at their prescribed motion's velocity.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes};
use crate::infra::traffic::Traffic;
use crate::model::Drive;
use crate::parallel::{grid_pass, Disjoint};
use crate::schedule::System;
use crate::systems::exchange::{exchange, EXTERNAL, FORCE, MASS, MOMENTUM};
use crate::systems::shared::{hold, Hold};

/// Holds the constrained components of every node: momentum m·v̄ (v̄ = 0 on a fixed face,
/// the motion's velocity on a driven node) and no force, so that the node moves at v̄.
///
/// A driven node's removed force is its reaction: the motion exerts −(f_int + f_ext) on
/// the body there. It is summed per motion in node order (the same bits on any thread
/// count) into [`Drive::reaction`] and added to the node's external force, so that K_F
/// counts the motion's load as applied load and W_ext its work.
#[derive(Debug, Default)]
pub struct Boundary {
    /// Nodes with a held component in the last call (for the byte budget).
    held: usize,
}

impl<D: Dim> System<D> for Boundary {
    fn name(&self) -> &str {
        "boundary"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // Over MPI: every force is mapped by now; the shared nodes get their whole sums.
        exchange(ctx, MASS | MOMENTUM | FORCE | EXTERNAL);
        let n = nodes(&ctx.world);
        let (fix, nm) = (col::<NodeFixity>(n), col::<NodeMass>(n));
        // Plain slices: the column guards cannot be shared with the pool.
        let (fix, nm) = (&*fix, &*nm);
        let drives = &ctx.state.control.drives[..];
        let velocities: Vec<[f64; 3]> = drives.iter().map(|d| d.velocity).collect();
        let velocities = &velocities[..];
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        let target = (
            Disjoint::new(&mut np),
            Disjoint::new(&mut nf),
            Disjoint::new(&mut ne),
        );
        let grid = &ctx.grid;
        let st = &ctx.numerics;
        let friction = Friction {
            faces: &ctx.model.friction_faces,
            drives,
            dt: st.dt,
            min_mass: st.min_node_mass,
            floor: st.virtual_mass_floor,
        };
        // Over several ranks a shared node is held on both; its reaction counts on its owner.
        let owned = ctx.owned_node_ids();
        let owned = owned.as_ref();
        let parts = grid_pass(grid, ctx.state.active_nodes, &target, |b, (np, nf, ne), first| {
            let mut reactions = vec![[0.0; 3]; velocities.len()];
            let mut held = 0;
            for i in b.rows(grid).flatten() {
                let f = fix[i];
                if f.0 == 0 {
                    continue;
                }
                held += 1;
                let k = i - first;
                if f.0 & NodeFixity::FRICTION != 0 {
                    friction.apply(grid, i, nm[i].0, &np[k].0, &mut nf[k].0, f);
                }
                for a in 0..D::N {
                    match hold(f, a, drives) {
                        Hold::Free => continue,
                        Hold::Driven(d) => {
                            let r = -nf[k].0.get(a);
                            if owned.is_none_or(|o| o.contains(&i)) {
                                reactions[d][a] += r;
                            }
                            ne[k].0.set(a, ne[k].0.get(a) + r);
                            np[k].0.set(a, nm[i].0 * velocities[d][a]);
                        }
                        Hold::Fixed => np[k].0.set(a, 0.0),
                    }
                    nf[k].0.set(a, 0.0);
                }
            }
            (reactions, held)
        });
        self.held = parts.iter().map(|(_, held)| held).sum();
        let mut reactions: Vec<f64> = (0..velocities.len())
            .flat_map(|d| {
                parts
                    .iter()
                    .fold([0.0; 3], |s, (p, _)| std::array::from_fn(|a| s[a] + p[d][a]))
            })
            .collect();
        // Each rank's owned nodes' part, added in rank order (no collective in a run
        // without motions: every rank has the same).
        if !reactions.is_empty() {
            ctx.comm.sum(&mut reactions);
        }
        for (drive, r) in ctx.state.control.drives.iter_mut().zip(reactions.chunks(3)) {
            drive.reaction = [r[0], r[1], r[2]];
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        // Every node's fixity is read; a held node's mass, momentum and forces too.
        let held = self.held;
        Some(
            Traffic::NONE
                .read_nodes::<NodeFixity>(ctx.state.active_nodes.len())
                .read_nodes::<NodeMass>(held)
                .update_nodes::<NodeMomentum<D::Vec>>(held)
                .update_nodes::<NodeForce<D::Vec>>(held)
                .update_nodes::<NodeExternalForce<D::Vec>>(held),
        )
    }
}

/// Coulomb friction on the nodes of `Friction` faces, before their normal component is held.
struct Friction<'a> {
    faces: &'a [(usize, bool, f64)],
    drives: &'a [Drive],
    dt: f64,
    min_mass: f64,
    floor: f64,
}

impl Friction<'_> {
    /// On each friction face through node `i` (mass `m`, momentum `p`, force `f`): the force
    /// the face must supply to hold the normal component, R = p_n m̃/(m Δt) + f_n (outward
    /// positive, m̃ the node's inertia as `integrate` takes it), and when the node presses
    /// on the face (R > 0), a tangential force that stops the node's trial tangential
    /// velocity v_t* = p_t/m + f_t Δt/m̃, at most tan δ · R (Coulomb; it slides beyond).
    /// Axes another face holds fixed are left to it; on an axis a motion drives, the
    /// friction enters the motion's reaction.
    fn apply<D: Dim>(
        &self,
        grid: &crate::grid::Grid<D>,
        i: usize,
        m: f64,
        p: &D::Vec,
        f: &mut D::Vec,
        fixity: NodeFixity,
    ) {
        if !grid.carries(i, m, self.min_mass) {
            return;
        }
        let inertia = grid.inertia(i, m, self.floor);
        let ijk = grid.node_ijk(i);
        for &(axis, upper, mu) in self.faces {
            let layer = if upper { grid.axes[axis].cells } else { 0 };
            if ijk[axis] != layer {
                continue;
            }
            let outward = if upper { 1.0 } else { -1.0 };
            let push = outward * (p.get(axis) * inertia / (m * self.dt) + f.get(axis));
            if push <= 0.0 {
                continue;
            }
            let mut stop = [0.0; 3];
            for (a, s) in stop.iter_mut().enumerate().take(D::N) {
                // A driven axis feels the friction too: the motion's reaction includes it.
                if a != axis && hold(fixity, a, self.drives) != Hold::Fixed {
                    *s = -(p.get(a) / m + f.get(a) * self.dt / inertia) * inertia / self.dt;
                }
            }
            let size = stop.iter().map(|s| s * s).sum::<f64>().sqrt();
            let scale = if size > mu * push { mu * push / size } else { 1.0 };
            for (a, s) in stop.iter().enumerate().take(D::N) {
                f.set(a, f.get(a) + s * scale);
            }
        }
    }
}
