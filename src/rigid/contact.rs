//! The contact solver: the soil's velocity at a body's surface samples may not enter the
//! body; friction and adhesion limit its slip where it presses.
//!
//! A sample's soil velocity is v(x_s) = Σ_i (w_i/W) v_i over the nodes that carry soil
//! (W = Σ w_i). A change δ of it along a unit direction d is spread as Δv_i ∝ (w_i/W) d / m̃_i
//! over the free axes, the least change of kinetic energy that makes it; the impulse the
//! soil takes is Σ m̃_i Δv_i. The nodes inside a body hold their normal velocity as
//! constraints of their own (without them a node that only a point's tail reaches, inside
//! the body, runs into it under a confining stress). The constraints are visited in a
//! fixed order (projected Gauss–Seidel: the normal impulse summed per constraint stays
//! ≥ 0, a patch's friction impulse within tan δ times the normal impulse it leans on plus
//! the adhesion cap) until no sweep changes a contact's velocity by more than
//! `TOLERANCE` (1e-5) of the fastest entry before the solve (or of the first sweep's
//! largest change, when that is larger). The order is fixed, so the result is the same on
//! any thread count.
//!
//! Each solve starts from the impulses the last step's ended with ([`Memory`], kept in
//! checkpoints): the overlapping samples of a curved surface and the inside nodes hold
//! more constraints than their nodes have velocities, and from zero the sweeps take
//! hundreds of passes to share a confined soil's push among them (the T-bar's first sweep
//! changes velocities by 6 m/s, the 200th still by 1e-4 of that); from the last step's
//! share the first sweep changes them by 1e-4 of it. With a few cold sweeps only, part of
//! each step's entry is left and a confined soil streams past the body.
//!
//! Friction is held per patch, not per sample: the samples of a part nearest one node
//! (about two of them in 2D, four in 3D) are one tangential row on the area-weighted mean
//! of their soil velocities, as a mortar method keeps one multiplier a node. Samples half
//! a cell apart reach nearly the same nodes with nearly the same weights, and with one
//! no-slip row each the rows were so alike that the sweeps converged by about 1 % each:
//! the rough T-bar's solves ran to `MAX_SWEEPS` and a rough body cost twice a smooth one.
//! The normal rows stay one a sample (pooled as well, they moved a smooth bar's static
//! states by up to 0.9 % and the rigid footing's corner excess not at all). A patch's
//! friction acts where one of its samples presses, and the normal impulse its cap leans on
//! is its nodes' (each node's share of what every constraint pushed into it, split among
//! the patches that reach it by weight) when that is more than its samples' own: the
//! inside nodes carry much of a body's normal force, and a cap of the sample's own impulse
//! held a block on a rigid base with a hundredth of its friction (docs/performance.md,
//! tried and dropped). Acting wherever its nodes were pressed (not only where a sample
//! presses) let a rough T-bar drag the soil behind it and the solve stop converging. The
//! friction impulse is projected on Coulomb's disc as a whole (a cap that falls during
//! the solve takes back what passes it), and it is not taken back where the soil stops
//! pressing within a solve: letting it go there made the remap's solve swing between two
//! states at every sweep.

/// Most Gauss–Seidel sweeps over the samples per solve.
const MAX_SWEEPS: usize = 200;

/// A solve ends when no sweep changes a contact's velocity by more than this fraction of
/// the fastest entry into a body before the solve, or of the first sweep's largest change
/// when that is larger (soil at rest against a held body enters it at no speed).
const TOLERANCE: f64 = 1e-5;

/// A surface sample that meets soil this step: its nodes (slots of [`Contacts::slots`])
/// and weights, and what it has pushed.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// Identity across steps (the body, whether a surface sample or an inside node, and
    /// its index): the key of its warm start in [`Memory`].
    pub key: u64,
    /// Index of the body.
    pub body: usize,
    /// Index of the part in the body.
    pub part: usize,
    /// Unit outward normal of the body (x y z).
    pub normal: [f64; 3],
    /// Friction coefficient tan δ of the sample's part (infinite when rough).
    pub friction: f64,
    /// Adhesion cap on the sample's tangential impulse (N s), a·A_s·Δt.
    pub adhesion: f64,
    /// The sample's surface A_s (m², per radian when axisymmetric; 0 for an inside node).
    pub area: f64,
    /// False for a node inside the body: it holds the normal only (friction and adhesion
    /// act at the surface samples).
    pub surface: bool,
    /// The node nearest a surface sample (its patch of the surface): the samples of one
    /// body and part that share it take their friction as one row.
    pub patch: usize,
    /// (slot, weight) of the nodes that carry soil.
    pub nodes: Vec<(usize, f64)>,
    /// Σ w over those nodes.
    pub weight: f64,
    /// Normal impulse so far (N s, ≥ 0).
    pub normal_impulse: f64,
    /// Impulse on the soil so far (N s, x y z).
    pub impulse: [f64; 3],
    /// The friction impulse of the patch this sample heads (N s, x y z): zero for the
    /// patch's other samples.
    pub friction_impulse: [f64; 3],
}

/// A node some sample reaches: its id, velocity (as solved so far and at the start),
/// inertia and free axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    /// Node id.
    pub node: usize,
    /// Velocity (m/s, x y z).
    pub v: [f64; 3],
    /// Velocity before the contacts (m/s).
    pub v0: [f64; 3],
    /// Mass that an impulse accelerates (kg).
    pub inertia: f64,
    /// Axes no boundary condition holds.
    pub free: [bool; 3],
    /// Impulse the node has taken from every constraint's normal push so far (N s, x y z):
    /// pushes of two bodies on either side of it cancel.
    pub pressed: [f64; 3],
    /// Σ w/W over the surface samples that reach the node: how its pressed impulse is
    /// shared among their friction caps.
    pub share: f64,
}

impl Slot {
    /// A slot for `node` at velocity `v` (m/s), nothing pressed yet.
    pub fn new(node: usize, v: [f64; 3], inertia: f64, free: [bool; 3]) -> Self {
        Slot {
            node,
            v,
            v0: v,
            inertia,
            free,
            pressed: [0.0; 3],
            share: 0.0,
        }
    }
}

/// This step's contacts and the nodes they reach (rebuilt each step by `rigid_contact`;
/// MUSL's remap holds them again on the remapped velocities).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Contacts {
    /// The samples that meet soil, bodies in scene order and each body's in sample order.
    pub contacts: Vec<Contact>,
    /// The nodes they reach, in order of first reach.
    pub slots: Vec<Slot>,
}

/// What one contact ended the last solve with: a solve starts from it (warm start), so
/// that a body pressed by the same soil step after step does not build its reaction, nor
/// the friction that holds the soil against it, up from zero every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Remembered {
    /// The contact's [`Contact::key`].
    pub key: u64,
    /// Its normal impulse (N s, ≥ 0).
    pub normal: f64,
    /// The friction impulse of the patch it heads (N s, x y z): zero for an inside node,
    /// a smooth sample and a patch's other samples.
    pub tangential: [f64; 3],
}

/// Each contact's impulses at the end of the last solve, by key in ascending order.
pub type Memory = Vec<Remembered>;

/// The key of a contact: body `body`, a surface sample (`surface`) or an inside node, and
/// the sample's or the node's index.
pub fn key(body: usize, surface: bool, index: usize) -> u64 {
    ((body as u64) << 48) | ((surface as u64) << 47) | index as u64
}

/// What a solve leaves for the next one to start from: each contact's normal impulse and
/// the tangential part of its impulse, by key.
pub fn remember(contacts: &[Contact]) -> Memory {
    let mut memory: Memory = contacts
        .iter()
        .map(|p| Remembered {
            key: p.key,
            normal: p.normal_impulse,
            tangential: p.friction_impulse,
        })
        .collect();
    memory.sort_unstable_by_key(|m| m.key);
    memory
}

/// The part of the impulse `j` across the unit normal `n`.
fn tangential(j: [f64; 3], n: [f64; 3]) -> [f64; 3] {
    let jn = dot(j, n);
    std::array::from_fn(|a| j[a] - jn * n[a])
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// How a change of the soil's velocity at a row (its nodes' `(slot, weight)` and Σ w)
/// along the unit `dir` spreads over its nodes: Δv_i = δ (w_i/W) dir / s² on the free
/// axes, s² = Σ (w_i/W)² (dir on free axes)², which moves the row's velocity by δ. Returns
/// (s², the impulse per unit δ, Σ m̃_i (w_i/W) dir² / s²).
fn spread(nodes: &[(usize, f64)], weight: f64, slots: &[Slot], dir: [f64; 3]) -> (f64, f64) {
    let (mut s2, mut m) = (0.0, 0.0);
    for &(k, w) in nodes {
        let s = &slots[k];
        let share = w / weight;
        let c = coefficient(share, s.inertia);
        let d2: f64 = (0..3).filter(|&a| s.free[a]).map(|a| dir[a] * dir[a]).sum();
        s2 += share * c * d2;
        m += s.inertia * c * d2;
    }
    if s2 > 0.0 {
        (s2, m / s2)
    } else {
        (0.0, 0.0)
    }
}

/// A node's part of a change at the sample: its weight over its inertia, the least change
/// of kinetic energy that makes it.
fn coefficient(share: f64, inertia: f64) -> f64 {
    share / inertia
}

/// Changes the soil's velocity at a row by `delta` (m/s) along the unit `dir`, spread as
/// [`spread`] says; returns the impulse the soil took (N s, x y z).
fn push(
    nodes: &[(usize, f64)],
    weight: f64,
    slots: &mut [Slot],
    dir: [f64; 3],
    delta: f64,
    s2: f64,
    normal: bool,
) -> [f64; 3] {
    let mut took = [0.0; 3];
    for &(k, w) in nodes {
        let s = &mut slots[k];
        let dv = delta * coefficient(w / weight, s.inertia) / s2;
        for a in 0..3 {
            if s.free[a] {
                s.v[a] += dv * dir[a];
                took[a] += s.inertia * dv * dir[a];
                if normal {
                    s.pressed[a] += s.inertia * dv * dir[a];
                }
            }
        }
    }
    took
}

/// The soil's velocity at a row (m/s).
fn velocity(nodes: &[(usize, f64)], weight: f64, slots: &[Slot]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for &(k, w) in nodes {
        for (a, c) in v.iter_mut().enumerate() {
            *c += w / weight * slots[k].v[a];
        }
    }
    v
}

/// The friction row of one patch: the surface samples of a body and part nearest one node,
/// their soil velocity the area-weighted mean of theirs.
///
/// One row a patch, not one a sample: samples half a cell apart reach nearly the same
/// nodes with nearly the same weights, and their no-slip rows, nearly alike, made the
/// sweeps converge by about 1 % each (the rough T-bar's solves ran to `MAX_SWEEPS`). A
/// patch is the surface a node's velocity stands for, as a mortar method's multiplier
/// is (docs/performance.md, "Rigid-body contact").
struct Patch {
    /// The contacts of its samples, the first one the patch's head (its key and memory).
    members: Vec<usize>,
    /// Area-weighted mean of the samples' normals, unit.
    normal: [f64; 3],
    /// tan δ of the part (infinite when rough).
    friction: f64,
    /// Σ of the samples' adhesion caps (N s).
    adhesion: f64,
    /// (slot, weight): Σ over the samples of their area × w_i/W.
    nodes: Vec<(usize, f64)>,
    /// Σ of the weights (the samples' area).
    weight: f64,
    /// Friction impulse so far (N s, x y z).
    impulse: [f64; 3],
}

/// The patches of the samples that carry friction or adhesion, in order of their first
/// sample.
fn patches(contacts: &[Contact]) -> Vec<Patch> {
    let mut out: Vec<Patch> = Vec::new();
    let mut index: std::collections::HashMap<(usize, usize, usize), usize> = Default::default();
    for (c, p) in contacts.iter().enumerate() {
        if !p.surface || (p.friction == 0.0 && p.adhesion == 0.0) {
            continue;
        }
        let scale = p.area / p.weight;
        let j = *index.entry((p.body, p.part, p.patch)).or_insert_with(|| {
            out.push(Patch {
                members: Vec::new(),
                normal: [0.0; 3],
                friction: p.friction,
                adhesion: 0.0,
                nodes: Vec::new(),
                weight: 0.0,
                impulse: [0.0; 3],
            });
            out.len() - 1
        });
        let g = &mut out[j];
        g.members.push(c);
        (0..3).for_each(|a| g.normal[a] += p.area * p.normal[a]);
        g.adhesion += p.adhesion;
        g.weight += p.area;
        for &(k, w) in &p.nodes {
            match g.nodes.iter_mut().find(|e| e.0 == k) {
                Some(e) => e.1 += w * scale,
                None => g.nodes.push((k, w * scale)),
            }
        }
    }
    for g in &mut out {
        let size = norm(g.normal);
        g.normal = g.normal.map(|c| c / size);
    }
    out
}

/// The normal impulse a patch's friction may lean on: its nodes' pressed impulse along its
/// normal, each node's shared among the patches that reach it by their weights (so the
/// caps sum to the whole normal impulse, the inside nodes' included).
fn leaning(g: &Patch, slots: &[Slot]) -> f64 {
    g.nodes
        .iter()
        .map(|&(k, w)| {
            let s = &slots[k];
            if s.share > 0.0 {
                dot(s.pressed, g.normal).max(0.0) * (w / g.weight) / s.share
            } else {
                0.0
            }
        })
        .sum()
}

/// Gives the soil at a patch the friction impulse `j` (N s, x y z), spread as [`spread`]
/// says along its direction; returns the change of the patch's velocity (m/s) and the
/// impulse the soil took.
fn apply(g: &mut Patch, slots: &mut [Slot], j: [f64; 3]) -> (f64, [f64; 3]) {
    let size = norm(j);
    if size <= 0.0 {
        return (0.0, [0.0; 3]);
    }
    let dir = j.map(|c| c / size);
    let (s2, mass) = spread(&g.nodes, g.weight, slots, dir);
    if s2 <= 0.0 || mass <= 0.0 {
        return (0.0, [0.0; 3]);
    }
    let delta = size / mass;
    let took = push(&g.nodes, g.weight, slots, dir, delta, s2, false);
    (0..3).for_each(|a| g.impulse[a] += took[a]);
    (delta, took)
}

/// One friction step at a patch: no slip where rough, else the slip taken out by an
/// impulse held within tan δ times the normal impulse it leans on plus the adhesion cap
/// (Coulomb's disc, projected as a whole); nothing where the soil is not in contact.
/// Returns the change of the patch's velocity (m/s).
fn rub(g: &mut Patch, contacts: &[Contact], slots: &mut [Slot], vb: [f64; 3]) -> f64 {
    let n = g.normal;
    let v = velocity(&g.nodes, g.weight, slots);
    let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
    let slip: [f64; 3] = std::array::from_fn(|a| rel[a] - dot(rel, n) * n[a]);
    let speed = norm(slip);
    // Friction acts where the soil is in contact: a sample presses, or the patch's nodes
    // were pressed and the soil does not leave (a separation slower than a tenth of the
    // slip). Its cap leans on its nodes' normal impulse.
    let pressing: f64 = g.members.iter().map(|&c| contacts[c].normal_impulse).sum();
    let lean = leaning(g, slots);
    if !(pressing > 0.0 || (lean > 0.0 && dot(rel, n) <= 0.1 * speed)) {
        return 0.0;
    }
    let sofar = g.impulse;
    let mut want = sofar;
    if speed > 0.0 {
        let t: [f64; 3] = slip.map(|c| -c / speed);
        let (s2, mass) = spread(&g.nodes, g.weight, slots, t);
        if s2 > 0.0 && mass > 0.0 {
            (0..3).for_each(|a| want[a] += t[a] * speed * mass);
        }
    }
    if g.friction.is_finite() {
        let cap = g.friction * lean.max(pressing) + g.adhesion;
        let size = norm(want);
        if size > cap {
            want = want.map(|c| c * cap / size);
        }
    }
    let change: [f64; 3] = std::array::from_fn(|a| want[a] - sofar[a]);
    apply(g, slots, change).0
}

/// Projected Gauss–Seidel, each normal impulse and each patch's friction impulse starting
/// at its value in `memory` (zero when it has none): no entry into a body moving at
/// `body_velocity` (m/s, per body) at any contact, then friction (each sample's
/// [`Contact::friction`] and [`Contact::adhesion`], pooled per patch) where the soil presses.
pub fn solve(set: &mut Contacts, body_velocity: &[[f64; 3]], memory: &Memory) {
    let slots = &mut set.slots[..];
    for s in slots.iter_mut() {
        s.pressed = [0.0; 3];
        s.share = 0.0;
    }
    for p in set.contacts.iter_mut() {
        p.normal_impulse = 0.0;
        p.impulse = [0.0; 3];
        p.friction_impulse = [0.0; 3];
    }
    let mut patches = patches(&set.contacts);
    for g in &patches {
        for &(k, w) in &g.nodes {
            slots[k].share += w / g.weight;
        }
    }
    // How each constraint's normal change spreads: the weights, inertias and free axes do
    // not change during the solve.
    let normal_spread: Vec<(f64, f64)> = set
        .contacts
        .iter()
        .map(|p| spread(&p.nodes, p.weight, slots, p.normal))
        .collect();
    // The scale of the solve: the fastest entry into a body before any impulse.
    let mut reference: f64 = 0.0;
    for p in &set.contacts {
        let v = velocity(&p.nodes, p.weight, slots);
        let vb = body_velocity[p.body];
        let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
        reference = reference.max(-dot(rel, p.normal));
    }
    let mut first = None;
    // Warm start: each contact's normal impulse of the last solve, applied at once; then
    // each patch's friction impulse where its samples press again, within its cap on the
    // normal impulses just restored.
    if !memory.is_empty() {
        let recall = |key: u64| {
            memory
                .binary_search_by_key(&key, |m| m.key)
                .ok()
                .map(|j| memory[j])
        };
        for (p, &(s2, mass)) in set.contacts.iter_mut().zip(&normal_spread) {
            if s2 <= 0.0 || mass <= 0.0 {
                continue;
            }
            if let Some(m) = recall(p.key).filter(|m| m.normal > 0.0) {
                p.normal_impulse = m.normal;
                let took = push(&p.nodes, p.weight, slots, p.normal, m.normal / mass, s2, true);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
        }
        for g in &mut patches {
            let pressing: f64 = g.members.iter().map(|&c| set.contacts[c].normal_impulse).sum();
            let Some(m) = recall(set.contacts[g.members[0]].key) else {
                continue;
            };
            if pressing <= 0.0 {
                continue;
            }
            let mut jt = tangential(m.tangential, g.normal);
            let size = norm(jt);
            let cap = g.friction * leaning(g, slots).max(pressing) + g.adhesion;
            if size > cap {
                jt = jt.map(|c| c * cap / size);
            }
            let took = apply(g, slots, jt).1;
            let head = &mut set.contacts[g.members[0]];
            (0..3).for_each(|a| head.impulse[a] += took[a]);
        }
    }
    for _ in 0..MAX_SWEEPS {
        let mut largest: f64 = 0.0;
        for (p, &(s2, mass)) in set.contacts.iter_mut().zip(&normal_spread) {
            let vb = body_velocity[p.body];
            let n = p.normal;
            if s2 <= 0.0 || mass <= 0.0 {
                continue;
            }
            let v = velocity(&p.nodes, p.weight, slots);
            let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
            // The normal impulse stays ≥ 0 in total: a sample only pushes.
            let delta = (-dot(rel, n)).max(-p.normal_impulse / mass);
            largest = largest.max(delta.abs());
            if delta != 0.0 {
                p.normal_impulse += delta * mass;
                let took = push(&p.nodes, p.weight, slots, n, delta, s2, true);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
        }
        for g in &mut patches {
            let head = g.members[0];
            let before = g.impulse;
            let vb = body_velocity[set.contacts[head].body];
            largest = largest.max(rub(g, &set.contacts, slots, vb));
            let p = &mut set.contacts[head];
            (0..3).for_each(|a| p.impulse[a] += g.impulse[a] - before[a]);
        }
        let scale = reference.max(*first.get_or_insert(largest));
        if largest <= TOLERANCE * scale {
            break;
        }
    }
    for g in &patches {
        set.contacts[g.members[0]].friction_impulse = g.impulse;
    }
}
