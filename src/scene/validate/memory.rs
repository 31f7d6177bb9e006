//! What a scene will hold in memory, bounded before anything is allocated, against what
//! the machine, its cgroup and the process limits allow.

use super::rules::*;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::rigid::Samples;
use crate::scene::loaded::LoadedScene;
use serde::Serialize;

/// An upper bound of what a scene holds in memory, computed before anything is allocated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Estimate {
    /// Points at most: every sub-cell centre in each body's bounding box, plus the load
    /// carriers (a polygon fills less than its box).
    pub points: u64,
    /// Grid nodes, Π (cells + 1).
    pub nodes: u64,
    /// The rigid bodies' contact samples: their surfaces every half cell within reach of
    /// the grid.
    pub samples: u64,
    /// Bytes of the point and node columns, of the largest set-up and sort buffers and of
    /// the contact samples.
    pub bytes: u64,
}

/// Bytes a contact sample costs: its place, normal, measure and part (64 B) and, each step
/// it meets soil, its contact with up to 27 nodes' slots and weights (about 512 B).
const SAMPLE_BYTES: u64 = 576;

/// Bytes a point costs besides its components: the ECS entity record (16 B), its slot in
/// the scatter's slab grouping (4 B) and the sort's permutation (4 B), rounded up.
pub(super) const POINT_OVERHEAD: u64 = 32;

/// Bytes a node costs: mass (8 B), momentum, force, external force, acceleration and
/// velocity (five vectors of 8·D B), fixity (1 B), its entity record (16 B), and the set-up
/// and sort buffers indexed by node (fixity, touched flag, a u32 count).
pub(super) fn node_bytes(n: u64) -> u64 {
    8 + 5 * 8 * n + 1 + 16 + 1 + 1 + 4
}

/// Bytes of a point's components: position, velocity, displacement (when kept), mass,
/// volume, stress (4 or 6 components), velocity gradient, material and point ids, and the
/// plastic strain of plastic materials.
pub(super) fn point_bytes(n: u64, displacements: bool, state_bytes: u64) -> u64 {
    let vector = 8 * n;
    let stress = if n == 2 { 32 } else { 48 };
    3 * vector - if displacements { 0 } else { vector }
        + 8
        + 8
        + stress
        + vector * n
        + 2
        + 4
        + state_bytes
        + POINT_OVERHEAD
}

/// The model whose state the points of material `name` carry: the first of the scene's
/// model and the models its stages give it that has state (the points carry it from the
/// start, so that a later stage finds it), the scene's model when none has. `None` when the
/// scene has no such material.
pub(crate) fn carried_state(
    loaded: &LoadedScene,
    table: &[(String, MaterialModel)],
    name: &str,
) -> Option<MaterialModel> {
    let own = table.iter().find(|(n, _)| n == name)?.1.clone();
    let staged = loaded
        .scene
        .stages
        .iter()
        .filter_map(|st| st.materials.get(name))
        .filter_map(|spec| spec.model(&|f: &str| f.to_string()).ok());
    let first = std::iter::once(own.clone())
        .chain(staged)
        .find(|m| m.state_name().is_some());
    Some(first.unwrap_or(own))
}

/// The machine's memory (bytes), from `/proc/meminfo`; `None` where it cannot be read.
pub fn machine_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// A `/proc/self/status` figure in bytes (`VmSize`, `VmData`).
pub(super) fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// What this process may still allocate under a resource limit (bytes): `getrlimit`'s
/// soft limit less what the process uses already by that measure.
pub(super) fn rlimit_room(resource: libc::__rlimit_resource_t, used: &str) -> Option<u64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes one `rlimit` through a valid pointer and reads nothing else.
    if unsafe { libc::getrlimit(resource, &mut r) } != 0 || r.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    // rlim_t is 64 bits on 64-bit Linux, 32 on some other targets.
    #[allow(clippy::unnecessary_cast)]
    let limit = r.rlim_cur as u64;
    Some(limit.saturating_sub(status_bytes(used).unwrap_or(0)))
}

/// The memory limit of this process's control group (v2 `memory.max`, v1
/// `memory.limit_in_bytes`), as a cluster's batch system or a container sets it.
pub(super) fn cgroup_limit() -> Option<u64> {
    let membership = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    let mut candidates = Vec::new();
    for line in membership.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, path) = (
            parts.next(),
            parts.next().unwrap_or(""),
            parts.next().unwrap_or(""),
        );
        let path = path.trim_start_matches('/');
        if controllers.is_empty() {
            candidates.push(format!("/sys/fs/cgroup/{path}/memory.max"));
        } else if controllers.split(',').any(|c| c == "memory") {
            candidates.push(format!("/sys/fs/cgroup/memory/{path}/memory.limit_in_bytes"));
        }
    }
    candidates.push("/sys/fs/cgroup/memory.max".into());
    candidates.push("/sys/fs/cgroup/memory/memory.limit_in_bytes".into());
    candidates
        .iter()
        .filter_map(|f| std::fs::read_to_string(f).ok()?.trim().parse::<u64>().ok())
        .min()
}

/// The most memory a run of this process can have (bytes) and what sets it: the machine's
/// memory, a control group's limit, or the address-space or data limit (`ulimit -v`,
/// `ulimit -d`), whichever is smallest; `None` where none can be read.
pub fn memory_limit() -> Option<(u64, &'static str)> {
    [
        (machine_memory_bytes(), "this machine's memory"),
        (cgroup_limit(), "the control group's memory limit"),
        (
            rlimit_room(libc::RLIMIT_AS, "VmSize:"),
            "the address-space limit (ulimit -v) left",
        ),
        (
            rlimit_room(libc::RLIMIT_DATA, "VmData:"),
            "the data-segment limit (ulimit -d) left",
        ),
    ]
    .into_iter()
    .filter_map(|(bytes, what)| Some((bytes?, what)))
    .min_by_key(|&(bytes, _)| bytes)
}

/// Counts points and nodes in checked arithmetic: a count that overflows is an error, not
/// a different problem.
/// The bound, and each rigid body's contact samples (in scene order).
pub(super) fn estimate(
    loaded: &LoadedScene,
    table: &[(String, MaterialModel)],
) -> Result<(Estimate, Vec<Samples>), SceneError> {
    let s = &loaded.scene;
    let n = s.dimension.axes();
    let too_many =
        |field: &str, what: &str| loaded.invalid(field, format!("{what} overflows a 64-bit count"));
    let nodes = s
        .grid
        .cells
        .iter()
        .try_fold(1u64, |acc, &c| acc.checked_mul((c as u64).checked_add(1)?))
        .filter(|&nodes| usize::try_from(nodes).is_ok())
        .ok_or_else(|| too_many("grid.cells", "the node count Π (cells + 1)"))?;
    let mut points = s.point_loads.len() as u64;
    let mut bytes = nodes
        .checked_mul(node_bytes(n as u64))
        .ok_or_else(|| too_many("grid.cells", "the grid's memory"))?;
    for (b, body) in s.bodies.iter().enumerate() {
        let field = format!("bodies[{b}].points_per_cell");
        let (lo, hi) = crate::scene::region::region_bounds(&body.region, n);
        let mut count = 1u64;
        for a in 0..n {
            // Cells of the bounding box along the axis, as set-up fills them.
            let inv_h = 1.0 / s.grid.cell_size;
            let (first, last) =
                crate::scene::region::cell_span(lo[a], hi[a], s.grid.origin[a], inv_h, s.grid.cells[a]);
            count = (last.saturating_sub(first) as u64)
                .checked_mul(body.points_per_cell[a] as u64)
                .and_then(|c| count.checked_mul(c))
                .ok_or_else(|| too_many(&field, "the point count"))?;
        }
        let state_bytes = carried_state(loaded, table, &body.material).map_or(0, |m| m.state_bytes());
        points = points
            .checked_add(count)
            .ok_or_else(|| too_many(&field, "the point count"))?;
        bytes = count
            .checked_mul(point_bytes(n as u64, s.output.displacements, state_bytes as u64))
            .and_then(|b| bytes.checked_add(b))
            .ok_or_else(|| too_many(&field, "the points' memory"))?;
    }
    let (lo, hi) = (
        crate::scene::spec::pad3(&s.grid.origin),
        std::array::from_fn(|a| {
            if a < n {
                s.grid.origin[a] + s.grid.cells[a] as f64 * s.grid.cell_size
            } else {
                0.0
            }
        }),
    );
    let per_body: Vec<Samples> = s
        .rigid_bodies
        .iter()
        .map(|b| b.samples(n, s.grid.cell_size, (lo, hi)))
        .collect();
    let samples: u64 = per_body.iter().map(|b| b.len() as u64).sum();
    let bytes = samples
        .checked_mul(SAMPLE_BYTES)
        .and_then(|b| bytes.checked_add(b))
        .ok_or_else(|| too_many("rigid_bodies", "the contact samples' memory"))?;
    Ok((
        Estimate {
            points,
            nodes,
            samples,
            bytes,
        },
        per_body,
    ))
}

/// The memory bound against what the process may have, and each rigid body's contact
/// samples.
pub(super) fn check_memory(
    r: &Rules,
    table: &[(String, MaterialModel)],
) -> Result<(Estimate, Vec<Samples>), SceneError> {
    let loaded = r.loaded;
    let (estimate, samples) = estimate(loaded, table)?;
    if let Some((total, what)) = memory_limit() {
        if estimate.bytes > total {
            return r.bad(
                "grid",
                format!(
                    "the scene needs up to {:.3} GB ({} points, {} nodes at most), more than {what}, {:.3} GB: \
                     use larger cells, fewer points per cell or a smaller grid",
                    estimate.bytes as f64 / 1e9,
                    estimate.points,
                    estimate.nodes,
                    total as f64 / 1e9
                ),
            );
        }
    }
    Ok((estimate, samples))
}
