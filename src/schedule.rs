//! The ordered list of named systems that makes one explicit step, with per-system timings.
//!
//! Reading a default schedule (see [`crate::systems::default_schedule`]) gives the whole
//! algorithm in order; every name leads to one file under `src/systems/`.

use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::traffic::Traffic;
use std::time::{Duration, Instant};

/// One stage of the explicit step.
///
/// A system that moves a point into another cell, or adds, removes or reorders points, calls
/// `ctx.slabs.invalidate()`, so that the next scatter groups them anew (see
/// [`crate::SlabCache`]; [`crate::grid::Grid::landing`] tells a cell change).
pub trait System<D: Dim>: Send {
    /// Stable name, used in schedules, profiles and error messages.
    fn name(&self) -> &str;
    /// Runs the stage once.
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError>;
    /// Prepares the world before the first step this schedule runs (marks nodes, sets up
    /// state): called again when the schedule changes and after a resume, so it must give
    /// the same result when repeated. Nothing by default.
    fn prepare(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let _ = ctx;
        Ok(())
    }
    /// Told the names of the schedule's systems, in order, before the first step it runs
    /// and whenever the list changes (before `prepare`): a system whose work depends on its
    /// neighbours decides it here (g2p gathers the sums of the system that moves the points
    /// where only the peak watch runs between them; the stress update updates the volumes
    /// where no `volume_update` does). Nothing by default.
    fn schedule_changed(&mut self, names: &[String]) {
        let _ = names;
    }
    /// Whether every rank of a run over MPI runs this system (the engine's systems do):
    /// its failure on one rank then stops every rank at it. A system that only some ranks
    /// run (rank 0's history writer) says false: its failure stops every rank at the next
    /// system they all run, or at the end of the step.
    fn on_every_rank(&self) -> bool {
        true
    }
    /// The bytes of point and node columns that the call which just ran read and wrote
    /// ([`Traffic`]), for the profile's byte budget; `None` (the default) where the system
    /// does not count them. Called after every call, so it must be cheap: counts from the
    /// columns' lengths and the box of nodes, not a pass over them.
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let _ = ctx;
        None
    }
}

/// A system made from a closure, for user code (see `examples/custom_system.rs`).
pub struct FnSystem<F> {
    name: String,
    f: F,
}

impl<F> FnSystem<F> {
    /// A system called `name` that runs `f`.
    pub fn new(name: impl Into<String>, f: F) -> Self {
        FnSystem { name: name.into(), f }
    }
}

impl<D: Dim, F> System<D> for FnSystem<F>
where
    F: FnMut(&mut Context<D>) -> Result<(), StepError> + Send,
{
    fn name(&self) -> &str {
        &self.name
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        (self.f)(ctx)
    }
}

/// Accumulated cost of one system.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timing {
    /// System name.
    pub name: String,
    /// Number of calls.
    pub calls: u64,
    /// Total wall time (s).
    pub seconds: f64,
    /// Bytes of point and node columns read and written over all calls, where the system
    /// counts them ([`System::traffic`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes: Option<Traffic>,
}

/// An ordered list of systems.
pub struct Schedule<D: Dim> {
    systems: Vec<Box<dyn System<D>>>,
    time: Vec<Duration>,
    calls: Vec<u64>,
    /// Bytes moved by each system so far; `None` once a call did not count them.
    bytes: Vec<Option<Traffic>>,
    /// Every system's `prepare` ran since the list last changed.
    prepared: bool,
}

impl<D: Dim> Default for Schedule<D> {
    fn default() -> Self {
        Schedule {
            systems: Vec::new(),
            time: Vec::new(),
            calls: Vec::new(),
            bytes: Vec::new(),
            prepared: false,
        }
    }
}

impl<D: Dim> Schedule<D> {
    /// An empty schedule.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a system.
    pub fn push(&mut self, system: impl System<D> + 'static) -> &mut Self {
        self.push_boxed(Box::new(system))
    }

    /// Appends a boxed system.
    pub fn push_boxed(&mut self, system: Box<dyn System<D>>) -> &mut Self {
        self.systems.push(system);
        self.prepared = false;
        self.time.push(Duration::ZERO);
        self.calls.push(0);
        self.bytes.push(Some(Traffic::NONE));
        self
    }

    /// Inserts a system right after the one called `after`. Returns false if there is none.
    pub fn insert_after(&mut self, after: &str, system: impl System<D> + 'static) -> bool {
        match self.position(after) {
            Some(i) => {
                self.systems.insert(i + 1, Box::new(system));
                self.prepared = false;
                self.time.insert(i + 1, Duration::ZERO);
                self.calls.insert(i + 1, 0);
                self.bytes.insert(i + 1, Some(Traffic::NONE));
                true
            }
            None => false,
        }
    }

    /// Inserts a system right before the one called `before`. Returns false if there is none.
    pub fn insert_before(&mut self, before: &str, system: impl System<D> + 'static) -> bool {
        match self.position(before) {
            Some(i) => {
                self.systems.insert(i, Box::new(system));
                self.prepared = false;
                self.time.insert(i, Duration::ZERO);
                self.calls.insert(i, 0);
                self.bytes.insert(i, Some(Traffic::NONE));
                true
            }
            None => false,
        }
    }

    /// Index of the first system called `name`.
    pub fn position(&self, name: &str) -> Option<usize> {
        self.systems.iter().position(|s| s.name() == name)
    }

    /// Names in order.
    pub fn names(&self) -> Vec<String> {
        self.systems.iter().map(|s| s.name().to_string()).collect()
    }

    /// Runs every system once, in order, timing each (after their `prepare`, the first
    /// time).
    pub fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // A failure of a system that not every rank runs, held for the next check.
        let mut held = None;
        if !self.prepared {
            let names = self.names();
            for system in &mut self.systems {
                system.schedule_changed(&names);
            }
            for system in &mut self.systems {
                let result = system.prepare(ctx);
                every_rank(ctx, system.on_every_rank(), result, &mut held)?;
            }
            self.prepared = true;
        }
        for (i, system) in self.systems.iter_mut().enumerate() {
            #[cfg(feature = "trace")]
            let _span = tracing::info_span!("system", name = system.name()).entered();
            let start = Instant::now();
            let result = system.run(ctx);
            self.time[i] += start.elapsed();
            self.calls[i] += 1;
            if result.is_ok() {
                self.bytes[i] = self.bytes[i].zip(system.traffic(ctx)).map(|(mut a, t)| {
                    a += t;
                    a
                });
            }
            every_rank(ctx, system.on_every_rank(), result, &mut held)?;
        }
        every_rank(ctx, true, Ok(()), &mut held)
    }

    /// Accumulated cost of every system, in schedule order.
    pub fn timings(&self) -> Vec<Timing> {
        self.systems
            .iter()
            .zip(self.time.iter().zip(&self.calls).zip(&self.bytes))
            .map(|(s, ((t, &calls), &bytes))| Timing {
                name: s.name().to_string(),
                calls,
                seconds: t.as_secs_f64(),
                bytes,
            })
            .collect()
    }
}

/// A system's outcome made every rank's: over MPI ranks a system that fails on one rank (a
/// point of its layers left the grid or turned non-finite) stops every rank at the same
/// system, the others with the lowest failing rank's message ([`StepError::OnRank`]);
/// otherwise the ranks still stepping would wait for it in the next collective for ever.
/// The failure of a system that not every rank runs (`shared` false) is `held` until the
/// next system they all run, or the end of the step. One small collective a shared system
/// a step; nothing on one rank.
fn every_rank<D: Dim>(
    ctx: &Context<D>,
    shared: bool,
    result: Result<(), StepError>,
    held: &mut Option<StepError>,
) -> Result<(), StepError> {
    if ctx.comm.size() == 1 {
        return result;
    }
    if let Err(e) = result {
        held.get_or_insert(e);
    }
    if !shared {
        return Ok(());
    }
    let mine = held.as_ref().map(|e| e.to_string());
    match (held.take(), ctx.comm.first_message(mine.as_deref())) {
        (Some(e), _) => Err(e),
        (None, Some((rank, message))) => Err(StepError::OnRank { rank, message }),
        (None, None) => Ok(()),
    }
}
