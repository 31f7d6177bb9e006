//! Contact between the soil and the scene's rigid bodies, held at the bodies' surfaces.
//!
//! Each body's surface is sampled every half cell ([`crate::rigid::Sample`]: a place, the
//! geometry's outward normal n and the surface it stands for). At a sample x_s the soil's
//! velocity is the grid's, v(x_s) = Σ_i w_i(x_s) v_i / Σ_i w_i over the nodes that carry
//! soil (with `corners: Released`, less those outside the body that face a corner of it,
//! [`crate::rigid::corners`]: past a footing's edge the soil is not under its base), built
//! from the trial velocities v_i* = p_i/m_i + f_i Δt/m̃_i (m̃ the node's
//! inertia, as `integrate` takes it). Contact holds (v(x_s) − v_b)·n ≥ 0: the soil may
//! leave the body but not enter it. A violated sample takes an impulse λ n spread over its
//! nodes as Δv_i = λ w_i n / m̃_i, with λ = −C / Σ w_i²/m̃_i for the violation C; the
//! samples are visited in a fixed order until they agree (projected Gauss–Seidel, λ ≥ 0
//! summed per sample), so that overlapping samples share their nodes' correction. Where the
//! soil presses, the tangential slip at a sample is removed the same way, by at most
//! tan δ · N_s + a·A_s·Δt (Coulomb friction with an adhesion cap a on the sample's surface
//! A_s, from the interface of the sample's part; when rough, the soil's own c and tan φ
//! beside the sample, [`crate::systems::soil_strength`]; nothing when smooth),
//! N_s being the normal impulse its nodes took, from the samples and the inside nodes
//! alike, shared among the samples that reach them ([`crate::rigid::contact`]).
//!
//! It runs before `boundary`, so that a `Friction` face and a motion's nodes feel the
//! contact's force; the components they hold enter the contact as `boundary` will set
//! them and are not moved by it.
//!
//! The constraint is held where the body's surface is, between nodes, so a body is as big
//! as its geometry whatever the grid: holding the nodes inside a body instead makes it
//! smaller or larger by up to a cell as it moves across the grid (docs/tried-and-dropped.md).
//!
//! The change is made as a force f_c = m̃ Δv/Δt added to the node's force and, since the
//! body applies it, to its external force (K_F counts it as applied load, W_ext its work).
//! Σ f_c, in sample order, is the force the body exerts on the soil, summed per body and
//! per part; the soil's resistance on the body is the opposite. MUSL maps the points' new
//! velocities back to the grid (`remap`); `remap_contact` holds the same contacts there.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::{Grid, NodeBox};
use crate::infra::columns::{col, col_mut, nodes};
use crate::rigid::contact::{key, remember, solve, Contact, Contacts, Slot};
use crate::rigid::{CornerTest, Corners, Exposed, Located};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::exchange::{exchange, EXTERNAL, FORCE, MASS, MOMENTUM};
use crate::systems::shared::{constrain, hold, Hold};
use crate::systems::soil_gap::SoilGap;
use crate::systems::soil_side::SoilSide;
use crate::systems::soil_strength::SoilStrength;
use std::marker::PhantomData;

/// Holds the contacts at the bodies' surface samples ([`crate::rigid::RigidBody::samples`],
/// cut at set-up) at every step (before `boundary`).
#[derive(Debug)]
pub struct RigidContact<D: Dim, S> {
    /// Per node, its slot in this step's [`Contacts::slots`] (`u32::MAX`: none); all
    /// `u32::MAX` between steps.
    slot_of: Vec<u32>,
    /// The soil's strength round the rough samples, summed again each step.
    strength: SoilStrength,
    /// Which face of a thin driven body the soil at its nodes lies against, summed again
    /// each step.
    side: SoilSide,
    /// How far the soil's surface stands off each body's, found again each step.
    gap: SoilGap,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for RigidContact<D, S> {
    fn default() -> Self {
        RigidContact {
            slot_of: Vec::new(),
            strength: SoilStrength::default(),
            side: SoilSide::default(),
            gap: SoilGap::default(),
            _marker: PhantomData,
        }
    }
}

/// The soil's mass, momentum, force and fixity at the nodes the contacts may reach: this
/// rank's columns with one rank; over several, every node's whole values gathered from the
/// rank that owns it, so that every rank places and solves the same contacts in the same
/// order (the answer one rank finds, to the order of the sums that made the nodal values).
/// Nodes are named by [`naming`]'s grid.
enum Soil<'a, D: Dim> {
    /// One rank: its node columns.
    Columns {
        nm: &'a [NodeMass],
        np: &'a [NodeMomentum<D::Vec>],
        nf: &'a [NodeForce<D::Vec>],
        fix: &'a [NodeFixity],
    },
    /// Several ranks: the node ids, ascending, and 2 + 2N values each (m, p, f, fixity).
    Gathered { ids: Vec<usize>, values: Vec<f64> },
}

/// Values a gathered node carries: mass, momentum, force and its fixity's bits.
fn gathered_width<D: Dim>() -> usize {
    2 + 2 * D::N
}

impl<D: Dim> Soil<'_, D> {
    /// Mass (kg), momentum (kg m/s), force (N) and fixity at node `i`; nothing and free
    /// for a node no contact reaches.
    fn at(&self, i: usize) -> (f64, D::Vec, D::Vec, NodeFixity) {
        match self {
            Soil::Columns { nm, np, nf, fix } => (nm[i].0, np[i].0, nf[i].0, fix[i]),
            Soil::Gathered { ids, values } => {
                let w = gathered_width::<D>();
                let Ok(k) = ids.binary_search(&i) else {
                    return (0.0, D::Vec::ZERO, D::Vec::ZERO, NodeFixity(0));
                };
                let v = &values[k * w..(k + 1) * w];
                let vec =
                    |o: usize| D::vec_from(std::array::from_fn(|a| if a < D::N { v[o + a] } else { 0.0 }));
                (v[0], vec(1), vec(1 + D::N), NodeFixity(v[w - 1] as u8))
            }
        }
    }
}

/// The grid whose numbering names the contacts' nodes: this rank's own with one rank; over
/// several the whole grid's, the same on every rank, since every rank places every contact
/// (a rank's own grid numbers only the nodes it holds).
pub(crate) fn naming<D: Dim>(ctx: &Context<D>) -> Grid<D> {
    if ctx.comm.size() == 1 {
        ctx.grid.clone()
    } else {
        ctx.grid.whole()
    }
}

/// This rank's id of node `i` of `naming`'s grid, `None` when the rank does not hold it.
pub(crate) fn local_id<D: Dim>(ctx: &Context<D>, naming: &Grid<D>, i: usize) -> Option<usize> {
    if ctx.comm.size() == 1 {
        Some(i)
    } else {
        ctx.grid.checked_node_id(naming.node_ijk(i))
    }
}

/// The nodes a body's inside-node constraints visit: those within its bounds at its current
/// place, among `region`.
fn inside_box<D: Dim>(
    ctx: &Context<D>,
    body: &crate::rigid::RigidBody,
    offset: [f64; 3],
    region: NodeBox,
) -> NodeBox {
    let grid = &ctx.grid;
    let (lo, hi) = body.spec.bounds(D::N);
    let o = D::vec_to3(grid.origin);
    let mut inside = region;
    for a in 0..D::N {
        let first = ((lo[a] + offset[a] - o[a]) * grid.inv_h).ceil().max(0.0) as usize;
        let last = ((hi[a] + offset[a] - o[a]) * grid.inv_h).floor().max(-1.0) + 1.0;
        inside.lo[a] = inside.lo[a].max(first);
        inside.hi[a] = inside.hi[a].min(last as usize).max(inside.lo[a]);
    }
    inside
}

/// The region of nodes the inside-node constraints look in: this rank's active nodes with
/// one rank, the whole grid over several (each rank sees every body whole).
fn region<D: Dim>(ctx: &Context<D>) -> NodeBox {
    if ctx.comm.size() == 1 {
        return ctx.state.active_nodes;
    }
    ctx.grid.all_nodes()
}

/// The soil's values at the nodes the contacts may reach (see [`Soil`]): over several
/// ranks, each rank gives the nodes it owns and the sums make them whole on every rank.
fn soil<'a, D: Dim, S: Shape>(
    ctx: &Context<D>,
    naming: &Grid<D>,
    nm: &'a [NodeMass],
    np: &'a [NodeMomentum<D::Vec>],
    nf: &'a [NodeForce<D::Vec>],
    fix: &'a [NodeFixity],
) -> Soil<'a, D> {
    let Some(owned) = ctx.owned_node_ids() else {
        return Soil::Columns { nm, np, nf, fix };
    };
    let grid = naming;
    let whole = region(ctx);
    let mut ids = Vec::new();
    for (b, body) in ctx.model.bodies.iter().enumerate() {
        let offset = ctx.state.control.bodies[b].offset;
        ids.extend(inside_box(ctx, body, offset, whole).rows(grid).flatten());
        for (s, _) in &body.samples {
            let x = D::vec_from(std::array::from_fn(|a| s.x[a] + offset[a]));
            if grid.contains(x) {
                for_each_node::<D, S>(grid, x, |i, w, _| {
                    if w > 0.0 {
                        ids.push(i);
                    }
                });
            }
        }
    }
    ids.sort_unstable();
    ids.dedup();
    let w = gathered_width::<D>();
    let mut values = vec![0.0; ids.len() * w];
    for (k, &g) in ids.iter().enumerate() {
        let Some(i) = local_id(ctx, naming, g).filter(|i| owned.contains(i)) else {
            continue;
        };
        let v = &mut values[k * w..(k + 1) * w];
        v[0] = nm[i].0;
        for a in 0..D::N {
            v[1 + a] = np[i].0.get(a);
            v[1 + D::N + a] = nf[i].0.get(a);
        }
        v[w - 1] = f64::from(fix[i].0);
    }
    // One rank owns each node: its value plus zeros, the same bits on every rank.
    ctx.comm.sum(&mut values);
    Soil::Gathered { ids, values }
}

/// Places every sample that meets soil at its body's current place: its nodes that carry
/// soil and their weights, each node's trial velocity p/m + f Δt/m̃. A sample meets soil
/// when nodes carrying mass hold at least half its support; it holds them all, or with
/// `corners: Released` those that do not face a corner of the body
/// ([`crate::rigid::corners`]). Body by body, its inside nodes first, then its samples: the
/// order the solve visits them in. `slot_of` (one entry a node) is all `u32::MAX` on entry
/// and is left so.
fn place<D: Dim, S: Shape>(
    ctx: &Context<D>,
    naming: &Grid<D>,
    soil: &Soil<D>,
    strength: &SoilStrength,
    side: &SoilSide,
    slot_of: &mut Vec<u32>,
) -> Contacts {
    slot_of.resize(naming.node_count(), u32::MAX);
    let mut placer = Placer {
        ctx,
        grid: naming,
        soil,
        side,
        slot_of,
        set: Contacts::default(),
    };
    let region = region(ctx);
    for b in 0..ctx.model.bodies.len() {
        placer.inside_nodes(b, region);
        placer.surface_samples::<S>(b, strength);
    }
    let Placer { set, slot_of, .. } = placer;
    for s in &set.slots {
        slot_of[s.node] = u32::MAX;
    }
    set
}

/// [`place`]'s working state: the contacts placed so far and each reached node's slot.
struct Placer<'a, 'b, D: Dim> {
    ctx: &'a Context<D>,
    /// The grid whose numbering names the nodes ([`naming`]).
    grid: &'a Grid<D>,
    soil: &'a Soil<'b, D>,
    /// Which side of a thin body each node's soil lies against.
    side: &'a SoilSide,
    slot_of: &'a mut Vec<u32>,
    set: Contacts,
}

impl<'a, D: Dim> Placer<'a, '_, D> {
    /// The slot of node `i` (which carries mass), made at its first reach with the node's
    /// trial velocity p/m + f Δt/m̃, inertia and free axes.
    fn slot(&mut self, i: usize) -> usize {
        if self.slot_of[i] != u32::MAX {
            return self.slot_of[i] as usize;
        }
        let (grid, st) = (self.grid, &self.ctx.numerics);
        let drives = &self.ctx.state.control.drives;
        let (m, p, f, fix) = self.soil.at(i);
        let inertia = grid.inertia(i, m, st.virtual_mass_floor);
        // The held components as `boundary` will hold them (it runs next, so that a
        // friction face and a motion feel the contact's force).
        let mut v = p * (1.0 / m) + f * (st.dt / inertia);
        constrain(&mut v, fix, D::N, drives);
        let v = D::vec_to3(v);
        let free = std::array::from_fn(|a| a < D::N && hold(fix, a, drives) == Hold::Free);
        let slots = &mut self.set.slots;
        slots.push(Slot::new(i, v, inertia, free));
        self.slot_of[i] = (slots.len() - 1) as u32;
        slots.len() - 1
    }

    /// Body `b`'s surface the soil meets, at its place this step.
    fn surface(&self, b: usize) -> Exposed<'a> {
        let (ctx, grid) = (self.ctx, self.grid);
        let bounds = (D::vec_to3(grid.origin), D::vec_to3(grid.max_corner()));
        let offset = ctx.state.control.bodies[b].offset;
        Exposed::new(
            &ctx.model.bodies[b].spec.parts,
            D::N,
            offset,
            bounds,
            grid.cell_size,
        )
    }

    /// Body `b`'s constraints at the nodes inside it (within `region`) that carry soil.
    /// They hold their normal velocity too: the soil's field there is the body's, and a
    /// light node that only a point's tail reaches would otherwise be free to run into it
    /// (under a confining stress it does). In a body of several parts, each bears on the
    /// part whose surface the soil meets nearest it ([`Exposed::bearing_part`]), not on
    /// the part it lies deepest in: a node in a pile's shaft a cell above its base carries
    /// the clay under the base.
    fn inside_nodes(&mut self, b: usize, region: NodeBox) {
        let ctx = self.ctx;
        let (grid, st) = (self.grid, &ctx.numerics);
        let body = &ctx.model.bodies[b];
        let offset = ctx.state.control.bodies[b].offset;
        let surface = (body.spec.parts.len() > 1).then(|| self.surface(b));
        for i in inside_box(ctx, body, offset, region).rows(grid).flatten() {
            if !grid.carries(i, self.soil.at(i).0, st.min_node_mass) {
                continue;
            }
            let x = D::vec_to3(grid.node_position(grid.node_ijk(i)));
            let at: [f64; 3] = std::array::from_fn(|a| x[a] - offset[a]);
            let (phi, normal, deepest) = body.spec.distance(at, D::N);
            // Not a node whose soil lies against a face a thin body is driven away from.
            if phi > 0.0 || self.side.lets_go(b, i, normal) {
                continue;
            }
            let part = surface.and_then(|s| s.bearing_part(x)).unwrap_or(deepest);
            let k = self.slot(i);
            self.set.contacts.push(Contact {
                key: key(b, false, i),
                body: b,
                part,
                at: x,
                normal,
                friction: 0.0,
                adhesion: 0.0,
                surface: false,
                nodes: vec![(k, 1.0)],
                weight: 1.0,
                normal_impulse: 0.0,
                impulse: [0.0; 3],
                closing: 0.0,
            });
        }
    }

    /// Body `b`'s surface samples that meet soil, each with its nodes, weights and the
    /// caps of its part's interface (`strength` where rough).
    fn surface_samples<S: Shape>(&mut self, b: usize, strength: &SoilStrength) {
        let ctx = self.ctx;
        let (grid, st) = (self.grid, &ctx.numerics);
        let body = &ctx.model.bodies[b];
        let offset = ctx.state.control.bodies[b].offset;
        let corners = (body.spec.corners == Corners::Released).then(|| CornerTest::new(self.surface(b)));
        let mut located: std::collections::HashMap<usize, Located> = Default::default();
        for (index, (s, part)) in body.samples.iter().enumerate() {
            let x3: [f64; 3] = std::array::from_fn(|a| s.x[a] + offset[a]);
            let x = D::vec_from(x3);
            if !grid.contains(x) {
                continue;
            }
            let mut reach = Vec::new();
            // Σ w over the nodes that carry soil (whether the sample meets soil), and over
            // those it holds.
            let (mut soil_weight, mut weight) = (0.0, 0.0);
            for_each_node::<D, S>(grid, x, |i, w, _| {
                if w <= 0.0 || !grid.carries(i, self.soil.at(i).0, st.min_node_mass) {
                    return;
                }
                // Not the soil behind a face a thin body is driven away from.
                if self.side.lets_go(b, i, s.normal) {
                    return;
                }
                soil_weight += w;
                // With `Released` corners, not a node beyond the body that faces a corner
                // (where a node stands to the body is found once a step, for every sample
                // that reaches it).
                if let Some(c) = &corners {
                    let node = located
                        .entry(i)
                        .or_insert_with(|| c.locate(D::vec_to3(grid.node_position(grid.node_ijk(i)))));
                    if !c.holds_node(node, s.normal) {
                        return;
                    }
                }
                reach.push((self.slot(i), w));
                weight += w;
            });
            if soil_weight < 0.5 || weight <= 0.0 {
                continue;
            }
            // The sample's surface, per radian when axisymmetric (as volumes are).
            let area = if D::AXISYMMETRIC {
                s.measure * x3[0]
            } else {
                s.measure
            };
            let nodes = reach.iter().map(|&(k, w)| (self.set.slots[k].node, w));
            let (friction, adhesion) = strength.caps(body.interfaces[*part], grid, nodes);
            self.set.contacts.push(Contact {
                key: key(b, true, index),
                body: b,
                part: *part,
                at: x3,
                normal: s.normal,
                friction,
                adhesion: adhesion * area * st.dt,
                surface: true,
                nodes: reach,
                weight,
                normal_impulse: 0.0,
                impulse: [0.0; 3],
                closing: 0.0,
            });
        }
    }
}

impl<D: Dim, S> RigidContact<D, S> {
    /// Each contact's [`Contact::closing`] for the bodies with `soil_surface: Points`: the
    /// least gap of the soil's points in front of it, over every rank's points, over Δt;
    /// zero where the soil touches, where no point is in front of it, and for the other
    /// bodies.
    fn closing(&mut self, ctx: &Context<D>, naming: &Grid<D>, set: &mut Contacts) {
        // The same on every rank: each places every contact of every body.
        if set.contacts.is_empty() || !SoilGap::wanted(ctx) {
            return;
        }
        self.gap.gather(ctx);
        let h = naming.cell_size;
        // −(least gap), so that one reduction (max) takes the least over the ranks.
        let mut far: Vec<f64> = (set.contacts.iter())
            .map(|p| -self.gap.least(p.body, p.at, p.normal, h))
            .collect();
        ctx.comm.max(&mut far);
        let dt = ctx.numerics.dt;
        for (p, g) in set.contacts.iter_mut().zip(far) {
            let g = -g;
            p.closing = if g.is_finite() && g > 0.0 { g / dt } else { 0.0 };
        }
    }
}

impl<D: Dim, S: Shape> System<D> for RigidContact<D, S> {
    fn name(&self) -> &str {
        "rigid_contact"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // Over MPI: every force is mapped by now; the shared nodes get their whole sums.
        exchange(ctx, MASS | MOMENTUM | FORCE | EXTERNAL);
        let naming = naming(ctx);
        let mut set = {
            let n = nodes(&ctx.world);
            let (nm, np, nf) = (
                col::<NodeMass>(n),
                col::<NodeMomentum<D::Vec>>(n),
                col::<NodeForce<D::Vec>>(n),
            );
            let fix = col::<NodeFixity>(n);
            self.strength.gather(ctx);
            self.side.gather::<D, S>(ctx, &naming);
            let soil = soil::<D, S>(ctx, &naming, &nm, &np, &nf, &fix);
            place::<D, S>(ctx, &naming, &soil, &self.strength, &self.side, &mut self.slot_of)
        };
        let dt = ctx.numerics.dt;
        self.closing(ctx, &naming, &mut set);
        let bodies = &ctx.model.bodies;
        let velocities: Vec<[f64; 3]> = ctx.state.control.bodies.iter().map(|b| b.velocity).collect();
        let tolerance = ctx.numerics.contact_tolerance;
        solve(
            &mut set,
            &velocities,
            &ctx.state.control.contact_memory,
            tolerance,
        );
        ctx.state.control.contact_memory = remember(&set.contacts);
        let n = nodes(&ctx.world);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        // Every rank solved the same contacts; each changes the nodes it holds.
        let held = ctx.held_node_ids();
        for s in &set.slots {
            let Some(i) = local_id(ctx, &naming, s.node) else {
                continue;
            };
            if held.as_ref().is_none_or(|h| h.contains(&i)) {
                let fc = D::vec_from(std::array::from_fn(|a| s.inertia * (s.v[a] - s.v0[a]) / dt));
                nf[i].0 += fc;
                ne[i].0 += fc;
            }
        }
        let control = &mut ctx.state.control;
        for (b, state) in control.bodies.iter_mut().enumerate() {
            state.reaction = [0.0; 3];
            state.parts = vec![[0.0; 3]; bodies[b].spec.parts.len()];
        }
        for p in &set.contacts {
            let state = &mut control.bodies[p.body];
            for a in 0..3 {
                state.reaction[a] += p.impulse[a] / dt;
                state.parts[p.part][a] += p.impulse[a] / dt;
            }
        }
        // The soil that moves with each body under load control: every node its contacts
        // reach, once (a body under displacement control does not need it).
        let loaded = bodies.iter().any(|b| b.spec.load.is_some());
        let mut seen = vec![u32::MAX; if loaded { set.slots.len() } else { 0 }];
        for state in &mut control.bodies {
            state.contact_mass = 0.0;
        }
        for p in set.contacts.iter().filter(|p| bodies[p.body].spec.load.is_some()) {
            for &(k, _) in &p.nodes {
                if seen[k] != p.body as u32 {
                    seen[k] = p.body as u32;
                    control.bodies[p.body].contact_mass += set.slots[k].inertia;
                }
            }
        }
        control.contacts = set;
        Ok(())
    }
}
