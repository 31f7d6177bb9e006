//! Building a simulation from a valid scene: grid nodes, material points, loads, tracing
//! and the schedule. Only what the scene uses is created.

use super::initial_stress::{Ground, Layer};
use super::loaded::{place_text, LoadedScene};
use super::region::{cell_span, region_bounds, region_contains, BodyPoint};
use super::spec::{pad3, Dimension, Region, Scene, SolverSpec};
use super::validate::{self, carried_state, Checked, CheckedGrid, CheckedStage, Derived};
use crate::components::*;
use crate::context::{node_window, spawn_nodes, Context};
use crate::dim::{Dim, Dim2, Dim3, DimAxi, Vector};
use crate::error::SceneError;
use crate::grid::Grid;
use crate::infra::columns::fill;
use crate::infra::decomposition::{Decomposition, Split, ACROSS, SLAB};
use crate::materials::{MaterialModel, MaterialState, StateVisitor};
use crate::model::{node_fixity, Control, Gravity, LoadStage, Model, MotionSpec};
use crate::parallel::SlabCache;
use crate::rigid::{RigidBody, Samples};
use crate::shape::{for_each_node, Linear, QuadraticBSpline, ShapeKind, UniformGimp};
use crate::simulation::{AnySimulation, Simulation, TracedPoint};
use crate::state::{Numerics, SolverState};
use crate::systems::spatial_sort::sort_points;
use crate::systems::{check_names, default_names, schedule_from_names, Needs};
use hecs::{ColumnBatchBuilder, ColumnBatchType, Entity, World};

/// Validates the scene and builds its simulation with its schedule (the default one for its
/// settings unless `solver.schedule` names the systems).
pub fn build(loaded: &LoadedScene) -> Result<(AnySimulation, Derived), SceneError> {
    build_part(loaded, None)
}

/// One MPI rank's part of a scene: which rank of how many.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RankPart {
    /// The run's rank count (≥ 1).
    pub ranks: usize,
    /// This rank (< `ranks`).
    pub rank: usize,
    /// The parts along the slab axis and the second split axis, whose product is `ranks`;
    /// `None`: [`Decomposition::split_for`]'s choice.
    pub split: Option<Split>,
}

/// [`build`], spawning only the points of `part`'s cell layers when a part is given: the
/// split ([`Decomposition::balanced`]) comes from the layer counts of every body's points,
/// found from the bodies' regions without spawning them, so a rank holds its own points
/// only, from set-up on. Everything global (ids, the nodes the points touch, the points a
/// traction loads, traced points, the initial energy) is found over every point, so each
/// rank's part is the one-rank build's cut to its layers.
pub fn build_part(
    loaded: &LoadedScene,
    part: Option<RankPart>,
) -> Result<(AnySimulation, Derived), SceneError> {
    let checked = validate::check(loaded)?;
    Ok(match loaded.scene.dimension {
        Dimension::Two => {
            let (sim, d) = build_dim::<Dim2>(loaded, checked, part)?;
            (AnySimulation::Two(sim), d)
        }
        Dimension::Axisymmetric => {
            let (sim, d) = build_dim::<DimAxi>(loaded, checked, part)?;
            (AnySimulation::Axi(sim), d)
        }
        Dimension::Three => {
            let (sim, d) = build_dim::<Dim3>(loaded, checked, part)?;
            (AnySimulation::Three(sim), d)
        }
    })
}

/// Calls `f(node, w)` over the support of `x` with the scene's shape functions.
fn visit_support<D: Dim>(grid: &Grid<D>, shape: ShapeKind, x: D::Vec, mut f: impl FnMut(usize, f64)) {
    match shape {
        ShapeKind::Linear => for_each_node::<D, Linear>(grid, x, |i, w, _| f(i, w)),
        ShapeKind::QuadraticBSpline => for_each_node::<D, QuadraticBSpline>(grid, x, |i, w, _| f(i, w)),
        ShapeKind::UniformGimp => for_each_node::<D, UniformGimp>(grid, x, |i, w, _| f(i, w)),
    }
}

/// Positions of the points filling `region`: centres of equal sub-cells of every grid cell,
/// generated on demand (a body of a million points is never held twice in memory).
fn fill_points<'a, D: Dim>(
    grid: &Grid<D>,
    region: &'a Region,
    ppc: &[usize],
    rigid: &'a [crate::rigid::RigidBodySpec],
) -> impl Iterator<Item = [f64; 3]> + Clone + 'a {
    let n = D::N;
    let (lo, hi) = region_bounds(region, n);
    let mut range = [(0usize, 1usize); 3];
    for a in 0..n {
        range[a] = cell_span(lo[a], hi[a], grid.origin.get(a), grid.inv_h, grid.axes[a].cells);
    }
    let sub = [ppc[0], ppc[1], if n == 3 { ppc[2] } else { 1 }];
    let o = D::vec_to3(grid.origin);
    let h = grid.cell_size;
    // Along each axis: cell index and sub-cell index, flattened.
    let along = move |a: usize| (range[a].0 * sub[a]..range[a].1 * sub[a]).map(move |q| (q, a));
    let coordinate = move |(q, a): (usize, usize)| {
        o[a] + h * ((q / sub[a]) as f64 + ((q % sub[a]) as f64 + 0.5) / sub[a] as f64)
    };
    along(2).flat_map(move |z| {
        along(1).flat_map(move |y| {
            along(0).filter_map(move |x| {
                let z = if n == 3 { coordinate(z) } else { 0.0 };
                let p = [coordinate(x), coordinate(y), z];
                // A rigid body stands where it is put: no point has its centre in or on one.
                let solid = rigid.iter().any(|b| b.distance(p, n).0 <= 0.0);
                (region_contains(region, p, n) && !solid).then_some(p)
            })
        })
    })
}

/// Adds the column of a material's state to a point batch (none for a model without one).
struct AddState<'a>(&'a mut ColumnBatchType);

impl StateVisitor for AddState<'_> {
    fn visit<S: MaterialState>(&mut self) {
        if std::mem::size_of::<S>() > 0 {
            self.0.add::<S>();
        }
    }
}

/// Fills a batch's column of a material's state with `count` default (initial) states.
struct FillState<'a>(&'a ColumnBatchBuilder, usize);

impl StateVisitor for FillState<'_> {
    fn visit<S: MaterialState>(&mut self) {
        fill(self.0, std::iter::repeat_n(S::default(), self.1));
    }
}

/// An iterator that knows its length, so that `spawn_batch` reserves the columns once.
#[derive(Clone)]
struct Counted<I> {
    inner: I,
    left: usize,
}

impl<I: Iterator> Iterator for Counted<I> {
    type Item = I::Item;
    fn next(&mut self) -> Option<I::Item> {
        let item = self.inner.next()?;
        self.left -= 1;
        Some(item)
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.left, Some(self.left))
    }
}

impl<I: Iterator> ExactSizeIterator for Counted<I> {}

/// The scene's stages with what the check built (`checked`: materials and faces) and their
/// loads by carrier id (`load_ids`).
fn stages(
    loaded: &LoadedScene,
    checked: Vec<CheckedStage>,
    load_ids: &[(String, u32)],
    shares: &[(String, Vec<super::tractions::Share>)],
) -> Vec<LoadStage> {
    let mut out = Vec::new();
    for (
        st,
        CheckedStage {
            materials,
            faces,
            water,
        },
    ) in loaded.scene.stages.iter().zip(checked)
    {
        let mut loads: Vec<(u32, [f64; 3])> = st
            .point_loads
            .iter()
            .map(|(name, f)| {
                let id = load_ids.iter().find(|(n, _)| n == name).expect("validated").1;
                (id, pad3(f))
            })
            .collect();
        for (name, t) in &st.tractions {
            let points = &shares.iter().find(|(n, _)| n == name).expect("validated").1;
            let spec = loaded
                .scene
                .tractions
                .iter()
                .find(|s| s.name == *name)
                .expect("validated");
            loads.extend(
                points
                    .iter()
                    .map(|p| (p.id, spec.load_at(t, p.normal).map(|c| c * p.share))),
            );
        }
        loads.sort_by_key(|l| l.0);
        let gravity = st.gravity.as_ref().map(|g| Gravity {
            acceleration: pad3(&g.acceleration),
            ramp_time: g.ramp_time,
            start: 0.0,
        });
        out.push(LoadStage {
            faces,
            gravity,
            name: st.name.clone(),
            materials,
            loads,
            water,
            reset_displacements: st.reset_displacements,
        });
    }
    out
}

/// The scene's rigid bodies as the run takes them, with their contact `samples`: a body
/// under load control without a mass of its own gets the mass of the soil it displaces
/// (its volume in the grid times the densest material's density, at least one cell's worth).
fn loaded_bodies<D: Dim>(
    s: &Scene,
    grid: &Grid<D>,
    table: &[(String, MaterialModel)],
    samples: Vec<Samples>,
) -> Vec<RigidBody> {
    let density = table.iter().map(|(_, m)| m.density()).fold(0.0, f64::max);
    let h = grid.cell_size;
    let origin = D::vec_to3(grid.origin);
    let cells = std::array::from_fn(|a| grid.axes[a].cells);
    let mut bodies = s.rigid_bodies.clone();
    for b in &mut bodies {
        if b.load.as_ref().is_some_and(|l| l.mass.is_none()) {
            let volume = b.volume(D::N, D::AXISYMMETRIC, origin, h, cells);
            let cell = h.powi(D::N as i32) * if D::AXISYMMETRIC { h } else { 1.0 };
            if let Some(l) = b.load.as_mut() {
                l.mass = Some(density * volume.max(cell));
            }
        }
    }
    bodies
        .into_iter()
        .zip(samples)
        .map(|(b, s)| RigidBody::new(b, s))
        .collect()
}

/// The run's numerics from the scene's solver settings: the time step the check chose, and
/// the node-mass thresholds scaled by the mass of a full interior node (kg).
fn numerics(solver: &SolverSpec, dt: f64, full_node_mass: f64, initial_energy: f64) -> Numerics {
    Numerics {
        dt,
        scheme: solver.scheme,
        damping: solver.damping,
        tolerance: solver.tolerance,
        force_norm: solver.force_norm,
        max_steps: solver.max_steps,
        max_time: solver.max_time,
        static_check: solver.static_check,
        anti_locking: solver.anti_locking,
        sort_every: solver.sort_every,
        peak_interpolation: solver.peak_interpolation,
        flip: solver.flip,
        min_node_mass: solver.node_mass_cutoff * full_node_mass,
        virtual_mass_floor: solver.virtual_mass_floor * full_node_mass,
        contact_tolerance: solver.contact_tolerance,
        initial_energy,
    }
}

fn build_dim<D: Dim>(
    loaded: &LoadedScene,
    checked: Checked,
    part: Option<RankPart>,
) -> Result<(Simulation<D>, Derived), SceneError> {
    let Checked {
        grid: checked_grid,
        materials: table,
        stages: checked_stages,
        p_wave_speed: c_p,
        critical_time_step: dt_crit,
        time_step: dt,
        unused_materials,
        estimate,
        body_samples,
        water,
    } = checked;
    let s: &Scene = &loaded.scene;
    let grid = new_grid::<D>(&checked_grid);
    let mut world = World::new();
    let decomposition = split(s, &grid, part);
    // A rank numbers and stores only the nodes its part holds; set-up places points on the
    // whole grid.
    let nodes = grid.windowed(node_window(&grid, &decomposition));
    let fixity = node_fixity(&nodes, &checked_grid.faces, &s.motions);
    spawn_nodes::<D>(&mut world, fixity);
    let keep = |x: [f64; 3]| decomposition.holds(grid.split_cell(D::vec_from(x)));
    let Bodies {
        ids: body_ids,
        next_id,
        full_node_mass,
        initial_energy,
    } = spawn_bodies(
        loaded,
        &grid,
        &table,
        &every_water(&water, &checked_stages),
        &mut world,
        &keep,
    )?;
    let every = || every_point(s, &grid, &body_ids);
    let touched = touched_nodes(&grid, s.shape, every().map(|p| p.x));
    validate::check_motion_boxes(loaded, &grid, &touched)?;
    let (load_ids, point_count) = spawn_point_loads(loaded, &grid, &mut world, &touched, next_id, &keep)?;
    let placed = super::tractions::place::<D, _>(&mut world, loaded, every)?;

    // Bodies are filled row of points by row of points; cell order keeps the points that
    // share nodes together in memory from the first step.
    sort_points(&world, &grid).expect("set-up spawns only kdmpm components");
    let traced = find_traced::<D>(loaded, &world, every())?;

    let numerics = numerics(&s.solver, dt, full_node_mass, initial_energy);
    let model = Model {
        gravity: s.gravity.as_ref().map(|g| Gravity {
            acceleration: pad3(&g.acceleration),
            ramp_time: g.ramp_time,
            start: 0.0,
        }),
        water,
        motions: s.motions.clone(),
        bodies: loaded_bodies::<D>(s, &grid, &table, body_samples),
        friction_faces: checked_grid
            .faces
            .iter()
            .filter_map(|f| f.friction.map(|mu| (f.axis, f.upper, mu)))
            .collect(),
        faces: checked_grid.faces.clone(),
        stages: stages(loaded, checked_stages, &load_ids, &placed.shares),
        load_steps: placed.steps,
        pressures: placed.pressures,
        inertia_factors: if s.solver.mass_scaling {
            table
                .iter()
                .map(|(_, m)| ((m.p_wave_modulus() / m.density()) / (c_p * c_p)).max(1.0))
                .collect()
        } else {
            Vec::new()
        },
    };
    let schedule = schedule_of::<D>(loaded, &numerics, &model)?;
    let derived = Derived {
        p_wave_speed: c_p,
        critical_time_step: dt_crit,
        time_step: dt,
        points: point_count as usize,
        active_nodes: touched.iter().filter(|&&t| t).count(),
        grid_nodes: grid.node_count(),
        systems: schedule.names(),
        unused_materials,
        estimate,
        bodies: describe_bodies(&model.bodies),
        water: model.water.as_ref().map(|w| describe_water(s, w)),
    };
    let state = initial_state(s);
    let materials = table.into_iter().map(|(_, m)| m).collect();
    let ctx = Context {
        world,
        grid: nodes,
        materials,
        numerics,
        model,
        state,
        slabs: SlabCache::default(),
        comm: Default::default(),
        decomposition,
        exchanged: 0,
        point_grid_velocity: Vec::new(),
    };
    Ok((
        Simulation {
            ctx,
            schedule,
            traced,
            measure_surface_angle: s.output.surface_angle,
        },
        derived,
    ))
}

/// Every water the run will see (the scene's and each stage's that moves it), named by
/// field, to find the points below a surface at set-up.
fn every_water<'a>(
    water: &'a Option<crate::water::Water>,
    stages: &'a [CheckedStage],
) -> Vec<(String, &'a crate::water::Water)> {
    let mut waters = Vec::new();
    if let Some(w) = water {
        waters.push(("water.table".into(), w));
    }
    for (k, st) in stages.iter().enumerate() {
        if let Some(w) = &st.water {
            waters.push((format!("stages[{k}].water"), w));
        }
    }
    waters
}

/// The schedule the scene names (`solver.schedule`, checked against its settings) or the
/// default one for its settings.
fn schedule_of<D: Dim>(
    loaded: &LoadedScene,
    numerics: &Numerics,
    model: &Model,
) -> Result<crate::schedule::Schedule<D>, SceneError> {
    let s = &loaded.scene;
    let needs = Needs {
        point_loads: !s.point_loads.is_empty() || !s.tractions.is_empty(),
        undrained: s.every_material().any(|(_, m)| m.holds_water()),
    };
    let names: Vec<String> = match &s.solver.schedule {
        Some(names) => {
            check_names(names, numerics, model, needs)
                .map_err(|rule| loaded.invalid("solver.schedule", rule))?;
            names.clone()
        }
        None => default_names(numerics, model, needs)
            .into_iter()
            .map(String::from)
            .collect(),
    };
    Ok(schedule_from_names::<D>(&names, numerics, model, s.shape))
}

/// The solver's state before the first step: each motion's drive and each rigid body at
/// rest, set off at its stage.
fn initial_state(s: &Scene) -> SolverState {
    let stages: Vec<&str> = s.stages.iter().map(|t| t.name.as_str()).collect();
    SolverState {
        control: Control {
            drives: s.motions.iter().map(MotionSpec::drive).collect(),
            bodies: s
                .rigid_bodies
                .iter()
                .map(|b| b.state(b.first_stage(&stages)))
                .collect(),
            ..Control::default()
        },
        ..SolverState::default()
    }
}

/// Each rigid body as `kdmpm check` prints it: name, parts, its contact samples, control
/// and travel, and its filters.
fn describe_bodies(bodies: &[RigidBody]) -> Vec<String> {
    bodies
        .iter()
        .map(|RigidBody { spec: b, samples, .. }| {
            let samples = samples.len();
            let control = match (&b.motion, &b.load) {
                (Some(m), _) => format!(
                    "moves {} m at {:?} m/s in {} increment(s)",
                    m.travel,
                    m.velocity,
                    b.increments()
                ),
                (_, Some(l)) => format!("under a load of {:?} N in {} increment(s)", l.force, l.increments),
                _ => "holds its place".into(),
            };
            let filters = match b.filters.len() {
                0 => String::new(),
                k => format!(", {k} pore-pressure filter(s)"),
            };
            let cpt = match &b.cpt {
                Some(c) => format!(
                    ", logged as a piezocone (tip {:?}, sleeve {:?}, u2 {:?}) in cpt.csv",
                    c.tip, c.sleeve, c.u2
                ),
                None => String::new(),
            };
            let corners = match b.corners {
                crate::rigid::Corners::Held => "",
                crate::rigid::Corners::Released => ", corners released",
            };
            let surface = match b.soil_surface {
                crate::rigid::SoilSurface::Nodes => "",
                crate::rigid::SoilSurface::Points => ", soil's surface from its points",
            };
            format!(
                "\"{}\": {} part(s), {samples} contact samples, {:?} interface{corners}{surface}, {control}{filters}{cpt}",
                b.name,
                b.parts.len(),
                b.interface
            )
        })
        .collect()
}

/// The water as `kdmpm check` prints it: γ_w, gravity's axis and the stages that move it.
fn describe_water(s: &Scene, w: &crate::water::Water) -> String {
    let moved: Vec<&str> = s
        .stages
        .iter()
        .filter(|st| st.water.is_some())
        .map(|st| st.name.as_str())
        .collect();
    let stages = match moved.is_empty() {
        true => String::new(),
        false => format!("; moved by stages {moved:?}"),
    };
    format!(
        "γ_w {} N/m³, gravity along axis {}{stages}",
        w.unit_weight, w.axis
    )
}

/// The checked grid, with each axis's point half-width (uniform GIMP).
fn new_grid<D: Dim>(checked: &CheckedGrid) -> Grid<D> {
    let mut grid = Grid::<D>::new(D::vec_from(checked.origin), checked.cell_size, checked.cells);
    for (axis, &w) in grid.axes.iter_mut().zip(&checked.half_width) {
        axis.particle_half_width = w;
    }
    grid
}

/// The split of the scene's cells over `part`'s ranks (every cell on one rank without a
/// part), balanced on the points every body and point load puts in each layer along the
/// two split axes: the counts the spawned points would give, found from the regions alone.
fn split<D: Dim>(s: &Scene, grid: &Grid<D>, part: Option<RankPart>) -> Decomposition {
    let support = s.shape.support();
    let [slab_axis, across_axis] = [grid.slab_axis, grid.across_axis()];
    let layers = [slab_axis, across_axis].map(|a| grid.axes[a].cells);
    let Some(RankPart { ranks, rank, split }) = part.filter(|p| p.ranks > 1) else {
        return Decomposition::whole(layers[SLAB], layers[ACROSS], support);
    };
    let split = Decomposition::split_for(ranks, layers[SLAB], layers[ACROSS], support, split);
    let mut counts = layers.map(|n| vec![0u64; n]);
    let mut count = |x: [f64; 3]| {
        let c = grid.split_cell(D::vec_from(x));
        counts[SLAB][c[SLAB]] += 1;
        counts[ACROSS][c[ACROSS]] += 1;
    };
    for body in &s.bodies {
        fill_points(grid, &body.region, &body.points_per_cell, &s.rigid_bodies).for_each(&mut count);
    }
    s.point_loads.iter().for_each(|l| count(pad3(&l.position)));
    Decomposition::balanced([&counts[SLAB], &counts[ACROSS]], split, rank, support)
}

/// Every body's points in id order, regenerated from the regions (`ids`: each body's).
fn every_point<'a, D: Dim>(
    s: &'a Scene,
    grid: &'a Grid<D>,
    ids: &'a [std::ops::Range<u32>],
) -> impl Iterator<Item = BodyPoint> + 'a {
    s.bodies
        .iter()
        .zip(ids)
        .enumerate()
        .flat_map(move |(body, (b, ids))| {
            fill_points(grid, &b.region, &b.points_per_cell, &s.rigid_bodies)
                .zip(ids.clone())
                .map(move |(x, id)| BodyPoint { body, id, x })
        })
}

/// The ids of each body's points, the next free id and the mass ρ·h^D of a node inside the
/// lightest body, after spawning every body's points.
struct Bodies {
    ids: Vec<std::ops::Range<u32>>,
    next_id: u32,
    full_node_mass: f64,
    /// Strain energy the points' initial stress may give up, at most (J; J/m in 2D).
    initial_energy: f64,
}

/// Fills every body with points (refusing one outside the grid, one that overlaps an
/// earlier body and one with no point) and spawns those at places `keep` takes (a rank's
/// layers); ids and the figures of [`Bodies`] count every point.
fn spawn_bodies<D: Dim>(
    loaded: &LoadedScene,
    grid: &Grid<D>,
    table: &[(String, MaterialModel)],
    waters: &[(String, &crate::water::Water)],
    world: &mut World,
    keep: &dyn Fn([f64; 3]) -> bool,
) -> Result<Bodies, SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    // Mass of a node inside a filled region, ρ·h^D, for the lightest material in use.
    let mut full_node_mass = f64::INFINITY;
    let mut initial_energy = 0.0;
    let (gmin, gmax) = (D::vec_to3(grid.origin), D::vec_to3(grid.max_corner()));
    let mut next_id = 0u32;
    // The ids of each body's points (spawn order).
    let mut body_ids: Vec<std::ops::Range<u32>> = Vec::new();
    let ground = ground(loaded, table, waters);
    for (b, body) in s.bodies.iter().enumerate() {
        let (lo, hi) = region_bounds(&body.region, n);
        if (0..n).any(|a| lo[a] < gmin[a] - 1e-9 || hi[a] > gmax[a] + 1e-9) {
            return Err(loaded.invalid(
                &format!("bodies[{b}].region"),
                format!(
                    "the body spans {:?}..{:?}, outside the grid {:?}..{:?}",
                    &lo[..n],
                    &hi[..n],
                    &gmin[..n],
                    &gmax[..n]
                ),
            ));
        }
        let points = fill_points(grid, &body.region, &body.points_per_cell, &s.rigid_bodies);
        // Bodies may not overlap: a point inside two bodies would be two points, its mass
        // counted twice. Split the region or change one body's material instead.
        let earlier = &s.bodies[..b];
        let mut count = 0usize;
        for x in points.clone() {
            if let Some(o) = earlier.iter().position(|e| region_contains(&e.region, x, n)) {
                return Err(loaded.invalid(
                    &format!("bodies[{b}].region"),
                    format!(
                        "overlaps bodies[{o}] (at {:?}): bodies must not overlap, as a point in two \
                         bodies would count its mass twice",
                        &x[..n]
                    ),
                ));
            }
            count += 1;
        }
        let xs = Counted {
            left: count,
            inner: points.zip(next_id..),
        };
        if xs.left == 0 {
            return Err(loaded.invalid(
                &format!("bodies[{b}].region"),
                "the body holds no material point (is it smaller than a sub-cell?)",
            ));
        }
        let spawned = spawn_body::<D>(loaded, b, table, waters, &ground, world, xs, next_id, keep)?;
        full_node_mass = full_node_mass.min(spawned.full_node_mass);
        initial_energy += spawned.initial_energy;
        body_ids.push(next_id..spawned.next_id);
        next_id = spawned.next_id;
    }

    Ok(Bodies {
        ids: body_ids,
        next_id,
        full_node_mass,
        initial_energy,
    })
}

/// The ground a geostatic start is worked out from: every body, the scene's gravity (down
/// one axis, as the check requires of a geostatic start; axis 1 and no weight without such
/// gravity) and its water.
fn ground<'a>(
    loaded: &'a LoadedScene,
    table: &[(String, MaterialModel)],
    waters: &[(String, &'a crate::water::Water)],
) -> Ground<'a> {
    let s = &loaded.scene;
    let id = |name: &str| table.iter().position(|(n, _)| n == name).expect("validated");
    let layers = s
        .bodies
        .iter()
        .map(|body| {
            let m = id(&body.material);
            Layer {
                region: &body.region,
                material: m as u16,
                density: table[m].1.density(),
            }
        })
        .collect();
    let g = s.gravity.as_ref().map_or(&[][..], |g| g.acceleration.as_slice());
    let axis = crate::water::down_axis(g);
    Ground {
        layers,
        axis: axis.unwrap_or(1),
        gravity: axis.map_or(0.0, |a| g[a].abs()),
        water: waters.first().map(|(_, w)| *w),
        n: s.grid.cells.len(),
    }
}

/// What [`spawn_body`] spawned: the next free point id and the mass ρ·h^D of a node inside
/// the body.
struct Spawned {
    next_id: u32,
    full_node_mass: f64,
    initial_energy: f64,
}

/// Spawns those of body `b`'s points `all` (positions and ids from `first`, as many as
/// `all.left`) at places `keep` takes, as one column batch of its material's columns.
#[allow(clippy::too_many_arguments)]
fn spawn_body<D: Dim>(
    loaded: &LoadedScene,
    b: usize,
    table: &[(String, MaterialModel)],
    waters: &[(String, &crate::water::Water)],
    ground: &Ground,
    world: &mut World,
    all: Counted<impl Iterator<Item = ([f64; 3], u32)> + Clone>,
    first: u32,
    keep: &dyn Fn([f64; 3]) -> bool,
) -> Result<Spawned, SceneError> {
    let kept = all.clone().filter(|(x, _)| keep(*x));
    let xs = Counted {
        left: kept.clone().count(),
        inner: kept,
    };
    let count = xs.left;
    let s = &loaded.scene;
    let body = &s.bodies[b];
    let z = D::Vec::ZERO;
    let cell_volume = s.grid.cell_size.powi(D::N as i32);
    let mat = table
        .iter()
        .position(|(name, _)| *name == body.material)
        .expect("validated");
    let model = &table[mat].1;
    // The points carry the state of every model their material takes, from the start.
    let state = carried_state(loaded, table, &body.material).expect("validated");
    let volume = cell_volume / body.points_per_cell.iter().product::<usize>() as f64;
    // In axisymmetry a point's volume is per radian: its area times its radius.
    let vol_at = |x: [f64; 3]| if D::AXISYMMETRIC { volume * x[0] } else { volume };
    // Below its piezometric surface a point weighs its material's saturated density (by the
    // share of its height below the surface, for a point astride it).
    validate::check_saturated(
        loaded,
        waters,
        mat as u16,
        &body.material,
        all.clone().map(|(x, _)| (x, vol_at(x))),
    )?;
    let start = |x: [f64; 3]| match &body.initial_stress {
        Some(spec) => ground.stress(spec, mat as u16, x),
        None => crate::tensor::Sym3::ZERO,
    };
    let initial_energy = if body.initial_stress.is_some() {
        start_energy::<D>(loaded, b, model, all.clone().map(|(x, _)| x), start, &vol_at)?
    } else {
        0.0
    };
    let mass_at = |x: [f64; 3]| {
        let (v, rho) = (vol_at(x), model.density());
        match waters.first() {
            Some((_, w)) => rho * v * w.density_factor(mat as u16, x, v),
            None => rho * v,
        }
    };
    let next_id = u32::try_from(all.left)
        .ok()
        .and_then(|c| first.checked_add(c))
        .ok_or_else(|| {
            loaded.invalid(
                &format!("bodies[{b}].points_per_cell"),
                "more than 4 294 967 295 points in all",
            )
        })?;
    // One column batch: the columns every point has, then the optional ones, the
    // material's state only where it has one and displacements only when asked for.
    // A new point column is one more `add` and one fill here. The spawned entities are
    // not kept: points are found again through the columns, which keeps the set-up's
    // peak memory near the run's.
    let mut columns = ColumnBatchType::new();
    columns.add_bundle::<(
        PointId,
        Position<D::Vec>,
        Velocity<D::Vec>,
        Mass,
        Volume,
        Stress<D::Stress>,
        VelocityGradient<D::Mat>,
        MaterialId,
    )>();
    state.visit_state(&mut AddState(&mut columns));
    if s.output.displacements {
        columns.add::<Displacement<D::Vec>>();
    }
    if s.solver.static_check.is_some() {
        columns.add::<WindowStart<D::Vec>>();
    }
    let batch = columns.into_batch(count as u32);
    fill(&batch, xs.clone().map(|(_, id)| PointId(id)));
    fill(&batch, xs.clone().map(|(x, _)| Position(D::vec_from(x))));
    fill(&batch, xs.clone().map(|(x, _)| WindowStart(D::vec_from(x))));
    fill(&batch, std::iter::repeat_n(Velocity(z), count));
    fill(&batch, xs.clone().map(|(x, _)| Mass(mass_at(x))));
    fill(&batch, xs.clone().map(|(x, _)| Volume(vol_at(x))));
    fill(
        &batch,
        xs.map(|(x, _)| Stress(<D::Stress as crate::tensor::StoredSym>::from_sym3(&start(x)))),
    );
    fill(&batch, std::iter::repeat_n(VelocityGradient(D::MAT_ZERO), count));
    fill(&batch, std::iter::repeat_n(MaterialId(mat as u16), count));
    state.visit_state(&mut FillState(&batch, count));
    fill(&batch, std::iter::repeat_n(Displacement(z), count));
    world.spawn_column_batch(batch.build().expect("every column of the batch is filled"));
    // A full node's mass ρ h^D; per radian at r = h in axisymmetry, ρ h³.
    let radius = if D::AXISYMMETRIC { s.grid.cell_size } else { 1.0 };
    Ok(Spawned {
        next_id,
        full_node_mass: model.density() * cell_volume * radius,
        initial_energy,
    })
}

/// The strain energy body `b`'s points at places `xs` may give up from their start stresses
/// `start(x)` (Pa), of volume `vol_at(x)` (J; J/m in 2D), refusing a start its `model` may
/// not take (every rank asks of every point, so all refuse alike). A unit volume holds
/// p²/(2K) + q²/(6G), bounded by 3(p² + q²)/(2M) from the P-wave modulus M: K ≥ M/3 for
/// ν ≥ 0, and 6G ≥ 2M/3 for ν ≤ 0.42. The energy guard allows for it.
fn start_energy<D: Dim>(
    loaded: &LoadedScene,
    b: usize,
    model: &MaterialModel,
    xs: impl Iterator<Item = [f64; 3]>,
    start: impl Fn([f64; 3]) -> crate::tensor::Sym3,
    vol_at: impl Fn([f64; 3]) -> f64,
) -> Result<f64, SceneError> {
    let m = model.p_wave_modulus();
    let mut energy = 0.0;
    for x in xs {
        let stress = start(x);
        if let Some(fault) = model.start_fault(&stress) {
            return Err(loaded.invalid(
                &format!("bodies[{b}].initial_stress"),
                format!("{fault} (the point at {})", place_text(&x[..D::N])),
            ));
        }
        let (p, s) = stress.mean_and_deviatoric_norm();
        energy += 1.5 * (p * p + 1.5 * s * s) / m * vol_at(x);
    }
    Ok(energy)
}

/// Which nodes the points at places `xs` touch at the start.
fn touched_nodes<D: Dim>(grid: &Grid<D>, shape: ShapeKind, xs: impl Iterator<Item = [f64; 3]>) -> Vec<bool> {
    let mut touched = vec![false; grid.node_count()];
    for x in xs {
        visit_support(grid, shape, D::vec_from(x), |i, w| touched[i] |= w > 0.0);
    }
    touched
}

/// Spawns the point loads' carriers, massless points that move with the body, from id
/// `next_id` on, those at places `keep` takes; returns each load's name and id, and the
/// next free id.
fn spawn_point_loads<D: Dim>(
    loaded: &LoadedScene,
    grid: &Grid<D>,
    world: &mut World,
    touched: &[bool],
    mut next_id: u32,
    keep: &dyn Fn([f64; 3]) -> bool,
) -> Result<(Vec<(String, u32)>, u32), SceneError> {
    let s = &loaded.scene;
    let z = D::Vec::ZERO;
    let mut load_ids = Vec::new();
    for (i, l) in s.point_loads.iter().enumerate() {
        let x = D::vec_from(pad3(&l.position));
        if !grid.contains(x) {
            return Err(loaded.invalid(
                &format!("point_loads[{i}].position"),
                "the load lies outside the grid",
            ));
        }
        let mut on_body = false;
        visit_support(grid, s.shape, x, |node, w| on_body |= w > 0.0 && touched[node]);
        if !on_body {
            return Err(loaded.invalid(
                &format!("point_loads[{i}].position"),
                format!(
                    "load \"{}\" acts on no node that carries mass: put it on a body",
                    l.name
                ),
            ));
        }
        load_ids.push((l.name.clone(), next_id));
        let id = next_id;
        next_id = next_id.checked_add(1).ok_or_else(|| {
            loaded.invalid(
                &format!("point_loads[{i}]"),
                "more than 4 294 967 295 points in all",
            )
        })?;
        if !keep(pad3(&l.position)) {
            continue;
        }
        let carrier = world.spawn((
            PointId(id),
            Position(x),
            Velocity(z),
            Mass(0.0),
            VelocityGradient(D::MAT_ZERO),
            PointLoad(D::vec_from(pad3(&l.force))),
        ));
        if s.output.displacements {
            world.insert_one(carrier, Displacement(z)).expect("just spawned");
        }
        if s.solver.static_check.is_some() {
            world.insert_one(carrier, WindowStart(x)).expect("just spawned");
        }
    }

    Ok((load_ids, next_id))
}

/// The traced points: the nearest point within one cell of each position asked for.
fn find_traced<D: Dim>(
    loaded: &LoadedScene,
    world: &World,
    every: impl Iterator<Item = BodyPoint>,
) -> Result<Vec<TracedPoint>, SceneError> {
    let s = &loaded.scene;
    let n = D::N;
    let wanted: Vec<[f64; 3]> = s.traced.iter().map(|t| pad3(&t.position)).collect();
    let dist = |x: &[f64; 3], want: &[f64; 3]| (0..3).map(|a| (x[a] - want[a]).powi(2)).sum::<f64>().sqrt();
    // The nearest of every body's points to each place, the first made on a tie (the same on
    // every rank, held by one of them), in one pass over the points.
    let mut best: Vec<Option<(f64, BodyPoint)>> = vec![None; wanted.len()];
    for p in every {
        for (b, want) in best.iter_mut().zip(&wanted) {
            let d = dist(&p.x, want);
            if b.is_none_or(|(e, _)| d.total_cmp(&e).is_lt()) {
                *b = Some((d, p));
            }
        }
    }
    let mut traced = Vec::new();
    for (i, (t, b)) in s.traced.iter().zip(best).enumerate() {
        match b {
            Some((d, p)) if d <= s.grid.cell_size => traced.push(TracedPoint {
                name: t.name.clone(),
                id: PointId(p.id),
                entity: crate::simulation::find_point(world, PointId(p.id)).unwrap_or(Entity::DANGLING),
                initial_position: p.x,
            }),
            _ => {
                return Err(loaded.invalid(
                    &format!("traced[{i}].position"),
                    format!(
                        "no material point within one cell ({} m) of {:?}",
                        s.grid.cell_size,
                        &wanted[i][..n]
                    ),
                ))
            }
        }
    }

    Ok(traced)
}
