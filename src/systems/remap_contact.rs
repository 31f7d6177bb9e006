//! MUSL's second contact pass: the rigid bodies' contacts of this step held again on the
//! nodal velocities the remap built from the points.
//!
//! `remap` maps the points' new velocities back to the grid; those velocities came from a
//! field the contacts held, yet mapped back they let the soil into the bodies again by a
//! little (each point's velocity spreads over nodes the contact did not hold alike). This
//! pass solves the same contacts ([`crate::systems::rigid_contact`]) on the remapped
//! velocities, so that the points move and strain with a field that keeps out of the
//! bodies. It is a system of its own so that `--profile` shows what the contact costs.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes};
use crate::rigid::contact::{solve, Memory};
use crate::schedule::System;
use crate::systems::rigid_contact::{local_id, naming};

/// Holds the step's contacts on the remapped velocities (MUSL with rigid bodies, after
/// `remap`); nothing in a reset step, whose remapped field is zero.
#[derive(Debug, Default)]
pub struct RemapContact;

impl<D: Dim> System<D> for RemapContact {
    fn name(&self) -> &str {
        "remap_contact"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if !ctx.state.resets.this_step {
            project(ctx);
        }
        Ok(())
    }
}

/// Holds this step's contacts on the nodal velocities built again from the points (MUSL's
/// remap), each node's change weighted by its mass: the soil at each sample loses its
/// velocity into the body and its slip as the interface's friction allows. The adhesion's
/// impulse for the step, a·A_s·Δt, was spent in `rigid_contact`'s solve, the one whose
/// impulses are the body's force: granted again here it held the soil with up to twice
/// the adhesion, the second half counted nowhere (a block on an adhesive base never came
/// to rest, K_F held at 1.2 %).
fn project<D: Dim>(ctx: &mut Context<D>) {
    if ctx.state.control.contacts.contacts.is_empty() {
        return;
    }
    // Over several ranks each rank gives the slots' nodes it owns (mass, then velocity),
    // and the sums make them whole on every rank: all solve the same contacts.
    let (owned, held) = (ctx.owned_node_ids(), ctx.held_node_ids());
    let naming = naming(ctx);
    // Each slot's node as this rank numbers it, if it holds it.
    let local: Vec<Option<usize>> = (ctx.state.control.contacts.slots.iter())
        .map(|s| local_id(ctx, &naming, s.node))
        .collect();
    let n = nodes(&ctx.world);
    let nm = col::<NodeMass>(n);
    let mut nv = col_mut::<NodeVelocity<D::Vec>>(n);
    let floor = ctx.numerics.virtual_mass_floor;
    let control = &mut ctx.state.control;
    let w = 1 + D::N;
    let mut values = vec![0.0; control.contacts.slots.len() * w];
    for (i, v) in local.iter().zip(values.chunks_mut(w)) {
        if let Some(i) = i.filter(|i| owned.as_ref().is_none_or(|o| o.contains(i))) {
            v[0] = nm[i].0;
            (0..D::N).for_each(|a| v[1 + a] = nv[i].0.get(a));
        }
    }
    ctx.comm.sum(&mut values);
    for (s, v) in control.contacts.slots.iter_mut().zip(values.chunks(w)) {
        s.v = std::array::from_fn(|a| if a < D::N { v[1 + a] } else { 0.0 });
        s.v0 = s.v;
        s.inertia = naming.inertia(s.node, v[0], floor);
    }
    let velocities: Vec<[f64; 3]> = control.bodies.iter().map(|b| b.velocity).collect();
    for p in &mut control.contacts.contacts {
        p.adhesion = 0.0;
    }
    solve(
        &mut control.contacts,
        &velocities,
        &Memory::new(),
        ctx.numerics.contact_tolerance,
    );
    for (s, i) in control.contacts.slots.iter().zip(&local) {
        if let Some(i) = i.filter(|i| held.as_ref().is_none_or(|h| h.contains(i))) {
            nv[i].0 = D::vec_from(s.v);
        }
    }
}
