//! Control of the rigid bodies: each is driven in increments, and the static state that
//! ends an increment is a row of the curve.
//!
//! Under displacement control (`motion`) a body moves one increment at its velocity, then
//! holds still while kinetic damping relaxes the soil to a static state (the run's own
//! stopping rule); the state is recorded (`curve.csv`: travel, the soil's resistance on
//! the body, the mean pressure over its `area`, and a row per part for a body of several)
//! and the next increment starts. A kinetic-damping reset zeroes the soil's velocities,
//! never the body's: a plain reset step moves nothing, and the body travels nothing in it.
//!
//! Under load control (`load`) the force F_k of increment k acts on the body, which moves
//! along the load's direction e only (guided), as a mass M with the soil its contacts
//! reach (m_c, `BodyState::contact_mass`):
//!
//!   V ← V + Δt ((F_k − R)·e) / (M + m_c),
//!
//! R the force it exerts on the soil this step (`rigid_contact`). Counting m_c makes the
//! update the momentum balance of the body and the soil held to it, which is stable at
//! the soil's own time step for any M; where the body rests (F_k = R·e) neither mass
//! matters. The body's kinetic energy ½ M V² is part of the energy the peak watch follows,
//! and a reset zeroes V with the soil's velocities. The static state needs |F_k − R|·e
//! within the tolerance of |F_k| as well as the run's K_F and K_E (`convergence`); its
//! travel is the displacement along e.
//!
//! A body whose increment finds no static state before `max_time` stops the run with
//! [`StepError::NoStaticState`] naming the increment; a loaded body that leaves the grid
//! stops it with [`StepError::BodyLeftGrid`]. The curve so far is kept.
//!
//! Grid contact holds the soil's velocity at the nodes inside a body, so the points near
//! its surface move with a field that does not enter it; a point whose centre still ends a
//! step inside (by less than a cell: the nodes around it straddle the surface) is put back
//! on the surface along the normal. The count and the deepest entry are kept
//! ([`crate::rigid::BodyState::entries`]).

use crate::components::{Displacement, MaterialId, Position, Stress, Volume};
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, col_mut, points_with};
use crate::materials::{with_state_column, MaterialState, WithStates};
use crate::model::CurvePoint;
use crate::model::LoadStage;
use crate::rigid::{BodyLoad, BodyState, InSitu, RigidBodySpec};
use crate::schedule::System;
use crate::state::StopReason;
use crate::state::{Numerics, SolverState};
use crate::systems::increments::Increments;
use crate::tensor::StoredSym;

/// Moves the bodies, holds them at the end of an increment and, at the static state that
/// follows, records the curve and starts the next increment.
#[derive(Debug)]
pub struct RigidControl {
    bodies: Vec<RigidBodySpec>,
    /// Per body: the first stage in which it is driven ([`RigidBodySpec::first_stage`]).
    first: Vec<Option<usize>>,
}

impl RigidControl {
    /// The system for these bodies (in scene order) in a run of these `stages`.
    pub fn new(bodies: Vec<RigidBodySpec>, stages: &[LoadStage]) -> Self {
        let names: Vec<&str> = stages.iter().map(|t| t.name.as_str()).collect();
        let first = bodies.iter().map(|b| b.first_stage(&names)).collect();
        RigidControl { bodies, first }
    }
}

/// True when a body whose first driven stage is `first` is driven during stage `k`.
fn driven(first: Option<usize>, k: usize) -> bool {
    first.is_some_and(|f| k >= f)
}

/// Puts every point whose centre lies inside a body back on its surface (along the
/// normal), moving its displacement with it. Returns (points moved, deepest entry in m)
/// per body.
fn push_out<D: Dim>(ctx: &mut Context<D>, bodies: &[RigidBodySpec]) -> Vec<(u64, f64)> {
    use rayon::prelude::*;
    /// Points a task: a chunk's bounds tests are cheap, so chunks are long.
    const CHUNK: usize = 4096;
    let mut out = vec![(0, 0.0); bodies.len()];
    for (b, body) in bodies.iter().enumerate() {
        let offset = ctx.state.control.bodies[b].offset;
        let (lo, hi) = body.bounds(D::N);
        // Moves a point inside the body to its surface: its shift (m), and its depth (m).
        let shift = |xp: &Position<D::Vec>| -> Option<(D::Vec, f64)> {
            let at: [f64; 3] = std::array::from_fn(|a| D::vec_to3(xp.0)[a] - offset[a]);
            if (0..D::N).any(|a| at[a] < lo[a] || at[a] > hi[a]) {
                return None;
            }
            let (phi, normal, _) = body.distance(at, D::N);
            (phi < 0.0).then(|| (D::vec_from(normal.map(|c| -phi * c)), -phi))
        };
        // Each point is moved on its own; the count and the deepest entry come out the
        // same in any order (a sum of integers, a maximum), so on any thread count.
        let add = |a: (u64, f64), b: (u64, f64)| (a.0 + b.0, a.1.max(b.1));
        // One chunk of points, with its displacements where the points keep them.
        let chunk = |x: &mut [Position<D::Vec>], mut u: Option<&mut [Displacement<D::Vec>]>| {
            let mut n = (0, 0.0);
            for (p, xp) in x.iter_mut().enumerate() {
                if let Some((s, depth)) = shift(xp) {
                    xp.0 += s;
                    if let Some(u) = u.as_deref_mut() {
                        u[p].0 += s;
                    }
                    n = add(n, (1, depth));
                }
            }
            n
        };
        for arch in points_with::<Position<D::Vec>>(&ctx.world) {
            let mut x = col_mut::<Position<D::Vec>>(arch);
            let moved = match arch.get::<&mut Displacement<D::Vec>>() {
                Some(mut u) => (x.par_chunks_mut(CHUNK).zip(u.par_chunks_mut(CHUNK)))
                    .map(|(x, u)| chunk(x, Some(u)))
                    .reduce(|| (0, 0.0), add),
                None => (x.par_chunks_mut(CHUNK))
                    .map(|x| chunk(x, None))
                    .reduce(|| (0, 0.0), add),
            };
            out[b] = add(out[b], moved);
        }
    }
    out
}

/// One step of a body under load `l`: it moves `moved` seconds (0 in a reset) at its
/// velocity, which the unbalanced load then changes over `full` seconds (zeroed instead at
/// a kinetic-damping `reset`).
fn carry(l: &BodyLoad, b: &mut BodyState, moved: f64, full: f64, reset: bool) {
    let e = l.direction();
    for a in 0..3 {
        b.offset[a] += b.velocity[a] * moved;
    }
    b.travel = (0..3).map(|a| b.offset[a] * e[a]).sum();
    if reset {
        b.velocity = [0.0; 3];
        return;
    }
    // The mass is set at set-up (`scene::build`): the scene's or the displaced soil's. A
    // body built without one that touches no soil has nothing to move: it waits (and a
    // run that never balances it stops at `max_time` naming the increment).
    let mass = l.mass.unwrap_or(0.0) + b.contact_mass;
    if mass <= 0.0 {
        return;
    }
    let net: f64 = (0..3).map(|a| (b.load[a] - b.reaction[a]) * e[a]).sum();
    let speed: f64 = (0..3).map(|a| b.velocity[a] * e[a]).sum::<f64>() + full * net / mass;
    b.velocity = e.map(|c| c * speed);
}

/// Stops the run when a loaded body has left the grid on an axis its load acts along.
fn check_in_grid<D: Dim>(
    spec: &RigidBodySpec,
    b: &BodyState,
    grid: &Grid<D>,
    step: u64,
) -> Result<(), StepError> {
    let (lo, hi) = spec.bounds(D::N);
    let (lo, hi) = (
        std::array::from_fn(|a| lo[a] + b.offset[a]),
        std::array::from_fn(|a| hi[a] + b.offset[a]),
    );
    let o = D::vec_to3(grid.origin);
    let out = (0..D::N).any(|a| {
        let end = o[a] + grid.axes[a].cells as f64 * grid.cell_size;
        b.load[a] != 0.0 && (lo[a] < o[a] || hi[a] > end)
    });
    if out {
        return Err(StepError::BodyLeftGrid {
            step,
            body: spec.name.clone(),
            increment: b.increments + 1,
            lo,
            hi,
        });
    }
    Ok(())
}

/// At the run's `max_time`: the first body still in an increment of this stage found no
/// static state.
fn stuck(
    bodies: &[RigidBodySpec],
    first: &[Option<usize>],
    s: &SolverState,
    numerics: &Numerics,
) -> Result<(), StepError> {
    for ((spec, b), &f) in bodies.iter().zip(&s.control.bodies).zip(first) {
        if driven(f, s.control.stage) && b.increments < spec.increments() {
            return Err(StepError::NoStaticState {
                step: s.clock.step,
                time: s.clock.time,
                body: spec.name.clone(),
                increment: b.increments + 1,
                force_ratio: s.convergence.force_ratio(numerics.force_norm),
                unbalanced: spec.load.as_ref().map(|_| s.control.unbalanced()),
            });
        }
    }
    Ok(())
}

impl<D: Dim> System<D> for RigidControl {
    fn name(&self) -> &str {
        "rigid_control"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        record_ground(&self.bodies, ctx);
        let s = &mut ctx.state;
        let dt = s.resets.motion_dt(ctx.numerics.dt).unwrap_or(0.0);
        for (spec, b) in self.bodies.iter().zip(&mut s.control.bodies) {
            if let (Some(l), true) = (&spec.load, b.load != [0.0; 3]) {
                carry(l, b, dt, ctx.numerics.dt, s.resets.this_step);
                check_in_grid(spec, b, &ctx.grid, s.clock.step)?;
                continue;
            }
            let Some(m) = &spec.motion else { continue };
            if b.velocity == [0.0; 3] {
                continue;
            }
            let moved = Increments::new(m.vector(), m.travel, m.increment).advance(
                &mut b.velocity,
                &mut b.travel,
                b.increments,
                dt,
                ctx.numerics.dt,
            );
            for a in 0..3 {
                b.offset[a] += moved[a];
            }
        }
        for (b, (count, depth)) in push_out(ctx, &self.bodies).into_iter().enumerate() {
            let state = &mut ctx.state.control.bodies[b];
            state.entries += count;
            state.deepest_entry = state.deepest_entry.max(depth);
        }
        let s = &mut ctx.state;
        if s.stop == Some(StopReason::MaxTime) {
            stuck(&self.bodies, &self.first, s, &ctx.numerics)?;
        }
        // A static state: the run's stop, or one `prescribed_motion` took this step.
        if s.stop != Some(StopReason::Converged) && !s.control.milestone {
            return Ok(());
        }
        // Every body holds (a moving one blocks convergence): a static state. Its filters'
        // readings first, every rank taking part in each.
        let readings: Vec<Vec<Option<f64>>> = (self.bodies.iter().zip(&ctx.state.control.bodies))
            .map(|(spec, b)| {
                (spec.filters.iter())
                    .map(|f| filter_reading(ctx, spec, f.part(&spec.parts, D::N), f.place(), b.offset))
                    .collect()
            })
            .collect();
        let s = &mut ctx.state;
        let mut more = false;
        let bodies = self.bodies.iter().zip(&mut s.control.bodies).zip(&self.first);
        for (((spec, b), &first), readings) in bodies.zip(&readings) {
            // The mean pressure along the motion, or, for a body that holds its place, of
            // the whole force.
            let along = |f: [f64; 3]| -> f64 {
                match (&spec.motion, &spec.load) {
                    (Some(m), _) => (0..3).map(|a| f[a] * m.vector()[a] / m.speed()).sum(),
                    (_, Some(l)) => (0..3).map(|a| f[a] * l.direction()[a]).sum(),
                    _ => f.iter().map(|c| c * c).sum::<f64>().sqrt(),
                }
            };
            s.control.curve.push(CurvePoint {
                name: spec.name.clone(),
                step: s.clock.step,
                time: s.clock.time,
                displacement: b.travel,
                force: b.reaction,
                pressure: spec.area.map(|a| along(b.reaction) / a),
            });
            if spec.parts.len() > 1 {
                for (part, f) in spec.parts.iter().zip(&b.parts) {
                    s.control.curve.push(CurvePoint {
                        name: format!("{}.{}", spec.name, part.name),
                        step: s.clock.step,
                        time: s.clock.time,
                        displacement: b.travel,
                        force: *f,
                        pressure: part.area.map(|a| along(*f) / a),
                    });
                }
            }
            for (filter, &u) in spec.filters.iter().zip(readings) {
                s.control.curve.push(CurvePoint {
                    name: format!("{}.{}", spec.name, filter.name),
                    step: s.clock.step,
                    time: s.clock.time,
                    displacement: b.travel,
                    force: [0.0; 3],
                    pressure: u,
                });
            }
            if !driven(first, s.control.stage) || b.increments >= spec.increments() {
                continue;
            }
            b.increments += 1;
            s.control.milestone = true;
            if let Some(m) = &spec.motion {
                if b.travel < m.travel * (1.0 - 1e-9) {
                    b.velocity = m.vector();
                    more = true;
                }
            }
            if let Some(l) = &spec.load {
                if b.increments < l.increments {
                    b.load = l.at(b.increments);
                    more = true;
                }
            }
        }
        if more {
            s.go_on(&ctx.numerics);
        }
        Ok(())
    }
}

/// The pore pressure (Pa, compression positive) a filter at `at` (m, x y z, in the
/// starting frame of `body`, which has moved by `offset`) on the body's part `part` reads:
/// the volume-weighted mean over the points within one cell of it whose nearest part of
/// the body is `part`, of their water table's pressure and the excess an undrained
/// material holds ([`crate::rigid::filter`]); `None` when no such point lies that near.
/// Over MPI ranks the sums of every rank.
fn filter_reading<D: Dim>(
    ctx: &Context<D>,
    body: &RigidBodySpec,
    part: usize,
    at: [f64; 3],
    offset: [f64; 3],
) -> Option<f64> {
    let mut read = Reading::<D> {
        ctx,
        body,
        part,
        at,
        offset,
        sums: [0.0; 2],
    };
    for arch in points_with::<Volume>(&ctx.world) {
        with_state_column(arch, &mut read);
    }
    ctx.comm.sum(&mut read.sums);
    (read.sums[1] > 0.0).then(|| read.sums[0] / read.sums[1])
}

/// A filter's reading, summed archetype by archetype.
struct Reading<'a, D: Dim> {
    ctx: &'a Context<D>,
    /// The body, its filter's part, the filter's place in the starting frame (m) and the
    /// body's offset from it (m).
    body: &'a RigidBodySpec,
    part: usize,
    at: [f64; 3],
    offset: [f64; 3],
    /// Σ V u, Σ V.
    sums: [f64; 2],
}

impl<D: Dim> WithStates for Reading<'_, D> {
    /// Adds the archetype's points within a cell of the filter beside its part; `states`
    /// their state column, `None` for points without state (no excess pore pressure).
    fn with<T: MaterialState>(&mut self, arch: &hecs::Archetype, states: Option<&[T]>) {
        let (xg, vg, mg) = (
            col::<Position<D::Vec>>(arch),
            col::<Volume>(arch),
            col::<MaterialId>(arch),
        );
        let r2 = self.ctx.grid.cell_size * self.ctx.grid.cell_size;
        let water = self.ctx.model.water.as_ref();
        for p in 0..xg.len() {
            let xp = D::vec_to3(xg[p].0);
            // The point in the body's starting frame.
            let x0: [f64; 3] = std::array::from_fn(|a| xp[a] - self.offset[a]);
            let d2: f64 = (0..3).map(|a| (x0[a] - self.at[a]).powi(2)).sum();
            if d2 > r2 || self.body.distance(x0, D::N).2 != self.part {
                continue;
            }
            let hydrostatic = water.map_or(0.0, |w| w.pore_pressure(mg[p].0, xp));
            let excess = states.map_or(0.0, |s| s[p].excess_pore_pressure());
            self.sums[0] += vg[p].0 * (hydrostatic + excess);
            self.sums[1] += vg[p].0;
        }
    }
}

/// Each piezocone's ground (`cpt`), the step its push begins, before it has moved.
fn record_ground<D: Dim>(bodies: &[RigidBodySpec], ctx: &mut Context<D>) {
    for (k, spec) in bodies.iter().enumerate() {
        let b = &ctx.state.control.bodies[k];
        if let (Some(m), Some(_), None, 0.0) = (&spec.motion, &spec.cpt, &b.in_situ, b.travel) {
            if b.velocity != [0.0; 3] {
                let unit = m.vector().map(|c| c / m.speed());
                ctx.state.control.bodies[k].in_situ = Some(in_situ(ctx, unit));
            }
        }
    }
}

/// The ground as it stands now, in slices one cell thick across the direction `unit` (x y
/// z), from the first point's to the last's ([`InSitu`]); over MPI ranks every rank's
/// points, the slices' ends agreed first.
fn in_situ<D: Dim>(ctx: &Context<D>, unit: [f64; 3]) -> InSitu {
    let along = |x: D::Vec| -> f64 {
        let x = D::vec_to3(x);
        (0..3).map(|a| x[a] * unit[a]).sum()
    };
    // Both ends as largest values: the first point's as −s.
    let mut ends = [f64::NEG_INFINITY; 2];
    for arch in points_with::<Volume>(&ctx.world) {
        for x in col::<Position<D::Vec>>(arch).iter() {
            let s = along(x.0);
            ends = [ends[0].max(-s), ends[1].max(s)];
        }
    }
    ctx.comm.max(&mut ends);
    let h = ctx.grid.cell_size;
    if !(ends[0].is_finite() && ends[1].is_finite()) {
        return InSitu::new(h, 0.0, 0.0);
    }
    let mut slicer = Slicer::<D> {
        ctx,
        unit,
        ground: InSitu::new(h, (-ends[0] / h).floor() * h, ends[1]),
    };
    for arch in points_with::<Volume>(&ctx.world) {
        with_state_column(arch, &mut slicer);
    }
    let mut ground = slicer.ground;
    let mut flat: Vec<f64> = ground.slices.iter().flatten().copied().collect();
    ctx.comm.sum(&mut flat);
    for (slice, sums) in ground.slices.iter_mut().zip(flat.chunks_exact(5)) {
        slice.copy_from_slice(sums);
    }
    ground
}

/// The ground's slices, added to archetype by archetype.
struct Slicer<'a, D: Dim> {
    ctx: &'a Context<D>,
    unit: [f64; 3],
    ground: InSitu,
}

impl<D: Dim> WithStates for Slicer<'_, D> {
    /// Adds the archetype's points; `states` their state column, `None` for points
    /// without state.
    fn with<T: MaterialState>(&mut self, arch: &hecs::Archetype, states: Option<&[T]>) {
        let (xg, vg, mg, sg) = (
            col::<Position<D::Vec>>(arch),
            col::<Volume>(arch),
            col::<MaterialId>(arch),
            col::<Stress<D::Stress>>(arch),
        );
        let water = self.ctx.model.water.as_ref();
        let n = self.unit;
        for p in 0..xg.len() {
            let x = D::vec_to3(xg[p].0);
            let sigma = sg[p].0.to_sym3();
            // m̂ · σ · m̂ of the stress column (σ′ − u_excess I, tension positive).
            let normal = n[0] * n[0] * sigma.xx
                + n[1] * n[1] * sigma.yy
                + n[2] * n[2] * sigma.zz
                + 2.0 * (n[0] * n[1] * sigma.xy + n[1] * n[2] * sigma.yz + n[2] * n[0] * sigma.zx);
            let u = water.map_or(0.0, |w| w.pore_pressure(mg[p].0, x));
            let model = &self.ctx.materials[mg[p].0 as usize];
            let strength = match states {
                Some(s) => model.undrained_strength(&sigma, &s[p]),
                None => model.undrained_strength(&sigma, &()),
            };
            let s = (0..3).map(|a| x[a] * n[a]).sum();
            self.ground.add(s, vg[p].0, u - normal, u, strength);
        }
    }
}
