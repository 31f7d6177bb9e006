//! Checkpoints: the whole state of a run between two steps, to resume it bit for bit.
//!
//! A step's outcome depends on the solver state ([`SolverState`], which also holds the
//! static-check window) and on the point columns, row by row: the scatters add points in
//! row order. Everything else is rebuilt from the scene: node columns are zero between
//! steps once the next grid reset has run, and the slab grouping of the scatters is a
//! function of the positions. So a checkpoint holds the scene's text, the solver state and
//! every point column of every archetype in row order; resuming builds the scene again
//! (which spawns the same archetypes with the same row counts) and overwrites them.
//!
//! The file is binary, little-endian, written for the machine that reads it back: numbers
//! are stored as their bits, so nothing is rounded on the way. It is refused, with the
//! reason, unless it is whole and unchanged (a CRC-32 of every byte ends it), was written
//! by this build of kdmpm (a fingerprint of its sources), carries the scene its hash says,
//! continues the `history.csv` beside it (a CRC-32 of the rows it had written), and holds
//! only ids within range: a damaged or foreign checkpoint is never resumed.
//!
//! A run over MPI ranks writes one such file per rank, of that rank's points, and a
//! manifest written last that ties them together ([`parts`]).

pub mod parts;

use crate::components::*;
use crate::dim::Dim;
use crate::grid::NodeBox;
use crate::infra::columns::{fill, points_with};
use crate::infra::decomposition::Decomposition;
use crate::model::{Control, CurvePoint, Drive, StageResult};
use crate::parallel::SlabCache;
use crate::rigid::BodyState;
use crate::simulation::Simulation;
use crate::state::{Clock, Convergence, EnergyWindow, Peak, RankCounters, Resets, SolverState, StaticWindow};
use hecs::{Archetype, ColumnBatchType, Entity};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The first bytes of a checkpoint file.
const MAGIC: &[u8; 8] = b"KDMPMCK\0";
/// Format version; a file of another version is refused.
const VERSION: u32 = 15;
/// The build that writes and reads checkpoints: the crate's version and a fingerprint of
/// its sources (build.rs).
pub const BUILD_ID: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("KDMPM_SOURCE_HASH"));
/// The file's name in an output directory.
pub const FILE_NAME: &str = "checkpoint.kdc";

/// A checkpoint that cannot be read or does not fit its scene.
#[derive(Debug, Error)]
pub enum CheckpointError {
    /// The file could not be read or written.
    #[error("checkpoint {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is not a whole, unchanged checkpoint of this build, or does not fit its
    /// scene.
    #[error("checkpoint {path}: {reason}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// What a checkpoint holds besides the simulation's state.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Header {
    /// The scene file the run was started from (for messages).
    pub scene_path: PathBuf,
    /// The scene's text, overrides applied.
    pub scene_text: String,
    /// Bytes of `history.csv` written up to this step.
    pub history_bytes: u64,
    /// CRC-32 of those bytes: the history a resumed run continues must be this one.
    pub history_crc: u32,
    /// Wall time of the stepping loop so far (s).
    pub wall_seconds: f64,
    /// CRC-32 of the STL meshes the scene read ([`crate::scene::LoadedScene::mesh_crc`]):
    /// a file replaced or moved before a resume would change the body under the run.
    pub meshes_crc: u32,
}

/// Serialises the header, the solver state and every point column of `sim`.
pub fn encode<D: Dim>(sim: &Simulation<D>, header: &Header) -> Vec<u8> {
    let mut w = Writer(Vec::new());
    w.header(MAGIC, D::N as u64, header);
    encode_state(&mut w, &sim.ctx.state);
    encode_ranks(&mut w, &sim.ctx.decomposition, &sim.ctx.state.ranks);
    let archs: Vec<&Archetype> = points_with::<Position<D::Vec>>(&sim.ctx.world).collect();
    w.u64(archs.len() as u64);
    for arch in archs {
        w.u64(arch.len() as u64);
        // The archetype's columns by name: a column is found again by its type, so the
        // list of point components (and of the materials' states) may grow.
        macro_rules! count {
            ($($t:ty),*) => { 0 $(+ arch.has::<$t>() as u64)* };
        }
        w.u64(point_components!(D, count));
        macro_rules! save {
            ($($t:ty),*) => {$(
                if let Some(c) = arch.get::<&$t>() {
                    w.str(std::any::type_name::<$t>());
                    // SAFETY: every point component is a plain struct of f64, u32 or u16
                    // fields without padding (`point_components_have_no_padding`, and the
                    // `Pod` bound of a material's state), so each of its bytes is initialised.
                    let bytes = unsafe { as_bytes(&c) };
                    w.u64(bytes.len() as u64);
                    w.0.extend_from_slice(bytes);
                }
            )*};
        }
        point_components!(D, save);
    }
    w.finish()
}

/// Reads the header of checkpoint bytes (the scene to build before [`restore`]).
pub fn header(bytes: &[u8], path: &Path) -> Result<Header, CheckpointError> {
    let mut r = Reader::new(bytes, path);
    r.header(MAGIC)
}

/// Puts the state saved in `bytes` into `sim`, freshly built from the checkpoint's scene.
pub fn restore<D: Dim>(
    sim: &mut Simulation<D>,
    bytes: &[u8],
    path: &Path,
) -> Result<Header, CheckpointError> {
    let total = sim.point_count();
    restore_part(sim, bytes, path, total)
}

/// Puts one rank's part of a run over ranks ([`parts`]), or the whole state of a run on
/// one rank, into `sim`: built from the checkpoint's scene and, over ranks, split by
/// [`crate::run::distribute::join`]. `total` is the scene's point count over every
/// rank. Over ranks the rank's points are spawned again as saved (a rank holds the points
/// that migrated to it, not those of the first split), with the cell layers each rank held.
pub fn restore_part<D: Dim>(
    sim: &mut Simulation<D>,
    bytes: &[u8],
    path: &Path,
    total: usize,
) -> Result<Header, CheckpointError> {
    let mut r = Reader::new(bytes, path);
    let header = r.header(MAGIC)?;
    if r.dimension != D::N as u64 {
        return Err(r.fault(format!("saved in {}D, the scene is {}D", r.dimension, D::N)));
    }
    let mut state = decode_state(&mut r)?;
    let (ranks, rank, [bounds, across]) = decode_ranks(&mut r, &mut state.ranks)?;
    let (size, here) = (sim.ctx.comm.size(), sim.ctx.comm.rank());
    if (ranks, rank) != (size, here) {
        return Err(r.fault(format!(
            "rank {rank} of a run over {ranks} ranks, read by rank {here} of {size}: resume a \
             run with the rank count it was started with"
        )));
    }
    let grid = &sim.ctx.grid;
    let layers = [grid.slab_axis, grid.across_axis()].map(|a| grid.axes[a].cells);
    let fits = |cuts: &[usize], layers: usize| {
        cuts.len() >= 2
            && cuts[0] == 0
            && cuts[cuts.len() - 1] == layers
            && cuts.windows(2).all(|b| b[0] <= b[1])
    };
    if !fits(&bounds, layers[0])
        || !fits(&across, layers[1])
        || (bounds.len() - 1) * (across.len() - 1) != ranks
    {
        return Err(r.fault(format!(
            "the saved split ({} × {} parts over {} × {} cell layers) differs from the scene's \
             grid ({} × {} cell layers along its split axes) over {ranks} rank(s): a checkpoint \
             of another scene",
            bounds.len().saturating_sub(1),
            across.len().saturating_sub(1),
            bounds.last().copied().unwrap_or_default(),
            across.last().copied().unwrap_or_default(),
            layers[0],
            layers[1]
        )));
    }
    if ranks > 1 {
        respawn(sim, &mut r)?;
    } else {
        overwrite(sim, &mut r)?;
    }
    if r.at != r.bytes.len() {
        return Err(r.fault("bytes left after the last column".into()));
    }
    check_ids(sim, &state, total).map_err(|reason| r.fault(reason))?;
    state.ranks.first_step = state.clock.step;
    sim.ctx.state = state;
    sim.ctx.set_decomposition(Decomposition {
        bounds,
        across,
        ..sim.ctx.decomposition.clone()
    });
    // Nodes are zero and no box is active right after building, as after a grid reset.
    sim.ctx.state.active_nodes = NodeBox::default();
    sim.ctx.slabs = SlabCache::default();
    for t in &mut sim.traced {
        // Over ranks a traced point is on one rank only (the others gather it each step).
        if let Some(e) = t.find(&sim.ctx.world) {
            t.entity = e;
        } else if ranks == 1 {
            t.entity = t.current_entity(&sim.ctx.world);
        }
    }
    Ok(header)
}

/// The saved columns of one archetype: the row count and each column's type name and bytes.
type SavedArchetype<'a> = (u64, Vec<(String, &'a [u8])>);

/// Reads one archetype's columns.
fn saved_archetype<'a>(r: &mut Reader<'a>) -> Result<SavedArchetype<'a>, CheckpointError> {
    let rows = r.u64()?;
    let columns = r.u64()?;
    let mut saved = Vec::new();
    for _ in 0..columns {
        let name = r.str()?;
        let n = r.u64()? as usize;
        saved.push((name, r.take(n)?));
    }
    Ok((rows, saved))
}

/// Overwrites the point columns of `sim`, built from the scene with the saved row counts
/// (a run on one rank).
fn overwrite<D: Dim>(sim: &mut Simulation<D>, r: &mut Reader) -> Result<(), CheckpointError> {
    let archs: Vec<&Archetype> = points_with::<Position<D::Vec>>(&sim.ctx.world).collect();
    if r.u64()? != archs.len() as u64 {
        return Err(r.fault("the scene's point archetypes differ from the saved ones".into()));
    }
    for arch in archs {
        let (rows, mut saved) = saved_archetype(r)?;
        if rows != arch.len() as u64 {
            return Err(r.fault("a point archetype's row count differs from the saved one".into()));
        }
        macro_rules! load {
            ($($t:ty),*) => {$(
                if let Some(mut c) = arch.get::<&mut $t>() {
                    let name = std::any::type_name::<$t>();
                    let at = saved
                        .iter()
                        .position(|(s, _)| s == name)
                        .ok_or_else(|| r.fault(format!("column {name} is not saved")))?;
                    let (_, src) = saved.swap_remove(at);
                    if src.len() != std::mem::size_of_val(&*c) {
                        return Err(r.fault(format!("column {name} has another length")));
                    }
                    // SAFETY: `c` is exactly `src.len()` bytes long (checked above) and its
                    // type is a plain struct of f64, u32 or u16 fields without padding, for
                    // which every bit pattern is a valid value; `src` is a distinct allocation.
                    unsafe {
                        std::ptr::copy_nonoverlapping(src.as_ptr(), c.as_mut_ptr().cast::<u8>(), src.len())
                    };
                }
            )*};
        }
        point_components!(D, load);
        if let Some((name, _)) = saved.first() {
            return Err(r.fault(format!("column {name} is saved but the scene's points lack it")));
        }
    }
    Ok(())
}

/// Replaces this rank's points by the saved ones, archetype by archetype and row by row in
/// the saved order (a run over ranks: its points are those that migrated to it). The
/// archetypes the set-up made exist already and the saved ones come in the world's order
/// (set-up's, then those points brought by migrating), so each saved one is appended to
/// the same archetype, in the same order, as in the run that wrote it: one column batch a
/// saved archetype, filled column by column as the set-up fills its own.
fn respawn<D: Dim>(sim: &mut Simulation<D>, r: &mut Reader) -> Result<(), CheckpointError> {
    let world = &mut sim.ctx.world;
    let held: Vec<Entity> = world
        .query::<(Entity, &Position<D::Vec>)>()
        .iter()
        .map(|(e, _)| e)
        .collect();
    for e in held {
        world.despawn(e).expect("a point found above");
    }
    for _ in 0..r.u64()? {
        let (rows, saved) = saved_archetype(r)?;
        // The positions' column bounds the row count by the file's length.
        let position = std::any::type_name::<Position<D::Vec>>();
        let per_row = std::mem::size_of::<Position<D::Vec>>() as u64;
        match saved.iter().find(|(s, _)| s == position) {
            Some((_, src)) if src.len() as u64 == rows * per_row => {}
            _ => return Err(r.fault("a saved archetype's positions do not fit its row count".into())),
        }
        let rows = u32::try_from(rows).map_err(|_| r.fault("a row count out of range".into()))?;
        // The batch's columns: each saved one by its type (once, should a type be listed twice).
        let mut types = ColumnBatchType::new();
        let mut found = vec![false; saved.len()];
        macro_rules! add {
            ($($t:ty),*) => {$(
                let name = std::any::type_name::<$t>();
                if let Some(at) = saved.iter().position(|(s, _)| s == name).filter(|&at| !found[at]) {
                    if saved[at].1.len() != std::mem::size_of::<$t>() * rows as usize {
                        return Err(r.fault(format!("column {name} has another length")));
                    }
                    found[at] = true;
                    types.add::<$t>();
                }
            )*};
        }
        point_components!(D, add);
        if let Some(at) = found.iter().position(|f| !f) {
            return Err(r.fault(format!("column {} is saved but no point has it", saved[at].0)));
        }
        let batch = types.into_batch(rows);
        let mut filled = vec![false; saved.len()];
        macro_rules! fill_saved {
            ($($t:ty),*) => {$(
                let name = std::any::type_name::<$t>();
                if let Some(at) = saved.iter().position(|(s, _)| s == name).filter(|&at| !filled[at]) {
                    filled[at] = true;
                    let (n, src) = (std::mem::size_of::<$t>(), saved[at].1);
                    // SAFETY: `src` holds `rows` values of this type (its length checked
                    // above), written by `encode` from a column of it: a plain struct of
                    // f64, u32 or u16 fields for which every bit pattern it was written with
                    // is valid, the file's checksum whole; the read is unaligned-safe.
                    fill(&batch, src.chunks_exact(n).map(|b| unsafe { std::ptr::read_unaligned(b.as_ptr().cast::<$t>()) }));
                }
            )*};
        }
        point_components!(D, fill_saved);
        let batch = batch
            .build()
            .map_err(|_| r.fault("a saved archetype's columns are incomplete".into()))?;
        world.spawn_column_batch(batch);
    }
    Ok(())
}

/// The ids and counts the restored columns and state hold are within the scene's ranges:
/// material ids name one of its materials, point ids are distinct and below the point
/// count, the motions, stages and loads under control are the scene's. Whole files of
/// this build never fail this; it guards what the checksum cannot (a file of another
/// scene made to fit).
fn check_ids<D: Dim>(sim: &Simulation<D>, state: &SolverState, count: usize) -> Result<(), String> {
    let world = &sim.ctx.world;
    let materials = sim.ctx.materials.len();
    for arch in points_with::<MaterialId>(world) {
        if let Some(m) = crate::infra::columns::col::<MaterialId>(arch)
            .iter()
            .find(|m| m.0 as usize >= materials)
        {
            return Err(format!(
                "a point has material id {}, but the scene has {materials} materials",
                m.0
            ));
        }
    }
    let mut seen = vec![false; count];
    for arch in points_with::<PointId>(world) {
        for id in crate::infra::columns::col::<PointId>(arch).iter() {
            match seen.get_mut(id.0 as usize) {
                None => {
                    return Err(format!(
                        "a point has id {}, but the scene has {count} points",
                        id.0
                    ))
                }
                Some(true) => return Err(format!("two points have id {}", id.0)),
                Some(s) => *s = true,
            }
        }
    }
    let model = &sim.ctx.model;
    if state.control.drives.len() != model.motions.len() {
        return Err(format!(
            "{} motions saved, the scene has {}",
            state.control.drives.len(),
            model.motions.len()
        ));
    }
    if state.control.bodies.len() != model.bodies.len() {
        return Err(format!(
            "{} rigid bodies saved, the scene has {}",
            state.control.bodies.len(),
            model.bodies.len()
        ));
    }
    if state.control.stage >= model.stages.len().max(1) || state.control.stages.len() > model.stages.len() {
        return Err(format!(
            "stage {} saved, the scene has {} stages",
            state.control.stage,
            model.stages.len()
        ));
    }
    if state.control.load_increments.len() > model.load_steps.len()
        || state
            .control
            .load_increments
            .iter()
            .zip(&model.load_steps)
            .any(|(&k, l)| k > l.increments)
    {
        return Err("the loads' increments saved do not fit the scene's loads".into());
    }
    if !state.clock.time.is_finite() {
        return Err("the saved time is not a finite number".into());
    }
    Ok(())
}

/// The bytes of a column.
///
/// # Safety
/// `T` must have no padding bytes (every byte of a value initialised).
unsafe fn as_bytes<T: Copy>(column: &[T]) -> &[u8] {
    // SAFETY: the caller guarantees every byte is initialised; the length is the slice's.
    unsafe { std::slice::from_raw_parts(column.as_ptr().cast::<u8>(), std::mem::size_of_val(column)) }
}

/// The solver state, part by part. What is not saved is said here: the stop (a checkpoint
/// is taken between steps of a run that goes on), the MPI counters (checkpoints are of one
/// rank) and the per-step node box (rebuilt by the next step).
fn encode_state(w: &mut Writer, s: &SolverState) {
    let SolverState {
        clock,
        energy,
        resets,
        convergence,
        static_window,
        stop: _,
        control,
        ranks: _,
        active_nodes: _,
        points_reordered,
    } = s;
    encode_clock(w, clock);
    energy.to_array().iter().for_each(|&e| w.f64(e));
    encode_resets(w, resets);
    encode_convergence(w, convergence);
    encode_static_window(w, static_window);
    encode_control(w, control);
    w.u8(*points_reordered as u8);
}

fn decode_state(r: &mut Reader) -> Result<SolverState, CheckpointError> {
    Ok(SolverState {
        clock: decode_clock(r)?,
        energy: EnergyWindow::from_array([r.f64()?, r.f64()?, r.f64()?]),
        resets: decode_resets(r)?,
        convergence: decode_convergence(r)?,
        static_window: decode_static_window(r)?,
        stop: None,
        control: decode_control(r)?,
        ranks: RankCounters::default(),
        active_nodes: NodeBox::default(),
        points_reordered: r.u8()? == 1,
    })
}

/// The split over ranks: the rank count, this rank, every rank's first cell layer (and
/// the end), and this rank's migration counters (in the summary).
fn encode_ranks(w: &mut Writer, d: &Decomposition, counters: &RankCounters) {
    w.u64(d.ranks() as u64);
    w.u64(d.rank as u64);
    for cuts in [&d.bounds, &d.across] {
        w.u64(cuts.len() as u64);
        cuts.iter().for_each(|&b| w.u64(b as u64));
    }
    w.u64(counters.migrations);
    w.u64(counters.rebalances);
}

/// Reads the split ([`encode_ranks`]) into its rank count, rank and bounds, and the counters.
fn decode_ranks(
    r: &mut Reader,
    counters: &mut RankCounters,
) -> Result<(usize, usize, [Vec<usize>; 2]), CheckpointError> {
    let ranks = r.u64()? as usize;
    let rank = r.u64()? as usize;
    let mut cuts = || {
        let n = r.u64()?;
        if n > 1 << 32 {
            return Err(r.fault("the saved cell layers of the ranks do not fit the grid".into()));
        }
        (0..n)
            .map(|_| Ok(r.u64()? as usize))
            .collect::<Result<Vec<_>, _>>()
    };
    let (bounds, across) = (cuts()?, cuts()?);
    counters.migrations = r.u64()?;
    counters.rebalances = r.u64()?;
    Ok((ranks, rank, [bounds, across]))
}

fn encode_clock(w: &mut Writer, c: &Clock) {
    let Clock { step, time } = c;
    w.u64(*step);
    w.f64(*time);
}

fn decode_clock(r: &mut Reader) -> Result<Clock, CheckpointError> {
    Ok(Clock {
        step: r.u64()?,
        time: r.f64()?,
    })
}

fn encode_resets(w: &mut Writer, s: &Resets) {
    let Resets {
        count,
        peaks,
        this_step,
        fraction,
    } = s;
    w.u64(*count);
    w.u64(peaks.len() as u64);
    for Peak { time, energy } in peaks {
        w.f64(*time);
        w.f64(*energy);
    }
    w.u8(*this_step as u8);
    w.f64(*fraction);
}

fn decode_resets(r: &mut Reader) -> Result<Resets, CheckpointError> {
    let count = r.u64()?;
    let mut peaks = Vec::new();
    for _ in 0..r.u64()? {
        peaks.push(Peak {
            time: r.f64()?,
            energy: r.f64()?,
        });
    }
    Ok(Resets {
        count,
        peaks,
        this_step: r.u8()? == 1,
        fraction: r.f64()?,
    })
}

fn encode_convergence(w: &mut Writer, c: &Convergence) {
    let Convergence {
        external_work,
        force_ratio_max,
        force_ratio_mean,
        energy_ratio,
        force_reference,
    } = c;
    w.f64(*external_work);
    w.f64(*force_ratio_max);
    w.f64(*force_ratio_mean);
    w.f64(*energy_ratio);
    w.u8(force_reference.is_some() as u8);
    force_reference.unwrap_or_default().iter().for_each(|&f| w.f64(f));
}

fn decode_convergence(r: &mut Reader) -> Result<Convergence, CheckpointError> {
    Ok(Convergence {
        external_work: r.f64()?,
        force_ratio_max: r.f64()?,
        force_ratio_mean: r.f64()?,
        energy_ratio: r.f64()?,
        force_reference: {
            let some = r.u8()? == 1;
            let reference = [r.f64()?, r.f64()?];
            some.then_some(reference)
        },
    })
}

fn encode_static_window(w: &mut Writer, s: &StaticWindow) {
    let StaticWindow { start, movement } = s;
    w.opt(*start);
    w.opt(*movement);
}

fn decode_static_window(r: &mut Reader) -> Result<StaticWindow, CheckpointError> {
    let (start, movement) = (r.opt()?, r.opt()?);
    Ok(StaticWindow { start, movement })
}

fn encode_control(w: &mut Writer, c: &Control) {
    let Control {
        drives,
        bodies,
        contacts: _,
        contact_memory,
        curve,
        stage,
        stages,
        load_increments,
        milestone,
    } = c;
    w.u64(drives.len() as u64);
    for d in drives {
        let Drive {
            name,
            axes,
            velocity,
            reaction,
            travel,
            increments,
        } = d;
        w.str(name);
        w.u8(*axes);
        velocity.iter().chain(reaction).for_each(|&c| w.f64(c));
        w.f64(*travel);
        w.u64(*increments as u64);
    }
    w.u64(bodies.len() as u64);
    for b in bodies {
        let BodyState {
            name,
            velocity,
            load,
            contact_mass: _,
            offset,
            travel,
            increments,
            reaction,
            parts,
            entries,
            deepest_entry,
            in_situ,
        } = b;
        w.str(name);
        velocity
            .iter()
            .chain(load)
            .chain(offset)
            .chain(reaction)
            .for_each(|&c| w.f64(c));
        w.f64(*travel);
        w.u64(*increments as u64);
        w.u64(parts.len() as u64);
        parts.iter().flatten().for_each(|&c| w.f64(c));
        w.u64(*entries);
        w.f64(*deepest_entry);
        // A piezocone's ground: its slices after a flag (0 before its push began).
        w.u8(in_situ.is_some() as u8);
        if let Some(g) = in_situ {
            w.f64(g.width);
            w.f64(g.start);
            w.u64(g.slices.len() as u64);
            g.slices.iter().flatten().for_each(|&c| w.f64(c));
        }
    }
    w.u64(contact_memory.len() as u64);
    for &(k, lambda) in contact_memory {
        w.u64(k);
        w.f64(lambda);
    }
    w.u64(curve.len() as u64);
    for c in curve {
        let CurvePoint {
            name,
            step,
            time,
            displacement,
            force,
            pressure,
        } = c;
        w.str(name);
        w.u64(*step);
        w.f64(*time);
        w.f64(*displacement);
        force.iter().for_each(|&f| w.f64(f));
        w.opt(*pressure);
    }
    w.u64(*stage as u64);
    w.u64(stages.len() as u64);
    for st in stages {
        let StageResult {
            name,
            step,
            time,
            force_ratio,
            energy_ratio,
            resets,
        } = st;
        w.str(name);
        w.u64(*step);
        w.f64(*time);
        w.f64(*force_ratio);
        w.f64(*energy_ratio);
        w.u64(*resets);
    }
    w.u64(load_increments.len() as u64);
    load_increments.iter().for_each(|&k| w.u64(k as u64));
    w.u8(*milestone as u8);
}

fn decode_control(r: &mut Reader) -> Result<Control, CheckpointError> {
    let mut c = Control::default();
    for _ in 0..r.u64()? {
        c.drives.push(Drive {
            name: r.str()?,
            axes: r.u8()?,
            velocity: [r.f64()?, r.f64()?, r.f64()?],
            reaction: [r.f64()?, r.f64()?, r.f64()?],
            travel: r.f64()?,
            increments: r.u64()? as u32,
        });
    }
    for _ in 0..r.u64()? {
        c.bodies.push(BodyState {
            name: r.str()?,
            velocity: [r.f64()?, r.f64()?, r.f64()?],
            load: [r.f64()?, r.f64()?, r.f64()?],
            contact_mass: 0.0,
            offset: [r.f64()?, r.f64()?, r.f64()?],
            reaction: [r.f64()?, r.f64()?, r.f64()?],
            travel: r.f64()?,
            increments: r.u64()? as u32,
            parts: {
                let mut parts = Vec::new();
                for _ in 0..r.u64()? {
                    parts.push([r.f64()?, r.f64()?, r.f64()?]);
                }
                parts
            },
            entries: r.u64()?,
            deepest_entry: r.f64()?,
            in_situ: match r.u8()? {
                0 => None,
                _ => {
                    let (width, start) = (r.f64()?, r.f64()?);
                    let mut slices = Vec::new();
                    for _ in 0..r.u64()? {
                        slices.push([r.f64()?, r.f64()?, r.f64()?, r.f64()?, r.f64()?]);
                    }
                    Some(crate::rigid::InSitu { width, start, slices })
                }
            },
        });
    }
    for _ in 0..r.u64()? {
        c.contact_memory.push((r.u64()?, r.f64()?));
    }
    for _ in 0..r.u64()? {
        c.curve.push(CurvePoint {
            name: r.str()?,
            step: r.u64()?,
            time: r.f64()?,
            displacement: r.f64()?,
            force: [r.f64()?, r.f64()?, r.f64()?],
            pressure: r.opt()?,
        });
    }
    c.stage = r.u64()? as usize;
    for _ in 0..r.u64()? {
        c.stages.push(StageResult {
            name: r.str()?,
            step: r.u64()?,
            time: r.f64()?,
            force_ratio: r.f64()?,
            energy_ratio: r.f64()?,
            resets: r.u64()?,
        });
    }
    for _ in 0..r.u64()? {
        c.load_increments.push(r.u64()? as u32);
    }
    c.milestone = r.u8()? == 1;
    Ok(c)
}

struct Writer(Vec<u8>);

impl Writer {
    fn u8(&mut self, v: u8) {
        self.0.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    fn opt(&mut self, v: Option<f64>) {
        self.u8(v.is_some() as u8);
        self.f64(v.unwrap_or(0.0));
    }
    fn str(&mut self, v: &str) {
        self.u64(v.len() as u64);
        self.0.extend_from_slice(v.as_bytes());
    }
    /// The first bytes of a file: `magic`, the format, the build, the dimension and the
    /// header ([`Reader::header`] reads them).
    fn header(&mut self, magic: &[u8; 8], dimension: u64, header: &Header) {
        self.0.extend_from_slice(magic);
        self.u32(VERSION);
        self.str(BUILD_ID);
        self.u64(dimension);
        self.str(&header.scene_path.to_string_lossy());
        self.str(&header.scene_text);
        self.u32(crc32fast::hash(header.scene_text.as_bytes()));
        self.u64(header.history_bytes);
        self.u32(header.history_crc);
        self.f64(header.wall_seconds);
        self.u32(header.meshes_crc);
    }
    /// Ends the file with the CRC-32 of every byte before it.
    fn finish(mut self) -> Vec<u8> {
        let crc = crc32fast::hash(&self.0);
        self.u32(crc);
        self.0
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
    dimension: u64,
}

impl<'a> Reader<'a> {
    fn new(bytes: &'a [u8], path: &'a Path) -> Self {
        Reader {
            bytes,
            at: 0,
            path,
            dimension: 0,
        }
    }
    fn fault(&self, reason: String) -> CheckpointError {
        CheckpointError::Format {
            path: self.path.to_path_buf(),
            reason,
        }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8], CheckpointError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| self.fault("the file is cut short".into()))?;
        let out = &self.bytes[self.at..end];
        self.at = end;
        Ok(out)
    }
    fn u8(&mut self) -> Result<u8, CheckpointError> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> Result<u64, CheckpointError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
    fn f64(&mut self) -> Result<f64, CheckpointError> {
        Ok(f64::from_bits(self.u64()?))
    }
    fn opt(&mut self) -> Result<Option<f64>, CheckpointError> {
        let some = self.u8()? == 1;
        let v = self.f64()?;
        Ok(some.then_some(v))
    }
    fn str(&mut self) -> Result<String, CheckpointError> {
        let n = self.u64()? as usize;
        let b = self.take(n)?;
        String::from_utf8(b.to_vec()).map_err(|_| self.fault("a text field is not UTF-8".into()))
    }
    fn u32(&mut self) -> Result<u32, CheckpointError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    /// Reads the header [`Writer::header`] wrote after `magic`, once the file's checksum is
    /// found whole.
    fn header(&mut self, magic: &[u8; 8]) -> Result<Header, CheckpointError> {
        let first = self.take(magic.len()).ok();
        if first != Some(magic.as_slice()) {
            return Err(self.fault(match first {
                Some(m) if m == parts::MANIFEST_MAGIC => parts::written_over_ranks(self.bytes, self.path),
                Some(m) if m == MAGIC => "written by a run on one rank: resume it without mpirun".into(),
                _ => "not a kdmpm checkpoint".into(),
            }));
        }
        let version = self.u32()?;
        if version != VERSION {
            return Err(self.fault(format!(
                "format version {version}; this kdmpm reads version {VERSION}: finish the run \
                 with the kdmpm that wrote it, or start it again"
            )));
        }
        // The checksum ends the file and covers every byte before it: the rest is read
        // only from a file that is whole and unchanged.
        let body = self.bytes.len().checked_sub(4).filter(|&b| b >= self.at);
        let body = body.ok_or_else(|| self.fault("the file is cut short".into()))?;
        let saved = u32::from_le_bytes(self.bytes[body..].try_into().expect("4 bytes"));
        if crc32fast::hash(&self.bytes[..body]) != saved {
            return Err(self.fault(
                "its checksum does not match: the file was damaged or changed after it was \
                 written, so it is not resumed"
                    .into(),
            ));
        }
        self.bytes = &self.bytes[..body];
        let build = self.str()?;
        if build != BUILD_ID {
            return Err(self.fault(format!(
                "written by kdmpm build {build}, this is {BUILD_ID}: a run resumes bit for bit only \
                 with the build that started it"
            )));
        }
        self.dimension = self.u64()?;
        let scene_path = PathBuf::from(self.str()?);
        let scene_text = self.str()?;
        if self.u32()? != crc32fast::hash(scene_text.as_bytes()) {
            return Err(self.fault("the scene it holds does not match the scene's hash".into()));
        }
        Ok(Header {
            scene_path,
            scene_text,
            history_bytes: self.u64()?,
            history_crc: self.u32()?,
            wall_seconds: self.f64()?,
            meshes_crc: self.u32()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::components::*;
    use crate::dim::{Dim, Dim2, Dim3};
    use std::mem::size_of;

    /// A body's state round-trips with its piezocone's ground and without one.
    #[test]
    fn a_bodys_state_with_its_ground_reads_back_as_written() {
        use crate::model::Control;
        use crate::rigid::{BodyState, InSitu};
        let mut ground = InSitu::new(0.25, -14.0, -10.0);
        ground.add(-13.9, 0.5, 100e3, 3e3, Some(25e3));
        let control = Control {
            bodies: vec![
                BodyState {
                    name: "cone".into(),
                    travel: 0.5,
                    parts: vec![[1.0, 2.0, 0.0]],
                    in_situ: Some(ground),
                    ..BodyState::default()
                },
                BodyState {
                    name: "wall".into(),
                    ..BodyState::default()
                },
            ],
            ..Control::default()
        };
        let mut w = super::Writer(Vec::new());
        super::encode_control(&mut w, &control);
        let mut r = super::Reader::new(&w.0, std::path::Path::new("test"));
        assert_eq!(super::decode_control(&mut r).expect("reads"), control);
        assert_eq!(r.at, w.0.len(), "every byte read");
    }

    /// Checkpoints copy point columns byte for byte: no component may hold padding, whose
    /// bytes are uninitialised. Each size must equal the sum of its fields' sizes.
    #[test]
    fn point_components_have_no_padding() {
        fn fields<D: Dim>() -> Vec<usize> {
            let (v, m) = (8 * D::N, 8 * D::N * D::N);
            let s = if D::N == 2 { 32 } else { 48 };
            vec![v, v, v, v, m, 8, 8, s, 2, 4]
        }
        fn sizes<D: Dim>() -> Vec<usize> {
            macro_rules! size {
                ($($t:ty),*) => { vec![$(size_of::<$t>()),*] };
            }
            point_components!(D, size)
        }
        // The fixed columns; the materials' states that follow them are `bytemuck::Pod`
        // (a bound of `MaterialState`), which rules out padding.
        assert_eq!(sizes::<Dim2>()[..10], fields::<Dim2>());
        assert_eq!(sizes::<Dim3>()[..10], fields::<Dim3>());
    }
}
