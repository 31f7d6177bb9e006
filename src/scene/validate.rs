//! Rules a scene must satisfy before anything is built or written, and the figures derived
//! from it.

use super::{BoundarySpec, LoadedScene, Region, TimeStep};
use crate::components::NodeFixity;
use crate::error::SceneError;
use crate::materials::MaterialModel;
use crate::shape::ShapeKind;
use crate::state::Scheme;
use serde::Serialize;

/// The largest Courant number accepted with the USL scheme. Measured on the self-weight
/// column (`studies/courant.ron`): USL with linear shapes diverges from Courant 0.8 and with
/// quadratic B-splines never settles at 1.0; on the 2D slope it loses a point at Courant 1.
pub const USL_COURANT_LIMIT: f64 = 0.7;

/// The largest Courant number (of the slowest material) accepted with mass scaling.
/// Measured on a soil layer on rock a million times stiffer (`tests/extremes.rs`): it
/// settles at Courant 0.5 to 0.9 and diverges at step 59 at Courant 1.
pub const MASS_SCALING_COURANT_LIMIT: f64 = 0.9;

/// Figures derived from a valid scene (printed by `kdmpm check`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Derived {
    /// Largest P-wave speed sqrt(M/ρ) over the materials the bodies use (m/s).
    pub p_wave_speed: f64,
    /// Critical time step h / c_p (s).
    pub critical_time_step: f64,
    /// Time step used (s).
    pub time_step: f64,
    /// Material points (load carriers included).
    pub points: usize,
    /// Nodes touched by the points at the start.
    pub active_nodes: usize,
    /// Grid nodes in all.
    pub grid_nodes: usize,
    /// Systems of one step, in order.
    pub systems: Vec<String>,
    /// Materials the scene defines but no body uses, in name order. They are validated
    /// like the others but do not set the time step.
    pub unused_materials: Vec<String>,
    /// The memory bound checked before anything was allocated.
    pub estimate: Estimate,
}

/// Each stage's materials, built once: the index in the scene's table and the model.
pub type StageModels = Vec<Vec<(u16, MaterialModel)>>;

/// What [`check`] establishes.
#[derive(Clone, Debug)]
pub struct Checked {
    /// Every material the scene defines, in name order.
    pub materials: Vec<(String, MaterialModel)>,
    /// The materials each stage sets (by index in `materials`), in stage order.
    pub stage_materials: StageModels,
    /// Largest P-wave speed sqrt(M/ρ) over the materials the bodies use (m/s).
    pub p_wave_speed: f64,
    /// Critical time step h / c_p (s).
    pub critical_time_step: f64,
    /// Time step to use (s).
    pub time_step: f64,
    /// Materials no body uses, in name order.
    pub unused_materials: Vec<String>,
    /// What the run will hold in memory, at most.
    pub estimate: Estimate,
}

/// An upper bound of what a scene holds in memory, computed before anything is allocated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Estimate {
    /// Points at most: every sub-cell centre in each body's bounding box, plus the load
    /// carriers (a polygon fills less than its box).
    pub points: u64,
    /// Grid nodes, Π (cells + 1).
    pub nodes: u64,
    /// Bytes of the point and node columns and of the largest set-up and sort buffers.
    pub bytes: u64,
}

/// Bytes a point costs besides its components: the ECS entity record (16 B), its slot in
/// the scatter's slab grouping (4 B) and the sort's permutation (4 B), rounded up.
const POINT_OVERHEAD: u64 = 32;

/// Bytes a node costs: mass (8 B), momentum, force, external force, acceleration and
/// velocity (five vectors of 8·D B), fixity (1 B), its entity record (16 B), and the set-up
/// and sort buffers indexed by node (fixity, touched flag, a u32 count).
fn node_bytes(n: u64) -> u64 {
    8 + 5 * 8 * n + 1 + 16 + 1 + 1 + 4
}

/// Bytes of a point's components: position, velocity, displacement (when kept), mass,
/// volume, stress (4 or 6 components), velocity gradient, material and point ids, and the
/// plastic strain of plastic materials.
fn point_bytes(n: u64, displacements: bool, state_bytes: u64) -> u64 {
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
pub(super) fn carried_state(
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
fn status_bytes(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// What this process may still allocate under a resource limit (bytes): `getrlimit`'s
/// soft limit less what the process uses already by that measure.
fn rlimit_room(resource: libc::__rlimit_resource_t, used: &str) -> Option<u64> {
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
fn cgroup_limit() -> Option<u64> {
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
fn estimate(loaded: &LoadedScene, table: &[(String, MaterialModel)]) -> Result<Estimate, SceneError> {
    let s = &loaded.scene;
    let n = s.dimension as usize;
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
        let (lo, hi) = super::region_bounds(&body.region, n);
        let mut count = 1u64;
        for a in 0..n {
            // Cells of the bounding box along the axis, as set-up fills them.
            let inv_h = 1.0 / s.grid.cell_size;
            let (first, last) = super::cell_span(lo[a], hi[a], s.grid.origin[a], inv_h, s.grid.cells[a]);
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
    Ok(Estimate { points, nodes, bytes })
}

/// Largest step count a `max_time` without `max_steps` may imply: 10^12 steps of the
/// smallest scene would take days; a larger count is a time step too small to mean it.
const MAX_IMPLIED_STEPS: f64 = 1e12;

/// Why a polygon cannot be filled, if it cannot: zero area, or two edges that cross or
/// touch other than at their shared vertex (the even-odd fill of a self-intersecting
/// polygon is rarely the region meant).
fn polygon_fault(vertices: &[Vec<f64>]) -> Option<String> {
    let m = vertices.len();
    let p = |i: usize| (vertices[i % m][0], vertices[i % m][1]);
    let twice_area: f64 = (0..m)
        .map(|i| {
            let ((x0, y0), (x1, y1)) = (p(i), p(i + 1));
            x0 * y1 - x1 * y0
        })
        .sum();
    if !positive(twice_area.abs()) {
        return Some("the polygon encloses no area".into());
    }
    let cross =
        |o: (f64, f64), a: (f64, f64), b: (f64, f64)| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let on = |a: (f64, f64), b: (f64, f64), q: (f64, f64)| {
        q.0 >= a.0.min(b.0) && q.0 <= a.0.max(b.0) && q.1 >= a.1.min(b.1) && q.1 <= a.1.max(b.1)
    };
    // Segments a-b and c-d meet (proper crossing, or one end on the other segment).
    let meet = |a, b, c, d| {
        let (d1, d2, d3, d4) = (cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d));
        (d1 * d2 < 0.0 && d3 * d4 < 0.0)
            || (d1 == 0.0 && on(c, d, a))
            || (d2 == 0.0 && on(c, d, b))
            || (d3 == 0.0 && on(a, b, c))
            || (d4 == 0.0 && on(a, b, d))
    };
    for i in 0..m {
        for j in i + 1..m {
            // Neighbouring edges share a vertex; they fault only by folding back on each other.
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            let (a, b, c, d) = (p(i), p(i + 1), p(j), p(j + 1));
            if adjacent {
                let (shared, u, v) = if j == i + 1 { (b, a, d) } else { (a, b, c) };
                let collinear_back = cross(shared, u, v) == 0.0
                    && (u.0 - shared.0) * (v.0 - shared.0) + (u.1 - shared.1) * (v.1 - shared.1) > 0.0;
                if collinear_back {
                    return Some(format!("edges {i} and {j} fold back on each other"));
                }
            } else if meet(a, b, c, d) {
                return Some(format!(
                    "edges {i} ({:?} to {:?}) and {j} ({:?} to {:?}) cross: give the vertices of a simple polygon, in order",
                    vertices[i], vertices[(i + 1) % m], vertices[j], vertices[(j + 1) % m]
                ));
            }
        }
    }
    None
}

/// The finest bisection of `kdmpm fos`, relative to the bracket's high end: about 24
/// halvings of a bracket [0.5, 2].
pub const MIN_FOS_TOLERANCE: f64 = 1e-7;

/// Names that label output (columns of `history.csv`, rows of `curve.csv` and
/// `stages.csv`) are unique within their list: two traced points called "top" would give
/// two columns of one name.
fn unique_names(s: &super::Scene) -> Result<(), (String, String)> {
    let lists: [(&str, Vec<&str>); 5] = [
        ("traced", s.traced.iter().map(|t| t.name.as_str()).collect()),
        (
            "point_loads",
            s.point_loads.iter().map(|t| t.name.as_str()).collect(),
        ),
        ("tractions", s.tractions.iter().map(|t| t.name.as_str()).collect()),
        ("motions", s.motions.iter().map(|t| t.name.as_str()).collect()),
        ("stages", s.stages.iter().map(|t| t.name.as_str()).collect()),
    ];
    for (field, names) in lists {
        for (i, name) in names.iter().enumerate() {
            if let Some(j) = names[..i].iter().position(|m| m == name) {
                return Err((
                    format!("{field}[{i}].name"),
                    format!("\"{name}\" is also the name of {field}[{j}]: each needs its own name"),
                ));
            }
        }
    }
    Ok(())
}

/// Each body's mass (ρ times its bounding box's volume, an upper bound) and the scene's
/// weight are finite numbers: a density of 1e308 kg/m³ gives points whose mass sums to
/// infinity, and a gravity of 1e308 m/s² forces that do, and the first step turns them
/// into NaN.
fn check_mass_finite(
    loaded: &LoadedScene,
    table: &[(String, MaterialModel)],
    n: usize,
) -> Result<(), SceneError> {
    let s = &loaded.scene;
    let mut total = 0.0f64;
    for body in &s.bodies {
        let Some((_, model)) = table.iter().find(|(name, _)| *name == body.material) else {
            continue;
        };
        let (lo, hi) = super::region_bounds(&body.region, n);
        let volume: f64 = (0..n).map(|a| (hi[a] - lo[a]).abs()).product();
        let mass = model.density() * volume;
        total += mass;
        if !mass.is_finite() || !total.is_finite() {
            return Err(loaded.invalid(
                &format!("materials.{}.density", body.material),
                format!(
                    "{:e} kg/m³ over the bodies' {volume:e} m{} gives a mass that is not a finite number",
                    model.density(),
                    if n == 2 { "² (per metre)" } else { "³" }
                ),
            ));
        }
    }
    if let Some(g) = &s.gravity {
        let size = g.acceleration.iter().fold(0.0f64, |s, a| s.hypot(*a));
        if !(total * size).is_finite() {
            return Err(loaded.invalid(
                "gravity.acceleration",
                format!("|g| = {size:e} m/s² on {total:e} kg gives a weight that is not a finite number"),
            ));
        }
    }
    Ok(())
}

/// Volumetric smoothing is for isochoric plastic flow (ψ = 0): it is refused on a material
/// that dilates, in the scene or in a stage. The smoothed strain rate is not work-conjugate
/// to the nodal forces, and on dilatant flow the mismatch feeds the kinetic energy: a
/// smooth strip footing on c = 10 kPa, φ = ψ = 30° soil stops at K_E > 10 (docs/verification.md).
/// Making the forces conjugate (the mean stress projected the same way) is stable there but
/// spreads a shear band's dilation into the soil around it, which loses confinement: the
/// limit pressure falls 12 % below Prandtl–Reissner and the footing then sinks without end.
fn check_smoothing(loaded: &LoadedScene) -> Result<(), SceneError> {
    let s = &loaded.scene;
    for (name, m) in s.every_material() {
        let psi = m.dilatancy_angle();
        if psi > 0.0 {
            return Err(loaded.invalid(
                "solver.volumetric_smoothing",
                format!(
                    "material \"{name}\" dilates (ψ = {psi}°): volumetric smoothing is for plastic \
                     flow without volume change (ψ = 0) and makes a run with dilatant flow \
                     unstable (docs/verification.md); set it false, or ψ = 0"
                ),
            ));
        }
    }
    Ok(())
}

/// True for a finite number > 0 (NaN fails).
fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

/// True for a finite number ≥ 0 (NaN fails).
fn non_negative(x: f64) -> bool {
    x >= 0.0 && x.is_finite()
}

/// Checks a list of face conditions (`field`: where it is in the scene): faces of the
/// grid's dimension `n`, one condition a face.
fn check_faces(list: &[BoundarySpec], field: &str, n: usize) -> Result<(), (String, String)> {
    for (i, bc) in list.iter().enumerate() {
        if bc.face.axis_side().0 >= n {
            return Err((
                format!("{field}[{i}].face"),
                format!("{:?} does not exist in {n}D", bc.face),
            ));
        }
        // One condition a face: two would leave the reader to guess which one holds.
        if let Some(j) = list[..i].iter().position(|o| o.face == bc.face) {
            return Err((
                format!("{field}[{i}].face"),
                format!(
                    "{:?} already has a condition ({field}[{j}]): give each face one condition \
                     (Fixed holds every component, Roller the normal one)",
                    bc.face
                ),
            ));
        }
    }
    Ok(())
}

/// The scene and its dimension, for the checks of each part: each names a field and the
/// rule it breaks through [`Rules::bad`].
struct Rules<'a> {
    loaded: &'a LoadedScene,
    /// 2 or 3.
    n: usize,
}

impl Rules<'_> {
    /// The error for `field`, breaking `rule`.
    fn bad<T>(&self, field: &str, rule: String) -> Result<T, SceneError> {
        Err(self.loaded.invalid(field, rule))
    }

    /// A vector of one entry per axis.
    fn len(&self, field: &str, v: usize) -> Result<(), SceneError> {
        let n = self.n;
        if v != n {
            return Err(self
                .loaded
                .invalid(field, format!("needs {n} entries (dimension {n}), found {v}")));
        }
        Ok(())
    }

    /// Every coordinate, force and acceleration is a finite number: a NaN or infinity in
    /// the input would reach the state and be written out.
    fn finite(&self, field: &str, v: &[f64], unit: &str) -> Result<(), SceneError> {
        match v.iter().position(|x| !x.is_finite()) {
            Some(k) => Err(self.loaded.invalid(
                field,
                format!("entry {k} must be a finite number ({unit}), found {}", v[k]),
            )),
            None => Ok(()),
        }
    }
}

/// Checks every rule that does not need the points, part by part.
pub fn check(loaded: &LoadedScene) -> Result<Checked, SceneError> {
    let s = &loaded.scene;
    if s.dimension != 2 && s.dimension != 3 {
        return Err(loaded.invalid("dimension", format!("must be 2 or 3, found {}", s.dimension)));
    }
    let r = Rules {
        loaded,
        n: s.dimension as usize,
    };
    check_grid(&r)?;
    let table = check_materials(&r)?;
    check_solver(&r)?;
    check_bodies(&r)?;
    check_loads(&r, &table)?;
    check_motions_and_analyses(&r)?;
    check_tractions_and_traced(&r)?;
    check_has_load(&r)?;
    let step = time_step(&r, &table)?;
    let stage_materials = check_stages(&r, &table, step.p_wave_speed)?;
    let estimate = check_memory(&r, &table)?;
    Ok(Checked {
        materials: table,
        stage_materials,
        p_wave_speed: step.p_wave_speed,
        critical_time_step: step.critical,
        time_step: step.dt,
        unused_materials: step.unused_materials,
        estimate,
    })
}

/// The time step and what set it.
struct StepChoice {
    /// Largest (smallest with mass scaling) P-wave speed of the materials bodies use (m/s).
    p_wave_speed: f64,
    /// h / c_p (s).
    critical: f64,
    /// The time step (s).
    dt: f64,
    /// Materials no body uses, in name order.
    unused_materials: Vec<String>,
}

/// The grid: origin, cells and cell size.
fn check_grid(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    r.len("grid.origin", s.grid.origin.len())?;
    r.finite("grid.origin", &s.grid.origin, "m")?;
    r.len("grid.cells", s.grid.cells.len())?;
    if !positive(s.grid.cell_size) {
        return r.bad(
            "grid.cell_size",
            format!("must be > 0 m, found {}", s.grid.cell_size),
        );
    }
    if s.shape == ShapeKind::UniformGimp {
        if let Some(i) = s
            .bodies
            .iter()
            .position(|b| b.points_per_cell != s.bodies[0].points_per_cell)
        {
            return r.bad(
                &format!("bodies[{i}].points_per_cell"),
                "UniformGimp sizes every point's box from its points a cell side: every body needs the same as bodies[0]".to_string(),
            );
        }
    }
    let min_cells = if s.shape.support() == 3 { 2 } else { 1 };
    // The grid's far corner and a cell's volume h^D must be finite numbers > 0: a cell
    // size of 1e-200 m would give cells of zero volume and points of zero mass.
    let cell_volume = s.grid.cell_size.powi(n as i32);
    if !(cell_volume.is_normal() && cell_volume.is_finite()) {
        return r.bad(
            "grid.cell_size",
            format!(
                "h = {:e} m gives a cell volume h^{n} = {cell_volume:e}, which is not a finite number > 0",
                s.grid.cell_size
            ),
        );
    }
    if let Some(a) =
        (0..n).find(|&a| !(s.grid.origin[a] + s.grid.cell_size * s.grid.cells[a] as f64).is_finite())
    {
        return r.bad(
            "grid.cells",
            format!("the grid's far corner along axis {a} is not a finite coordinate"),
        );
    }
    if let Some(c) = s.grid.cells.iter().find(|&&c| c < min_cells) {
        return r.bad(
            "grid.cells",
            format!(
                "every axis needs at least {min_cells} cell(s) with {:?} shape functions, found {c}",
                s.shape
            ),
        );
    }
    Ok(())
}

/// Every material, checked by its own scene entry; the models in name order.
fn check_materials(r: &Rules) -> Result<Vec<(String, MaterialModel)>, SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    if s.materials.is_empty() {
        return r.bad("materials", "the scene defines no material".into());
    }
    let mut table = Vec::new();
    for (name, m) in &s.materials {
        let at = |f: &str| format!("materials.{name}.{f}");
        let model = m
            .model(&at)
            .map_err(|(field, rule)| loaded.invalid(&field, rule))?;
        table.push((name.clone(), model));
    }
    Ok(table)
}

/// The solver's and the output's settings that stand alone.
fn check_solver(r: &Rules) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    if !positive(s.solver.tolerance) {
        return r.bad(
            "solver.tolerance",
            format!("must be > 0, found {}", s.solver.tolerance),
        );
    }
    if let crate::state::Damping::Viscous { beta } = s.solver.damping {
        if !non_negative(beta) {
            return r.bad(
                "solver.damping",
                format!("viscous β must be ≥ 0 (1/s), found {beta}"),
            );
        }
    }
    if let Some(snap) = s.output.snapshots {
        if snap.every_steps == Some(0) {
            return r.bad("output.snapshots.every_steps", "must be ≥ 1 step".to_string());
        }
        if let Some(t) = snap.every_time {
            if !positive(t) {
                return r.bad("output.snapshots.every_time", format!("must be > 0 s, found {t}"));
            }
        }
        if snap.every_steps.is_none() && snap.every_time.is_none() && !snap.at_resets {
            return r.bad(
                "output.snapshots",
                "takes no snapshot but the last: set every_steps, every_time or at_resets".to_string(),
            );
        }
    }
    if s.solver.peak_interpolation && s.solver.damping != crate::state::Damping::Kinetic {
        return r.bad(
            "solver.peak_interpolation",
            "places kinetic-damping resets: it needs `damping: Kinetic`".to_string(),
        );
    }
    if let crate::state::Damping::Local { alpha } = s.solver.damping {
        if !(non_negative(alpha) && alpha < 1.0) {
            return r.bad(
                "solver.damping",
                format!("local damping α must be in [0, 1), found {alpha}"),
            );
        }
    }
    if let Some(c) = s.solver.static_check {
        if !positive(c.window) {
            return r.bad(
                "solver.static_check.window",
                format!("must be > 0 s, found {}", c.window),
            );
        }
        if !positive(c.max_displacement) {
            return r.bad(
                "solver.static_check.max_displacement",
                format!("must be > 0 m, found {}", c.max_displacement),
            );
        }
    }
    for (field, value) in [
        ("solver.node_mass_cutoff", s.solver.node_mass_cutoff),
        ("solver.virtual_mass_floor", s.solver.virtual_mass_floor),
    ] {
        if !(0.0..1.0).contains(&value) {
            return r.bad(
                field,
                format!("must be in [0, 1) (a fraction of a full node's mass), found {value}"),
            );
        }
    }
    if !(0.0..=1.0).contains(&s.solver.flip) {
        return r.bad(
            "solver.flip",
            format!("must be in [0, 1] (1 = FLIP, 0 = PIC), found {}", s.solver.flip),
        );
    }
    if s.solver.max_steps.is_none() && s.solver.max_time.is_none() {
        return r.bad(
            "solver",
            "set max_steps or max_time, so that a run that never converges still ends".into(),
        );
    }
    if s.solver.max_steps == Some(0) {
        return r.bad("solver.max_steps", "must be ≥ 1".into());
    }
    if let Some(t) = s.solver.max_time {
        if !positive(t) {
            return r.bad("solver.max_time", format!("must be > 0 s, found {t}"));
        }
    }
    match s.solver.checkpoint_every {
        Some(super::CheckpointEvery::Steps(0)) => {
            return r.bad("solver.checkpoint_every", "Steps(n) needs n ≥ 1".into());
        }
        Some(super::CheckpointEvery::Seconds(t)) if !positive(t) => {
            return r.bad(
                "solver.checkpoint_every",
                format!("Seconds(t) needs a wall time t > 0 s, found {t}"),
            );
        }
        _ => {}
    }
    if s.output.history_every == 0 {
        return r.bad("output.history_every", "must be ≥ 1".into());
    }
    Ok(())
}

/// The bodies: material, points per cell, region.
fn check_bodies(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    if s.bodies.is_empty() {
        return r.bad(
            "bodies",
            "the scene has no body: there is nothing to simulate".into(),
        );
    }
    for (b, body) in s.bodies.iter().enumerate() {
        if !s.materials.contains_key(&body.material) {
            let known: Vec<_> = s.materials.keys().map(String::as_str).collect();
            return r.bad(
                &format!("bodies[{b}].material"),
                format!(
                    "unknown material \"{}\" (defined: {})",
                    body.material,
                    known.join(", ")
                ),
            );
        }
        r.len(
            &format!("bodies[{b}].points_per_cell"),
            body.points_per_cell.len(),
        )?;
        if body.points_per_cell.contains(&0) {
            return r.bad(
                &format!("bodies[{b}].points_per_cell"),
                "every entry must be ≥ 1".into(),
            );
        }
        match &body.region {
            Region::Box { min, max } => {
                r.len(&format!("bodies[{b}].region.min"), min.len())?;
                r.len(&format!("bodies[{b}].region.max"), max.len())?;
                r.finite(&format!("bodies[{b}].region.min"), min, "m")?;
                r.finite(&format!("bodies[{b}].region.max"), max, "m")?;
                if min.iter().zip(max).any(|(a, b)| !positive(b - a)) {
                    return r.bad(
                        &format!("bodies[{b}].region"),
                        "box needs min < max on every axis".into(),
                    );
                }
            }
            Region::Polygon { vertices, z } => {
                if vertices.len() < 3 {
                    return r.bad(
                        &format!("bodies[{b}].region.vertices"),
                        "a polygon needs at least 3 vertices".into(),
                    );
                }
                if let Some(k) = vertices.iter().position(|v| v.len() != 2) {
                    return r.bad(
                        &format!("bodies[{b}].region.vertices"),
                        format!("vertex {k} needs 2 entries [x, y], found {}", vertices[k].len()),
                    );
                }
                for (k, v) in vertices.iter().enumerate() {
                    r.finite(&format!("bodies[{b}].region.vertices[{k}]"), v, "m")?;
                }
                if let Some(z) = z {
                    if n == 2 {
                        return r.bad(
                            &format!("bodies[{b}].region.z"),
                            "a 2D polygon has no extent along z: remove z (it is for 3D scenes)".into(),
                        );
                    }
                    r.finite(&format!("bodies[{b}].region.z"), z, "m")?;
                }
                if let Some(rule) = polygon_fault(vertices) {
                    return r.bad(&format!("bodies[{b}].region.vertices"), rule);
                }
                if n == 3 && !z.as_ref().is_some_and(|z| z.len() == 2 && positive(z[1] - z[0])) {
                    return r.bad(
                        &format!("bodies[{b}].region"),
                        "in 3D a polygon needs z: [z_min, z_max] with z_min < z_max".into(),
                    );
                }
            }
        }
    }
    Ok(())
}

/// Face conditions, gravity, point loads, and what the materials make of them.
fn check_loads(r: &Rules, table: &[(String, MaterialModel)]) -> Result<(), SceneError> {
    let (loaded, s, n) = (r.loaded, &r.loaded.scene, r.n);
    check_faces(&s.boundaries, "boundaries", n).map_err(|(field, rule)| loaded.invalid(&field, rule))?;
    if let Some(g) = &s.gravity {
        r.len("gravity.acceleration", g.acceleration.len())?;
        r.finite("gravity.acceleration", &g.acceleration, "m/s²")?;
        if !non_negative(g.ramp_time) {
            return r.bad(
                "gravity.ramp_time",
                format!("must be ≥ 0 s, found {}", g.ramp_time),
            );
        }
    }
    check_mass_finite(loaded, table, n)?;
    if s.solver.volumetric_smoothing {
        check_smoothing(loaded)?;
    }
    for (i, l) in s.point_loads.iter().enumerate() {
        r.len(&format!("point_loads[{i}].position"), l.position.len())?;
        r.len(&format!("point_loads[{i}].force"), l.force.len())?;
        r.finite(&format!("point_loads[{i}].position"), &l.position, "m")?;
        r.finite(&format!("point_loads[{i}].force"), &l.force, "N")?;
    }
    Ok(())
}

/// Motions, names, and the strength-reduction analysis.
fn check_motions_and_analyses(r: &Rules) -> Result<(), SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    if s.motions.len() > NodeFixity::MAX_DRIVES {
        return r.bad(
            "motions",
            format!(
                "at most {} motions, found {}",
                NodeFixity::MAX_DRIVES,
                s.motions.len()
            ),
        );
    }
    for (i, m) in s.motions.iter().enumerate() {
        m.check(s.dimension as usize)
            .map_err(|(field, rule)| loaded.invalid(&format!("motions[{i}].{field}"), rule))?;
    }
    unique_names(s).map_err(|(field, rule)| loaded.invalid(&field, rule))?;
    if let Some(spec) = &s.strength_reduction {
        let ok =
            matches!(spec.bracket[..], [lo, hi] if lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi);
        if !ok {
            return r.bad(
                "strength_reduction.bracket",
                format!("needs two factors 0 < low < high, found {:?}", spec.bracket),
            );
        }
        let hi = spec.bracket[1];
        if !(spec.tolerance.is_finite() && spec.tolerance >= MIN_FOS_TOLERANCE * hi) {
            return r.bad(
                "strength_reduction.tolerance",
                format!(
                    "must be at least {MIN_FOS_TOLERANCE:e} of the bracket's high end ({:e}), found {:e}: \
                     each halving of the bracket is a whole run, and a factor finer than that is \
                     below what a trial resolves",
                    MIN_FOS_TOLERANCE * hi,
                    spec.tolerance
                ),
            );
        }
        if !(spec.failure_displacement.is_finite() && spec.failure_displacement > 0.0) {
            return r.bad(
                "strength_reduction.failure_displacement",
                "must be above 0 (m)".into(),
            );
        }
        if spec.check_every == 0 {
            return r.bad(
                "strength_reduction.check_every",
                "must be at least 1 (steps)".into(),
            );
        }
        if !s.output.displacements {
            return r.bad(
                "output.displacements",
                "strength reduction judges trials by displacement: keep them (true)".into(),
            );
        }
    }
    Ok(())
}

/// Tractions and traced points.
fn check_tractions_and_traced(r: &Rules) -> Result<(), SceneError> {
    let (s, n) = (&r.loaded.scene, r.n);
    for (i, t) in s.tractions.iter().enumerate() {
        r.len(&format!("tractions[{i}].min"), t.min.len())?;
        r.len(&format!("tractions[{i}].max"), t.max.len())?;
        r.len(&format!("tractions[{i}].traction"), t.traction.len())?;
        r.finite(&format!("tractions[{i}].min"), &t.min, "m")?;
        r.finite(&format!("tractions[{i}].max"), &t.max, "m")?;
        r.finite(&format!("tractions[{i}].traction"), &t.traction, "Pa")?;
        if t.min.iter().zip(&t.max).any(|(lo, hi)| lo > hi) {
            return r.bad(
                &format!("tractions[{i}].max"),
                "every entry must be at least min's".into(),
            );
        }
        if t.increments == Some(0) {
            return r.bad(&format!("tractions[{i}].increments"), "must be at least 1".into());
        }
        if t.increments.is_some() && !s.output.displacements {
            return r.bad(
                &format!("tractions[{i}].increments"),
                "the curve follows the loaded points' displacement: keep them (output.displacements: true)"
                    .into(),
            );
        }
        if t.surface.axis_side().0 >= n {
            return r.bad(
                &format!("tractions[{i}].surface"),
                format!("{:?} is not a face of a {n}D grid", t.surface),
            );
        }
    }
    for (i, t) in s.traced.iter().enumerate() {
        r.len(&format!("traced[{i}].position"), t.position.len())?;
        r.finite(&format!("traced[{i}].position"), &t.position, "m")?;
    }
    Ok(())
}

/// A scene without load is static as it stands.
fn check_has_load(r: &Rules) -> Result<(), SceneError> {
    let s = &r.loaded.scene;
    // A scene without load is static as it stands: K_F and K_E are 0/0 at every step and
    // there is nothing to solve. Say so rather than run it.
    let gravity = s
        .gravity
        .as_ref()
        .is_some_and(|g| g.acceleration.iter().any(|&a| a != 0.0));
    let loads = s.point_loads.iter().any(|l| l.force.iter().any(|&f| f != 0.0))
        || s.tractions.iter().any(|t| t.traction.iter().any(|&f| f != 0.0));
    if !gravity && !loads && s.motions.is_empty() {
        return r.bad(
            if s.gravity.is_some() {
                "gravity.acceleration"
            } else {
                "gravity"
            },
            "the scene applies no load (no gravity, no non-zero point load, no motion): its \
             static state is the state it starts in; add gravity, point_loads or motions"
                .into(),
        );
    }
    Ok(())
}

/// The time step: the critical one of the materials bodies use, and the scheme's limits.
fn time_step(r: &Rules, table: &[(String, MaterialModel)]) -> Result<StepChoice, SceneError> {
    let s = &r.loaded.scene;
    // Only materials that bodies use set the time step: a stiff material kept in a scene
    // for later would otherwise make every run take more steps for nothing.
    let used = |name: &str| s.bodies.iter().any(|b| b.material == name);
    // With mass scaling the slowest material sets the step; the others are given inertia.
    let speeds = table
        .iter()
        .filter(|(name, _)| used(name))
        .map(|(_, m)| (m.p_wave_modulus() / m.density()).sqrt());
    let c_p = if s.solver.mass_scaling {
        speeds.fold(f64::INFINITY, f64::min)
    } else {
        speeds.fold(0.0f64, f64::max)
    };
    let unused_materials = table
        .iter()
        .filter(|(name, _)| !used(name))
        .map(|(name, _)| name.clone())
        .collect();
    let dt_crit = s.grid.cell_size / c_p;
    if !positive(dt_crit) {
        return r.bad(
            "grid.cell_size",
            format!(
                "the critical time step h/c_p = {} m / {c_p} m/s = {dt_crit} s is not a finite number > 0",
                s.grid.cell_size
            ),
        );
    }
    let dt = match s.solver.time_step {
        TimeStep::Fixed(dt) => {
            if !positive(dt) {
                return r.bad(
                    "solver.time_step",
                    format!("Fixed(Δt) needs Δt > 0 s, found {dt}"),
                );
            }
            if dt > dt_crit {
                return r.bad(
                    "solver.time_step",
                    format!(
                        "Δt = {dt} s is above the critical step h/c_p = {dt_crit:.6} s (c_p = {c_p:.4} m/s) \
                         by {:.1} %: the explicit scheme would be unstable",
                        100.0 * (dt / dt_crit - 1.0)
                    ),
                );
            }
            dt
        }
        TimeStep::Courant(a) => {
            if !(positive(a) && a <= 1.0) {
                return r.bad(
                    "solver.time_step",
                    format!("Courant(α) needs 0 < α ≤ 1, found {a}"),
                );
            }
            a * dt_crit
        }
    };
    if s.solver.mass_scaling && dt > MASS_SCALING_COURANT_LIMIT * dt_crit * (1.0 + 1e-12) {
        return r.bad(
            "solver.time_step",
            format!(
                "Δt = {dt:.6e} s is Courant {:.3} of the slowest material; with mass scaling the \
                 nodes where stiff and soft points meet diverge above Courant {MASS_SCALING_COURANT_LIMIT} \
                 (docs/verification.md): use Courant({MASS_SCALING_COURANT_LIMIT}) or less",
                dt / dt_crit
            ),
        );
    }
    if s.solver.scheme == Scheme::Usl && dt > USL_COURANT_LIMIT * dt_crit * (1.0 + 1e-12) {
        return r.bad(
            "solver.time_step",
            format!(
                "Δt = {dt:.6e} s is Courant {:.3}; USL is unstable above Courant {USL_COURANT_LIMIT} \
                 (it diverges or never settles there, see docs/verification.md): use \
                 Courant({USL_COURANT_LIMIT}) or less, or scheme Musl or Usf, which are stable up to 1",
                dt / dt_crit
            ),
        );
    }
    // Explicit viscous damping scales a node's velocity by (1 − 2βΔt) each step: above
    // βΔt = 1 that factor is below −1 and the velocities grow without bound.
    if let crate::state::Damping::Viscous { beta } = s.solver.damping {
        if beta * dt > 1.0 {
            return r.bad(
                "solver.damping",
                format!(
                    "viscous β = {beta:e} 1/s with Δt = {dt:.6e} s gives βΔt = {:.3e}: explicit viscous \
                     damping is unstable above βΔt = 1; use β ≤ {:.6e} 1/s",
                    beta * dt,
                    1.0 / dt
                ),
            );
        }
    }
    // A time step that rounds to zero or to a subnormal never advances the clock: the run
    // would write history rows for ever without getting anywhere.
    if !dt.is_normal() {
        return r.bad(
            "solver.time_step",
            format!("gives Δt = {dt:e} s, too small to advance the simulated time"),
        );
    }
    if let (Some(t), None) = (s.solver.max_time, s.solver.max_steps) {
        let steps = t / dt;
        if steps > MAX_IMPLIED_STEPS {
            return r.bad(
                "solver.max_time",
                format!(
                    "{t} s at Δt = {dt:e} s is {steps:.3e} steps (more than {MAX_IMPLIED_STEPS:e}): \
                     set max_steps as well, or a shorter max_time"
                ),
            );
        }
    }
    Ok(StepChoice {
        p_wave_speed: c_p,
        critical: dt_crit,
        dt,
        unused_materials,
    })
}

/// The stages: each material, load, face condition and gravity they set.
fn check_stages(r: &Rules, table: &[(String, MaterialModel)], c_p: f64) -> Result<StageModels, SceneError> {
    let (loaded, s, n) = (r.loaded, &r.loaded.scene, r.n);
    let mut built = Vec::with_capacity(s.stages.len());
    for (k, st) in s.stages.iter().enumerate() {
        let mut models = Vec::with_capacity(st.materials.len());
        for (name, spec) in &st.materials {
            if !s.materials.contains_key(name) {
                return r.bad(
                    &format!("stages[{k}].materials"),
                    format!("\"{name}\" is not a material of the scene: a stage replaces one"),
                );
            }
            let at = |f: &str| format!("stages[{k}].materials.{name}.{f}");
            let model = spec
                .model(&at)
                .map_err(|(field, rule)| loaded.invalid(&field, rule))?;
            // A point carries one model's state for the whole run.
            if let Some(carried) = carried_state(loaded, table, name) {
                if let (Some(a), Some(b)) = (carried.state_name(), model.state_name()) {
                    if a != b {
                        return r.bad(
                            &format!("stages[{k}].materials.{name}"),
                            format!(
                                "{} has another internal state than {}, which \"{name}\" takes \
                                 in the scene or an earlier stage: a stage may change a material \
                                 to a model with the same state, or with none",
                                model.name(),
                                carried.name()
                            ),
                        );
                    }
                }
            }
            let speed = (model.p_wave_modulus() / model.density()).sqrt();
            if speed > c_p * (1.0 + 1e-12) {
                return r.bad(
                    &at("youngs_modulus"),
                    format!(
                        "a P-wave speed of {speed:.6} m/s, above the {c_p:.6} m/s that set the time \
                         step: the explicit scheme would be unstable in this stage; give the \
                         stiffest stage's material to the scene"
                    ),
                );
            }
            let id = table.iter().position(|(n, _)| n == name).expect("checked above");
            models.push((id as u16, model));
        }
        built.push(models);
        for (name, force) in &st.point_loads {
            if !s.point_loads.iter().any(|l| l.name == *name) {
                return r.bad(
                    &format!("stages[{k}].point_loads"),
                    format!("\"{name}\" is not a point load of the scene"),
                );
            }
            r.len(&format!("stages[{k}].point_loads.{name}"), force.len())?;
            r.finite(&format!("stages[{k}].point_loads.{name}"), force, "N")?;
        }
        for (name, traction) in &st.tractions {
            let field = format!("stages[{k}].tractions.{name}");
            match s.tractions.iter().find(|t| t.name == *name) {
                None => return r.bad(&field, format!("\"{name}\" is not a traction of the scene")),
                Some(t) if t.increments.is_some() => {
                    return r.bad(
                        &field,
                        "this traction is applied in increments: a stage cannot set it too".into(),
                    )
                }
                Some(_) => {}
            }
            r.len(&field, traction.len())?;
            r.finite(&field, traction, "Pa")?;
        }
        if let Some(b) = &st.boundaries {
            check_faces(b, &format!("stages[{k}].boundaries"), n)
                .map_err(|(field, rule)| loaded.invalid(&field, rule))?;
        }
        if let Some(g) = &st.gravity {
            if s.gravity.is_none() {
                return r.bad(
                    &format!("stages[{k}].gravity"),
                    "the scene has no gravity: give it one (even [0, 0]) for a stage to change".into(),
                );
            }
            r.len(&format!("stages[{k}].gravity.acceleration"), g.acceleration.len())?;
            r.finite(
                &format!("stages[{k}].gravity.acceleration"),
                &g.acceleration,
                "m/s²",
            )?;
            if !non_negative(g.ramp_time) {
                return r.bad(&format!("stages[{k}].gravity.ramp_time"), "must be ≥ 0 s".into());
            }
        }
        if st.reset_displacements && !s.output.displacements {
            return r.bad(
                &format!("stages[{k}].reset_displacements"),
                "needs the displacements kept (output.displacements: true)".into(),
            );
        }
    }
    Ok(built)
}

/// The memory bound against what the process may have.
fn check_memory(r: &Rules, table: &[(String, MaterialModel)]) -> Result<Estimate, SceneError> {
    let loaded = r.loaded;
    let estimate = estimate(loaded, table)?;
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
    Ok(estimate)
}
