//! Point snapshots during a run: a ParaView time series (`points.pvd` and one `.vtu` a
//! snapshot under `snapshots/`), written by a thread of its own so that stepping does not
//! wait on the disk.

use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::output::bodies::write_bodies;
use crate::output::dir::write_atomic;
use crate::output::vtk::{write_frame, write_parallel_frame, Frame};
use crate::schedule::System;
use crossbeam::channel::{bounded, Receiver, Sender};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

/// When snapshots are taken (`output.snapshots`); any combination, and always at the last
/// step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SnapshotSpec {
    /// Every this many steps (≥ 1).
    #[serde(default)]
    pub every_steps: Option<u64>,
    /// Every this much simulated time (s, > 0).
    #[serde(default)]
    pub every_time: Option<f64>,
    /// At each kinetic-damping reset (the static states the paper's figures show).
    #[serde(default)]
    pub at_resets: bool,
}

/// The collection file ParaView opens.
pub const PVD: &str = "points.pvd";
/// The folder of the snapshot files.
pub const FOLDER: &str = "snapshots";
/// How the rigid bodies' files in it begin (`bodies_<step>.vtu`).
pub const BODIES: &str = "bodies_";
/// Frames in flight between the step loop and the writer: a third waits (back-pressure)
/// rather than holding more copies of the points in memory.
const IN_FLIGHT: usize = 2;

/// What the writer thread reports when it is done.
#[derive(Clone, Debug, Default)]
pub struct SnapshotReport {
    /// Snapshots in the series (`points.pvd`), a resumed run's earlier ones included.
    pub written: usize,
    /// Wall-clock seconds stepping waited for the writer (s).
    pub wait_seconds: f64,
}

/// The step-loop side: a system that copies the points when a snapshot is due and hands
/// the copy to the writer thread.
pub struct Snapshots<D> {
    spec: SnapshotSpec,
    sender: Arc<Mutex<Option<Sender<Frame>>>>,
    /// Frames the writer is done with, to be filled again.
    written: Receiver<Frame>,
    wait: Arc<Mutex<f64>>,
    _marker: PhantomData<fn() -> D>,
}

/// The writer side: join it with [`SnapshotWriter::finish`] after the run.
pub struct SnapshotWriter {
    thread: Option<JoinHandle<std::io::Result<usize>>>,
    sender: Arc<Mutex<Option<Sender<Frame>>>>,
    wait: Arc<Mutex<f64>>,
}

/// A collection entry: simulated time and the file, relative to the output directory.
type Entry = (f64, String);

impl<D: Dim> Snapshots<D> {
    /// Starts the writer thread for output directory `dir`. `resume_time` (s) keeps the
    /// entries of an earlier run's `points.pvd` up to that time (a resumed run).
    ///
    /// Over MPI (`rank` of `ranks`) every rank writes its own points of each snapshot,
    /// `points_<step>_<rank>.vtu`; rank 0 also writes `points_<step>.pvtu`, which ties them
    /// together, the bodies and the collection, which lists the `.pvtu`. Rank 0 clears an
    /// earlier series before the first step; no rank writes a snapshot before every rank
    /// has begun stepping (a step's sums wait for all).
    pub fn start(
        dir: &Path,
        spec: SnapshotSpec,
        resume_time: Option<f64>,
        (rank, ranks): (usize, usize),
    ) -> std::io::Result<(Self, SnapshotWriter)> {
        let folder = dir.join(FOLDER);
        if resume_time.is_none() && rank == 0 {
            clear(dir)?;
        }
        std::fs::create_dir_all(&folder)?;
        let mut entries: Vec<Entry> = match resume_time {
            Some(t) => read_pvd(&dir.join(PVD))
                .into_iter()
                .filter(|e| e.0 <= t * (1.0 + 1e-12))
                .collect(),
            None => Vec::new(),
        };
        let (tx, rx) = bounded::<Frame>(IN_FLIGHT);
        let (back, written) = bounded::<Frame>(IN_FLIGHT + 1);
        let dir = dir.to_path_buf();
        let thread = std::thread::Builder::new().name("snapshots".into()).spawn(
            move || -> std::io::Result<usize> {
                lower_priority();
                let mut sorted = Frame::default();
                for mut frame in rx {
                    let bodies = std::mem::take(&mut frame.bodies);
                    frame.sort_into(&mut sorted);
                    // Hand the buffers back for the next snapshot; never blocks (a full
                    // return channel drops them).
                    let _ = back.try_send(frame);
                    let name = if ranks == 1 {
                        format!("{FOLDER}/points_{:09}.vtu", sorted.step)
                    } else {
                        let piece = |r: usize| format!("points_{:09}_{r}.vtu", sorted.step);
                        write_frame(&sorted, &dir.join(FOLDER).join(piece(rank)))?;
                        if rank > 0 {
                            continue;
                        }
                        let name = format!("{FOLDER}/points_{:09}.pvtu", sorted.step);
                        let pieces: Vec<String> = (0..ranks).map(piece).collect();
                        write_parallel_frame(&sorted, &dir.join(&name), &pieces)?;
                        name
                    };
                    if ranks == 1 {
                        write_frame(&sorted, &dir.join(&name))?;
                    }
                    entries.push((sorted.time, name));
                    if !bodies.is_empty() {
                        let name = format!("{FOLDER}/{BODIES}{:09}.vtu", sorted.step);
                        write_bodies(&dir.join(&name), &bodies)?;
                        entries.push((sorted.time, name));
                    }
                    write_pvd(&dir.join(PVD), &entries)?;
                }
                Ok(entries.len())
            },
        )?;
        let wait = Arc::new(Mutex::new(0.0));
        let sender = Arc::new(Mutex::new(Some(tx)));
        Ok((
            Snapshots {
                spec,
                sender: sender.clone(),
                written,
                wait: wait.clone(),
                _marker: PhantomData,
            },
            SnapshotWriter {
                thread: Some(thread),
                sender,
                wait,
            },
        ))
    }

    fn due(&self, ctx: &Context<D>) -> bool {
        let st = &ctx.state;
        let by_steps = self
            .spec
            .every_steps
            .is_some_and(|n| st.clock.step.is_multiple_of(n));
        // A snapshot in each step that crosses a multiple of T: decided from this step
        // alone, so a resumed run takes the snapshots the uninterrupted one takes.
        let by_time = self
            .spec
            .every_time
            .is_some_and(|t| (st.clock.time / t).floor() > ((st.clock.time - ctx.numerics.dt) / t).floor());
        // Every static state a control system consumed (an increment, a stage) too.
        by_steps
            || by_time
            || (self.spec.at_resets && st.resets.this_step)
            || st.control.milestone
            || st.stop.is_some()
    }
}

impl<D: Dim> System<D> for Snapshots<D> {
    fn name(&self) -> &str {
        "snapshots"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if !self.due(ctx) {
            return Ok(());
        }
        let mut sender = lock(&self.sender);
        let Some(tx) = sender.as_ref() else { return Ok(()) };
        let mut frame = self.written.try_recv().unwrap_or_default();
        frame.refill::<D>(
            &ctx.world,
            ctx.state.clock.step,
            ctx.state.clock.time,
            ctx.model.water.clone(),
        );
        let spacing = 0.5 * ctx.grid.cell_size;
        let grid = (D::vec_to3(ctx.grid.origin), D::vec_to3(ctx.grid.max_corner()));
        frame.bodies = (0u32..)
            .zip(ctx.model.bodies.iter().zip(&ctx.state.control.bodies))
            .flat_map(|(k, (body, state))| body.spec.outlines(k, state.offset, spacing, grid))
            .collect();
        let start = Instant::now();
        if tx.send(frame).is_err() {
            // The writer stopped on an error; finish() reports it. Stepping goes on.
            *sender = None;
        }
        *lock(&self.wait) += start.elapsed().as_secs_f64();
        Ok(())
    }
}

impl SnapshotWriter {
    /// Closes the channel, waits for every snapshot in it to be written and reports what
    /// was written and how long stepping waited. Snapshots due after this are not taken.
    pub fn finish(mut self) -> std::io::Result<SnapshotReport> {
        lock(&self.sender).take();
        let written = match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r?,
            Some(Err(_)) => return Err(std::io::Error::other("the snapshot writer thread panicked")),
            None => 0,
        };
        let wait_seconds = *lock(&self.wait);
        Ok(SnapshotReport {
            written,
            wait_seconds,
        })
    }
}

/// Gives the calling thread the lowest scheduling priority (nice 19), so that writing
/// snapshots takes a core mostly when the stepping threads leave it idle; back-pressure
/// (two frames in flight) keeps the writer from falling behind without bound.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority reads and writes no memory of ours; on Linux, PRIO_PROCESS with
    // who = 0 names the calling thread only. A failure leaves the priority as it was, which
    // is harmless, so the result is ignored.
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 19);
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Writes the collection: every snapshot with its simulated time (s).
fn write_pvd(path: &Path, entries: &[Entry]) -> std::io::Result<()> {
    write_atomic(path, |out| {
        out.write_all(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n")?;
        for (t, file) in entries {
            // The points are part 0, the rigid bodies part 1. Shortest decimal that reads
            // back to the same f64.
            let part = u8::from(of_bodies(file));
            writeln!(
                out,
                "<DataSet timestep=\"{t:?}\" part=\"{part}\" file=\"{file}\"/>"
            )?;
        }
        out.write_all(b"</Collection>\n</VTKFile>\n")
    })
}

/// True for a collection entry's file (relative to the output directory) that draws the
/// rigid bodies rather than the points.
fn of_bodies(file: &str) -> bool {
    file.strip_prefix(FOLDER)
        .and_then(|f| f.strip_prefix('/'))
        .is_some_and(|f| f.starts_with(BODIES))
}

/// The entries of a collection this module wrote (empty when there is none).
fn read_pvd(path: &Path) -> Vec<Entry> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Vec::new();
    };
    let attr = |line: &str, name: &str| -> Option<String> {
        let start = line.find(&format!("{name}=\""))? + name.len() + 2;
        let end = start + line[start..].find('"')?;
        Some(line[start..end].to_string())
    };
    text.lines()
        .filter(|l| l.trim_start().starts_with("<DataSet"))
        .filter_map(|l| Some((attr(l, "timestep")?.parse().ok()?, attr(l, "file")?)))
        .collect()
}

/// The point snapshot files of a collection, for readers: (time, path) in time order.
pub fn collection(dir: &Path) -> Vec<(f64, PathBuf)> {
    read_pvd(&dir.join(PVD))
        .into_iter()
        .filter(|(_, f)| !of_bodies(f))
        .map(|(t, f)| (t, dir.join(f)))
        .collect()
}

/// Removes an earlier run's series from output directory `dir`: its `points.pvd` and the
/// snapshots (points and bodies) in its folder (a new run's series is its own).
pub(crate) fn clear(dir: &Path) -> std::io::Result<()> {
    let folder = dir.join(FOLDER);
    if let Ok(entries) = std::fs::read_dir(&folder) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            // Over MPI, each rank's pieces and the `.pvtu` that ties them.
            let vtk = name.ends_with(".vtu") || name.ends_with(".pvtu");
            if (name.starts_with("points_") || name.starts_with(BODIES)) && vtk {
                std::fs::remove_file(e.path())?;
            }
        }
    }
    crate::output::dir::remove_if_there(&dir.join(PVD))
}
