//! A simulation: the ECS world, grid, materials and solver state, stepped by a schedule.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Dim2, Dim3, DimAxi};
use crate::error::StepError;
use crate::infra::columns::{col, points_with};
use crate::materials::first_non_finite_state;
use crate::schedule::Schedule;
use crate::state::SolverState;
use crate::tensor::{StoredSym, Sym3};
use hecs::{Entity, World};

/// A point whose history is recorded.
#[derive(Clone, Debug)]
pub struct TracedPoint {
    /// Name given in the scene.
    pub name: String,
    /// The point.
    pub id: PointId,
    /// The entity whose row held the point when last looked up: the spatial sort moves
    /// point data between rows, so this is checked against `id` before use.
    pub entity: Entity,
    /// Position at the start (m).
    pub initial_position: [f64; 3],
}

impl TracedPoint {
    /// The entity that holds the point now.
    pub fn current_entity(&self, world: &World) -> Entity {
        self.find(world).expect("traced point exists")
    }

    /// The entity that holds the point now, `None` when this rank does not hold it (over
    /// MPI).
    pub fn find(&self, world: &World) -> Option<Entity> {
        match world.get::<&PointId>(self.entity) {
            Ok(id) if *id == self.id => Some(self.entity),
            _ => find_point(world, self.id),
        }
    }

    /// Displacement from the start (m, x y z): the point's accumulated displacement when the
    /// scene keeps them (`output.displacements`), else its position less its initial one.
    pub fn displacement<D: Dim>(&self, world: &World) -> [f64; 3] {
        let entity = self.current_entity(world);
        // The accumulated Σ Δt v is exact to the increments' precision; x − x₀ loses a
        // displacement far below the position's own rounding (a 1e-15 N load on a 5 m bar
        // moves its points by 1e-18 m a step, under half an ulp of 5 m: x never changes).
        if let Ok(u) = world.get::<&Displacement<D::Vec>>(entity) {
            return D::vec_to3(u.0);
        }
        let x = D::vec_to3(
            world
                .get::<&Position<D::Vec>>(entity)
                .expect("traced point exists")
                .0,
        );
        std::array::from_fn(|a| x[a] - self.initial_position[a])
    }
}

/// The entity holding point `id`, by a scan of the point ids.
pub fn find_point(world: &World, id: PointId) -> Option<Entity> {
    world
        .query::<(Entity, &PointId)>()
        .iter()
        .find(|(_, p)| **p == id)
        .map(|(e, _)| e)
}

/// What a traced point reports at the end of a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TracedResult {
    /// Name given in the scene.
    pub name: String,
    /// Position at the start (m).
    pub initial_position: [f64; 3],
    /// Displacement (m).
    pub displacement: [f64; 3],
    /// Cauchy stress (Pa, tension positive); zero for a load carrier.
    pub stress: Sym3,
}

/// A ready-to-run simulation of dimension `D`.
pub struct Simulation<D: Dim> {
    /// World, grid, materials and state.
    pub ctx: Context<D>,
    /// The systems of one step, in order.
    pub schedule: Schedule<D>,
    /// Points whose history is recorded.
    pub traced: Vec<TracedPoint>,
    /// Report the free-surface angle in the summary.
    pub measure_surface_angle: bool,
}

impl<D: Dim> Simulation<D> {
    /// Runs one explicit step.
    pub fn step(&mut self) -> Result<(), StepError> {
        let s = &mut self.ctx.state;
        s.clock.step += 1;
        // time = n·Δt rather than a running sum, so long runs do not drift.
        s.clock.time = s.clock.step as f64 * self.ctx.numerics.dt;
        s.resets.this_step = false;
        s.control.milestone = false;
        let result = self.schedule.run(&mut self.ctx);
        if self.ctx.state.points_reordered {
            for t in &mut self.traced {
                if let Some(e) = t.find(&self.ctx.world) {
                    t.entity = e;
                }
            }
        }
        result
    }

    /// Steps until a stop reason is set (convergence or a limit) or an error occurs.
    /// `observe` is called after every step.
    ///
    /// The loop runs on a thread of the current rayon pool (the global one unless called
    /// inside `ThreadPool::install`). Called from any other thread, every parallel loop of
    /// every step would hand its work over to the pool and put the caller to sleep until it
    /// is done: two thread wake-ups per loop (their cost is in docs/performance.md).
    pub fn run(&mut self, mut observe: impl FnMut(&SolverState) + Send) -> Result<(), StepError> {
        self.run_with(|sim| {
            observe(&sim.ctx.state);
            Ok(())
        })
    }

    /// As [`Simulation::run`], with `between` given the whole simulation after every step:
    /// it may write output, checkpoint, or end the run by setting `ctx.state.stop`.
    pub fn run_with(
        &mut self,
        mut between: impl FnMut(&mut Simulation<D>) -> Result<(), StepError> + Send,
    ) -> Result<(), StepError> {
        rayon::scope(|_| {
            self.ctx.state.stop = None;
            while self.ctx.state.stop.is_none() {
                self.step()?;
                between(self)?;
            }
            Ok(())
        })
    }

    /// The first non-finite value of the point state that output would write (position,
    /// velocity, displacement, stress, volume, plastic strain), as "stress of point 17".
    pub fn first_non_finite(&self) -> Option<String> {
        let w = &self.ctx.world;
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        for arch in points_with::<Position<D::Vec>>(w) {
            let id = col::<PointId>(arch);
            let bad = |what: &str, r: usize| Some(format!("{what} of point {}", id[r].0));
            if let Some(r) = col::<Position<D::Vec>>(arch)
                .iter()
                .position(|x| !finite(&D::vec_to3(x.0)))
            {
                return bad("position", r);
            }
            if let Some(r) = col::<Velocity<D::Vec>>(arch)
                .iter()
                .position(|v| !finite(&D::vec_to3(v.0)))
            {
                return bad("velocity", r);
            }
            if let Some(u) = arch.get::<&Displacement<D::Vec>>() {
                if let Some(r) = u.iter().position(|u| !finite(&D::vec_to3(u.0))) {
                    return bad("displacement", r);
                }
            }
            if let Some(s) = arch.get::<&Stress<D::Stress>>() {
                if let Some(r) = s.iter().position(|s| {
                    let s = s.0.to_sym3();
                    !finite(&[s.xx, s.yy, s.zz, s.xy, s.yz, s.zx])
                }) {
                    return bad("stress", r);
                }
            }
            if let Some(v) = arch.get::<&Volume>() {
                if let Some(r) = v.iter().position(|v| !v.0.is_finite()) {
                    return bad("volume", r);
                }
            }
            if let Some(r) = first_non_finite_state(arch) {
                return bad("material state", r);
            }
        }
        None
    }

    /// Number of material points (load carriers included).
    pub fn point_count(&self) -> usize {
        points_with::<Position<D::Vec>>(&self.ctx.world)
            .map(|a| a.len() as usize)
            .sum()
    }

    /// Total mass of the points (kg).
    pub fn total_mass(&self) -> f64 {
        // Exact, then rounded once: the same bits whatever the order of the points and the
        // number of ranks (over MPI a collective).
        let masses = points_with::<Mass>(&self.ctx.world)
            .flat_map(|a| col::<Mass>(a).iter().map(|m| m.0).collect::<Vec<_>>());
        self.ctx.comm.exact_sum(masses)
    }

    /// Current displacement and stress of every traced point. Over MPI a collective: each
    /// point's values come from the rank that holds it, and every rank gets them.
    pub fn traced_results(&self) -> Vec<TracedResult> {
        let mut traced = self.traced.clone();
        traced_values(&self.ctx, &mut traced)
            .into_iter()
            .zip(&self.traced)
            .map(|((displacement, stress), t)| TracedResult {
                name: t.name.clone(),
                initial_position: t.initial_position,
                displacement,
                stress,
            })
            .collect()
    }
}

/// Displacement (m) and stress (Pa; zero for a load carrier) of each of `traced`, whose
/// entities it finds again. Over MPI a collective: each point's values come from the rank
/// that holds it, and every rank gets them.
pub fn traced_values<D: Dim>(ctx: &Context<D>, traced: &mut [TracedPoint]) -> Vec<([f64; 3], Sym3)> {
    // Per point: displacement (3) and stress (6), zero on the ranks that lack it.
    let mut values = Vec::with_capacity(traced.len() * 9);
    for t in traced.iter_mut() {
        match t.find(&ctx.world) {
            Some(entity) => {
                t.entity = entity;
                let e = ctx.world.entity(entity).expect("found above");
                let s = e
                    .get::<&Stress<D::Stress>>()
                    .map(|s| s.0.to_sym3())
                    .unwrap_or_default();
                values.extend(t.displacement::<D>(&ctx.world));
                values.extend([s.xx, s.yy, s.zz, s.xy, s.yz, s.zx]);
            }
            None => values.extend([0.0; 9]),
        }
    }
    // One rank holds each point: the others add zeros, which leaves its value.
    ctx.comm.sum(&mut values);
    values
        .chunks(9)
        .map(|v| {
            let stress = Sym3 {
                xx: v[3],
                yy: v[4],
                zz: v[5],
                xy: v[6],
                yz: v[7],
                zx: v[8],
            };
            ([v[0], v[1], v[2]], stress)
        })
        .collect()
}

/// A simulation of either dimension, as built from a scene.
pub enum AnySimulation {
    /// Plane strain.
    Two(Simulation<Dim2>),
    /// Three dimensions.
    Three(Simulation<Dim3>),
    /// Axisymmetric, per radian.
    Axi(Simulation<DimAxi>),
}

/// Evaluates `$body` with `$sim` bound to the inner [`Simulation`] of an [`AnySimulation`].
#[macro_export]
macro_rules! with_simulation {
    ($any:expr, $sim:ident => $body:expr) => {
        match $any {
            $crate::AnySimulation::Two($sim) => $body,
            $crate::AnySimulation::Three($sim) => $body,
            $crate::AnySimulation::Axi($sim) => $body,
        }
    };
}
