//! The contact solver: the soil's velocity at a body's surface samples may not enter the
//! body; friction and adhesion limit its slip where it presses.
//!
//! A sample's soil velocity is v(x_s) = Σ_i (w_i/W) v_i over the nodes that carry soil
//! (W = Σ w_i). An impulse j along a unit direction d spreads as Δv_i = j (w_i/W) d / m̃_i
//! over its free axes, the least change of kinetic energy that moves v(x_s) by j times the
//! sample's compliance Σ (w_i/W)² d·d / m̃_i. The samples are visited in a fixed order
//! four times (projected Gauss–Seidel: the normal impulse summed per sample stays
//! ≥ 0, the tangential one within tan δ times it plus the adhesion cap), so overlapping
//! samples share their nodes' correction and the result is the same on any thread count.

/// Gauss–Seidel sweeps over the samples per solve.
const SWEEPS: usize = 4;

/// A surface sample that meets soil this step: its nodes (slots of [`Contacts::slots`])
/// and weights, and what it has pushed.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// Index of the body.
    pub body: usize,
    /// Index of the part in the body.
    pub part: usize,
    /// Unit outward normal of the body (x y z).
    pub normal: [f64; 3],
    /// Adhesion cap on the sample's tangential impulse (N s), a·A_s·Δt.
    pub adhesion: f64,
    /// (slot, weight) of the nodes that carry soil.
    pub nodes: Vec<(usize, f64)>,
    /// Σ w over those nodes.
    pub weight: f64,
    /// Normal impulse so far (N s, ≥ 0).
    pub normal_impulse: f64,
    /// Impulse on the soil so far (N s, x y z).
    pub impulse: [f64; 3],
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

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One impulse `j` (N s, along the unit `dir`) on the sample's nodes; returns the impulse
/// the soil took (N s, x y z; less than `j` along held axes).
fn push(p: &Contact, slots: &mut [Slot], dir: [f64; 3], j: f64) -> [f64; 3] {
    let mut took = [0.0; 3];
    for &(k, w) in &p.nodes {
        let s = &mut slots[k];
        for a in 0..3 {
            if s.free[a] {
                let dj = j * w / p.weight * dir[a];
                s.v[a] += dj / s.inertia;
                took[a] += dj;
            }
        }
    }
    took
}

/// Σ (w/W)² dir_a² / m̃ over the sample's nodes: the velocity an impulse of 1 N s along
/// `dir` gives the soil at the sample.
fn compliance(p: &Contact, slots: &[Slot], dir: [f64; 3]) -> f64 {
    p.nodes
        .iter()
        .map(|&(k, w)| {
            let s = &slots[k];
            let share = w / p.weight;
            (0..3)
                .filter(|&a| s.free[a])
                .map(|a| dir[a] * dir[a])
                .sum::<f64>()
                * share
                * share
                / s.inertia
        })
        .sum()
}

/// The soil's velocity at the sample (m/s).
fn velocity(p: &Contact, slots: &[Slot]) -> [f64; 3] {
    let mut v = [0.0; 3];
    for &(k, w) in &p.nodes {
        for (a, c) in v.iter_mut().enumerate() {
            *c += w / p.weight * slots[k].v[a];
        }
    }
    v
}

/// Projected Gauss–Seidel over the samples, each impulse starting at zero: no entry into a
/// body moving at `body_velocity` (m/s, per body), then friction (`mu` = tan δ per body,
/// infinite when rough, 0 with adhesion alone) where a sample presses.
pub fn solve(set: &mut Contacts, body_velocity: &[[f64; 3]], mu: &[f64]) {
    let slots = &mut set.slots[..];
    for p in set.contacts.iter_mut() {
        p.normal_impulse = 0.0;
        p.impulse = [0.0; 3];
    }
    for _ in 0..SWEEPS {
        for p in set.contacts.iter_mut() {
            let vb = body_velocity[p.body];
            let n = p.normal;
            let c = compliance(p, slots, n);
            if c <= 0.0 {
                continue;
            }
            let rel: [f64; 3] = {
                let v = velocity(p, slots);
                std::array::from_fn(|a| v[a] - vb[a])
            };
            // λ ≥ 0 in total: a sample only pushes.
            let want = (-dot(rel, n) / c).max(-p.normal_impulse);
            if want != 0.0 {
                p.normal_impulse += want;
                let took = push(p, slots, n, want);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
            let m = mu[p.body];
            if p.normal_impulse <= 0.0 || (m == 0.0 && p.adhesion == 0.0) {
                continue;
            }
            let v = velocity(p, slots);
            let rel: [f64; 3] = std::array::from_fn(|a| v[a] - vb[a]);
            let slip: [f64; 3] = std::array::from_fn(|a| rel[a] - dot(rel, n) * n[a]);
            let speed = dot(slip, slip).sqrt();
            if speed <= 0.0 {
                continue;
            }
            let t: [f64; 3] = slip.map(|c| -c / speed);
            let ct = compliance(p, slots, t);
            if ct <= 0.0 {
                continue;
            }
            // The tangential impulse so far, and the most it may reach.
            let sofar = dot(p.impulse, t);
            let cap = if m.is_infinite() {
                f64::INFINITY
            } else {
                m * p.normal_impulse + p.adhesion
            };
            let j = (speed / ct).min((cap - sofar).max(0.0));
            if j > 0.0 {
                let took = push(p, slots, t, j);
                (0..3).for_each(|a| p.impulse[a] += took[a]);
            }
        }
    }
}
