//! The contact solver: the soil's velocity at a body's surface samples may not enter the
//! body; friction and adhesion limit its slip where it presses.
//!
//! A sample's soil velocity is v(x_s) = Σ_i (w_i/W) v_i over the nodes that carry soil
//! (W = Σ w_i). A change δ of it along a unit direction d is spread as Δv_i ∝ (w_i/W) d / m̃_i
//! over the free axes, the least change of kinetic energy that makes it; the impulse the
//! soil takes is Σ m̃_i Δv_i. The nodes inside a body hold their normal velocity as
//! constraints of their own (without them a node that only a point's tail reaches, inside
//! the body, runs into it under a confining stress). Where the soil's surface stands off
//! the body's, a constraint lets it approach as fast as closes that gap in a step
//! ([`Contact::closing`], [`crate::systems::soil_gap`]). The constraints are visited in a
//! fixed order (projected Gauss–Seidel: the normal impulse summed per constraint stays
//! ≥ 0, a surface sample's tangential one within tan δ times the normal impulse it leans
//! on plus the adhesion cap) until no sweep changes a contact's velocity by more than
//! `solver.contact_tolerance` ([`TOLERANCE`], 1e-5, by default) of the fastest entry
//! before the solve (or of the first sweep's largest change, when that is larger). The
//! order is fixed, so the result is the same on any thread count.
//!
//! Each solve starts from the normal impulses the last step's ended with ([`Memory`],
//! kept in checkpoints): the overlapping samples of a curved surface and the inside nodes
//! hold more constraints than their nodes have velocities, and from zero the sweeps take
//! hundreds of passes to share a confined soil's push among them (the T-bar's first sweep
//! changes velocities by 6 m/s, the 200th still by 1e-4 of that); from the last step's
//! share the first sweep changes them by 1e-4 of it. With a few cold sweeps only, part of
//! each step's entry is left and a confined soil streams past the body. Where two bodies
//! push the same nodes from opposite sides and cancel more than they pass on, the weaker
//! side starts cold instead (`contested`), so that the pair does not grow.
//!
//! Friction acts at a sample that presses itself, and the normal impulse its cap leans on
//! is its nodes' (each node's share of what every constraint pushed into it, split among
//! the samples that reach it by weight) when that is more than its own: the inside nodes
//! carry much of a body's normal force, and a cap of the sample's own impulse held a
//! block on a rigid base with a hundredth of its friction (docs/tried-and-dropped.md).
//! Acting wherever its nodes were pressed (not only where the sample presses) let a rough
//! T-bar drag the soil behind it and the solve stop converging.

/// Most Gauss–Seidel sweeps over the samples per solve.
const MAX_SWEEPS: usize = 200;

/// The default of `solver.contact_tolerance`: a solve ends when no sweep changes a
/// contact's velocity by more than this fraction of the fastest entry into a body before
/// the solve, or of the first sweep's largest change when that is larger (soil at rest
/// against a held body enters it at no speed).
pub const TOLERANCE: f64 = 1e-5;

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
    /// Where the constraint stands (m, x y z): the sample's place, or the node's.
    pub at: [f64; 3],
    /// Unit outward normal of the body (x y z).
    pub normal: [f64; 3],
    /// Friction coefficient tan δ of the sample's part (a rough part's: the soil's tan φ
    /// beside it; infinite, no slip, where that soil has no strength).
    pub friction: f64,
    /// Adhesion cap on the sample's tangential impulse (N s), a·A_s·Δt.
    pub adhesion: f64,
    /// False for a node inside the body: it holds the normal only (friction and adhesion
    /// act at the surface samples).
    pub surface: bool,
    /// (slot, weight) of the nodes that carry soil.
    pub nodes: Vec<(usize, f64)>,
    /// Σ w over those nodes.
    pub weight: f64,
    /// Normal impulse so far (N s, ≥ 0).
    pub normal_impulse: f64,
    /// Impulse on the soil so far (N s, x y z).
    pub impulse: [f64; 3],
    /// How fast the soil may still approach the body here (m/s): the gap between the
    /// soil's surface and the body's over Δt, zero where the soil touches
    /// ([`crate::systems::soil_gap`]).
    pub closing: f64,
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

/// The normal impulse (N s) each contact ended the last solve with, by key in ascending
/// order: a solve starts from it (warm start), so that a body pressed by the same soil step
/// after step does not build its reaction up from zero every step.
pub type Memory = Vec<(u64, f64)>;

/// The key of a contact: body `body`, a surface sample (`surface`) or an inside node, and
/// the sample's or the node's index.
pub fn key(body: usize, surface: bool, index: usize) -> u64 {
    ((body as u64) << 48) | ((surface as u64) << 47) | index as u64
}

/// What a solve leaves for the next one to start from: each contact's normal impulse by key.
pub fn remember(contacts: &[Contact]) -> Memory {
    let mut memory: Memory = contacts.iter().map(|p| (p.key, p.normal_impulse)).collect();
    memory.sort_unstable_by_key(|&(k, _)| k);
    memory
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One node of a constraint as a solve uses it: its slot, its share w_i/W of the
/// constraint's velocity and its coefficient (w_i/W)/m̃_i, fixed for the solve (the
/// weights and inertias do not change within it).
#[derive(Clone, Copy, Debug)]
struct Term {
    /// Index in [`Contacts::slots`].
    slot: usize,
    /// w_i/W.
    share: f64,
    /// (w_i/W)/m̃_i: the node's part of a change at the constraint, the least change of
    /// kinetic energy that makes it.
    coefficient: f64,
}

/// Each constraint's [`Term`]s, laid end to end in constraint order, and where each
/// constraint's run of them starts (one entry more than there are constraints).
fn terms(contacts: &[Contact], slots: &[Slot]) -> (Vec<Term>, Vec<usize>) {
    let mut terms = Vec::with_capacity(contacts.iter().map(|p| p.nodes.len()).sum());
    let mut starts = Vec::with_capacity(contacts.len() + 1);
    starts.push(0);
    for p in contacts {
        terms.extend(p.nodes.iter().map(|&(k, w)| {
            let share = w / p.weight;
            Term {
                slot: k,
                share,
                coefficient: share / slots[k].inertia,
            }
        }));
        starts.push(terms.len());
    }
    (terms, starts)
}

/// How a change of the soil's velocity at the constraint along the unit `dir` spreads over
/// its nodes: Δv_i = δ (w_i/W) dir / (m̃_i s²) on the free axes, s² = Σ (w_i/W)²/m̃_i
/// (dir on free axes)², which moves v(x_s) by δ. Returns (s², the impulse per unit δ,
/// Σ m̃_i (w_i/W)/m̃_i dir² / s²).
fn spread(terms: &[Term], slots: &[Slot], dir: [f64; 3]) -> (f64, f64) {
    let (mut s2, mut m) = (0.0, 0.0);
    for t in terms {
        let s = &slots[t.slot];
        let d2: f64 = (0..3).filter(|&a| s.free[a]).map(|a| dir[a] * dir[a]).sum();
        s2 += t.share * t.coefficient * d2;
        m += s.inertia * t.coefficient * d2;
    }
    if s2 > 0.0 {
        (s2, m / s2)
    } else {
        (0.0, 0.0)
    }
}

/// Changes the soil's velocity at the constraint by `delta` (m/s) along the unit `dir`,
/// spread as [`spread`] says; returns the impulse the soil took (N s, x y z).
fn push(terms: &[Term], slots: &mut [Slot], dir: [f64; 3], delta: f64, s2: f64, normal: bool) -> [f64; 3] {
    let mut took = [0.0; 3];
    for t in terms {
        let s = &mut slots[t.slot];
        let dv = delta * t.coefficient / s2;
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

/// The normal impulse a surface sample's friction may lean on: its nodes' pressed impulse
/// along the sample's `normal`, each node's shared among the samples that reach it by their
/// weights (so the caps sum to the whole normal impulse, the inside nodes' included).
fn leaning(terms: &[Term], slots: &[Slot], normal: [f64; 3]) -> f64 {
    terms
        .iter()
        .map(|t| {
            let s = &slots[t.slot];
            if s.share > 0.0 {
                dot(s.pressed, normal).max(0.0) * t.share / s.share
            } else {
                0.0
            }
        })
        .sum()
}

/// The soil's velocity at the constraint (m/s).
fn velocity(terms: &[Term], slots: &[Slot]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for t in terms {
        for (a, c) in v.iter_mut().enumerate() {
            *c += t.share * slots[t.slot].v[a];
        }
    }
    v
}

/// Which constraints reach a node that the last solve pushed from opposite sides by two
/// bodies (the pushes of each body's constraints on the node, summed by their remembered
/// impulses `warm`, at more than 90°): two bodies that touch, or nearly, across the node.
///
/// Such a pair holds the node's velocity from both sides, so any equal and opposite pair
/// of impulses leaves the velocities unchanged and the solve cannot tell how much each
/// pushes; started from the last step's impulses the pair grows from step to step (a wall
/// whose foot slid on a fixed block read −10.8 MN/m against the block's +10.7,
/// docs/scene-format.md). With one side started from zero each step the pair cannot grow
/// across steps. Only bodies that pushed the same nodes pay for it; a body alone, or parts
/// of one body, keep their warm start. With three or more bodies on a node, every body but
/// the first to push it counts as one side.
fn contested(
    contacts: &[Contact],
    warm: &[f64],
    terms: &[Term],
    starts: &[usize],
    slots: usize,
) -> Vec<bool> {
    // Per node: the first body that pushed it, its pushes summed, and the other bodies'.
    let mut owner = vec![usize::MAX; slots];
    let mut own = vec![[0.0; 3]; slots];
    let mut other = vec![[0.0; 3]; slots];
    let mut shared = false;
    for (c, p) in contacts.iter().enumerate() {
        if warm[c] <= 0.0 {
            continue;
        }
        for t in &terms[starts[c]..starts[c + 1]] {
            let k = t.slot;
            if owner[k] == usize::MAX {
                owner[k] = p.body;
            }
            let sum = if owner[k] == p.body {
                &mut own[k]
            } else {
                shared = true;
                &mut other[k]
            };
            (0..3).for_each(|a| sum[a] += warm[c] * t.share * p.normal[a]);
        }
    }
    if !shared {
        return vec![false; contacts.len()];
    }
    // A node is contested where the two sides' pushes cancel more than they pass on to
    // the soil: the weaker side's push exceeds the net. There the constraints of the
    // weaker side that face the stronger side's push start cold, so the pair cannot grow
    // across steps while one side rebuilds from zero. The side that carries the load, the
    // weaker body's other faces and a pair that passes most of its push on (a wall a few
    // centimetres above a base, both holding the soil at its corner) keep their warm start.
    (contacts.iter().enumerate())
        .map(|(c, p)| {
            terms[starts[c]..starts[c + 1]].iter().any(|t| {
                let k = t.slot;
                let (mine, theirs) = if owner[k] == p.body {
                    (own[k], other[k])
                } else {
                    (other[k], own[k])
                };
                let net: [f64; 3] = std::array::from_fn(|a| mine[a] + theirs[a]);
                let weaker = dot(mine, mine);
                dot(mine, theirs) < 0.0
                    && weaker < dot(theirs, theirs)
                    && weaker > dot(net, net)
                    && dot(p.normal, theirs) < 0.0
            })
        })
        .collect()
}

/// Projected Gauss–Seidel over the samples, each normal impulse starting at its value in
/// `memory` (zero when it has none; the tangential ones at zero): no entry into a body
/// moving at `body_velocity` (m/s, per body) faster than the soil's gap closes
/// ([`Contact::closing`]), then friction (each sample's
/// [`Contact::friction`] and [`Contact::adhesion`]) where a sample presses; until no sweep
/// changes a contact's velocity by more than `tolerance` of the solve's scale
/// ([`TOLERANCE`] by default).
pub fn solve(set: &mut Contacts, body_velocity: &[[f64; 3]], memory: &Memory, tolerance: f64) {
    let slots = &mut set.slots[..];
    // Each constraint's nodes as the sweeps use them, and how its normal change spreads:
    // the weights, inertias and free axes do not change during the solve.
    let (terms, starts) = terms(&set.contacts, slots);
    let of = |c: usize| &terms[starts[c]..starts[c + 1]];
    for s in slots.iter_mut() {
        s.pressed = [0.0; 3];
        s.share = 0.0;
    }
    for (c, p) in set.contacts.iter_mut().enumerate() {
        p.normal_impulse = 0.0;
        p.impulse = [0.0; 3];
        if p.surface {
            for t in of(c) {
                slots[t.slot].share += t.share;
            }
        }
    }
    let normal_spread: Vec<(f64, f64)> = (set.contacts.iter().enumerate())
        .map(|(c, p)| spread(of(c), slots, p.normal))
        .collect();
    // The scale of the solve: the fastest entry into a body before any impulse.
    let mut reference: f64 = 0.0;
    for (c, p) in set.contacts.iter().enumerate() {
        let v = velocity(of(c), slots);
        let vb = body_velocity[p.body];
        let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
        reference = reference.max(-dot(rel, p.normal) - p.closing);
    }
    let mut first = None;
    // Warm start: each contact's normal impulse of the last solve, applied at once, but
    // not where two bodies hold the same nodes from opposite sides ([`contested`]).
    if !memory.is_empty() {
        let warm: Vec<f64> = (set.contacts.iter())
            .map(|p| match memory.binary_search_by_key(&p.key, |&(k, _)| k) {
                Ok(j) => memory[j].1,
                Err(_) => 0.0,
            })
            .collect();
        let cold = contested(&set.contacts, &warm, &terms, &starts, slots.len());
        for (c, (p, &(s2, mass))) in set.contacts.iter_mut().zip(&normal_spread).enumerate() {
            if s2 <= 0.0 || mass <= 0.0 || cold[c] {
                continue;
            }
            let lambda = warm[c];
            if lambda > 0.0 {
                p.normal_impulse = lambda;
                let took = push(of(c), slots, p.normal, lambda / mass, s2, true);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
        }
    }
    for _ in 0..MAX_SWEEPS {
        let mut largest: f64 = 0.0;
        for (c, (p, &(s2, mass))) in set.contacts.iter_mut().zip(&normal_spread).enumerate() {
            let terms = of(c);
            let vb = body_velocity[p.body];
            let n = p.normal;
            if s2 <= 0.0 || mass <= 0.0 {
                continue;
            }
            let v = velocity(terms, slots);
            let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
            // The soil may close its gap, no more; the normal impulse stays ≥ 0 in total:
            // a sample only pushes.
            let delta = (-dot(rel, n) - p.closing).max(-p.normal_impulse / mass);
            largest = largest.max(delta.abs());
            if delta != 0.0 {
                p.normal_impulse += delta * mass;
                let took = push(terms, slots, n, delta, s2, true);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
            let m = p.friction;
            if !p.surface || (m == 0.0 && p.adhesion == 0.0) {
                continue;
            }
            let v = velocity(terms, slots);
            let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
            let slip: [f64; 3] = std::array::from_fn(|a| rel[a] - dot(rel, n) * n[a]);
            let speed = dot(slip, slip).sqrt();
            if speed <= 0.0 {
                continue;
            }
            // Friction acts where the soil is in contact: the sample presses, or its nodes
            // were pressed and the soil does not leave (a separation slower than a tenth
            // of the slip). Its cap leans on its nodes' normal impulse.
            let lean = leaning(terms, slots, n);
            let touching = p.normal_impulse > 0.0 || (lean > 0.0 && dot(rel, n) <= 0.1 * speed);
            if !touching {
                continue;
            }
            let t: [f64; 3] = slip.map(|c| -c / speed);
            let (s2, mass) = spread(terms, slots, t);
            if s2 <= 0.0 || mass <= 0.0 {
                continue;
            }
            // The tangential impulse so far, and the most it may reach.
            let sofar = dot(p.impulse, t);
            let cap = if m.is_infinite() {
                f64::INFINITY
            } else {
                m * lean.max(p.normal_impulse) + p.adhesion
            };
            let delta = speed.min((cap - sofar).max(0.0) / mass);
            largest = largest.max(delta);
            if delta > 0.0 {
                let took = push(terms, slots, t, delta, s2, false);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
        }
        let scale = reference.max(*first.get_or_insert(largest));
        if largest <= tolerance * scale {
            break;
        }
    }
}
