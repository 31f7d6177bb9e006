//! The model a run solves, as set-up hands it over: the gravity, the water, the rigid
//! bodies, the prescribed motions, the stages and the loads under control, each checked by
//! its own module; and what their control keeps through the run ([`Control`]). The
//! numerics that solve it are [`crate::state::Numerics`].

use crate::components::NodeFixity;
use crate::dim::Dim;
use crate::error::Refusal;
use crate::grid::Grid;
use crate::materials::MaterialModel;
use serde::{Deserialize, Serialize};

/// What the scene puts in the ground and how it is driven, fixed for the run but for what
/// a loading stage changes (the gravity and the water).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// Gravity, if any.
    pub gravity: Option<Gravity>,
    /// The water table, if any.
    pub water: Option<crate::water::Water>,
    /// Prescribed motions (displacement control), in scene order.
    pub motions: Vec<MotionSpec>,
    /// Rigid bodies, in scene order.
    pub bodies: Vec<crate::rigid::RigidBody>,
    /// The scene's `Friction` faces: (normal axis, upper face, tan δ).
    pub friction_faces: Vec<(usize, bool, f64)>,
    /// The face conditions in force: the scene's, then those of the last stage that set
    /// any.
    pub faces: Vec<FaceHold>,
    /// Loading stages, in order; the first is the scene as built.
    pub stages: Vec<LoadStage>,
    /// Loads applied in increments (load control), each increment to its static stop.
    pub load_steps: Vec<LoadSteps>,
    /// The points whose traction is a pressure that follows the surface.
    pub pressures: crate::surface_pressure::SurfacePressures,
    /// Mass scaling's inertia factor s_m of each material, by
    /// [`MaterialId`](crate::components::MaterialId); empty without mass scaling.
    pub inertia_factors: Vec<f64>,
}

impl Model {
    /// The held axes of every node `grid` numbers under the face conditions in force and
    /// the motions ([`node_fixity`]).
    pub fn node_fixity<D: Dim>(&self, grid: &Grid<D>) -> Vec<NodeFixity> {
        node_fixity(grid, &self.faces, &self.motions)
    }

    /// True when the scene asked for mass scaling (`solver.mass_scaling`).
    pub fn mass_scaling(&self) -> bool {
        !self.inertia_factors.is_empty()
    }

    /// The kinetic energy of the model's own masses, beside the points' (J; J/m in 2D;
    /// J/rad axisymmetric): what a kinetic-damping peak watch counts with the soil's.
    pub fn kinetic_energy(&self, control: &Control) -> f64 {
        (self.bodies.iter().zip(&control.bodies))
            .map(|(body, b)| body.spec.kinetic_energy(b))
            .sum()
    }

    /// Sets off what waits for the stage named `stage` to begin (the rigid bodies whose
    /// motion or load starts with it).
    pub fn start_stage(&self, stage: &str, control: &mut Control) {
        for (body, b) in self.bodies.iter().zip(&mut control.bodies) {
            if body.spec.stage().is_some_and(|s| s == stage) {
                body.spec.set_off(b);
            }
        }
    }
}

/// The held axes of every node `grid` numbers: the face conditions `faces`, and the nodes of
/// `motions` driven on their axes (a node in a motion's box keeps its face conditions on the
/// other axes: a footing on a symmetry plane keeps its roller). Set-up, a stage's faces and
/// a new window of a rank all take it from here.
pub fn node_fixity<D: Dim>(grid: &Grid<D>, faces: &[FaceHold], motions: &[MotionSpec]) -> Vec<NodeFixity> {
    let mut fixity = vec![NodeFixity(0); grid.node_count()];
    for (id, f) in fixity.iter_mut().enumerate() {
        let ijk = grid.node_ijk(id);
        for face in faces {
            let layer = if face.upper { grid.axes[face.axis].cells } else { 0 };
            if ijk[face.axis] == layer {
                f.0 |= face.mask;
                if face.friction.is_some() {
                    f.0 |= NodeFixity::FRICTION;
                }
            }
        }
        if motions.is_empty() {
            continue;
        }
        let x = D::vec_to3(grid.node_position(ijk));
        for (k, m) in motions.iter().enumerate() {
            if m.holds_node(x, D::N, grid.cell_size) {
                *f = NodeFixity::driven(f.0 | m.drive().axes, k);
            }
        }
    }
    fixity
}

/// Gravity acting on all points (m/s²), applied at once or ramped linearly.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gravity {
    /// Full gravitational acceleration (m/s², x y z).
    pub acceleration: [f64; 3],
    /// Time over which it rises linearly from zero (s); 0 applies it at once.
    pub ramp_time: f64,
    /// When the ramp starts (s): 0, or the start of the loading stage that set it.
    pub start: f64,
}

impl Gravity {
    /// The fraction of full gravity at time `t` (s).
    pub fn factor(&self, t: f64) -> f64 {
        if self.ramp_time > 0.0 {
            ((t - self.start) / self.ramp_time).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// The fraction of full gravity applied in the step that ends at `time` (s): the load
    /// of a step acts over [t − Δt, t], so a ramp uses its start.
    pub fn step_factor(&self, time: f64, dt: f64) -> f64 {
        self.factor(time - dt)
    }
}

/// A load applied in equal increments, each relaxed to its static state and recorded as a
/// row of the load–displacement curve.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadSteps {
    /// Name given in the scene.
    pub name: String,
    /// The points that carry it (ids) and the force each carries at full load (N; N/m in
    /// 2D, x y z).
    pub points: Vec<(u32, [f64; 3])>,
    /// Number of increments.
    pub increments: u32,
    /// The full load as a pressure (Pa): the traction's size.
    pub pressure: f64,
}

/// One face condition, as the nodes on that face carry it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceHold {
    /// The face's normal axis.
    pub axis: usize,
    /// The upper face (x = max) rather than the lower (x = origin).
    pub upper: bool,
    /// The held velocity components, one bit an axis (`NodeFixity`'s low bits): every axis
    /// for `Fixed`, the normal one for `Roller` and `Friction`.
    pub mask: u8,
    /// tan δ of a `Friction` face.
    pub friction: Option<f64>,
}

/// A loading stage: what changes when it begins; it runs to the static stop.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadStage {
    /// Name given in the scene.
    pub name: String,
    /// Materials it replaces, by material index.
    pub materials: Vec<(u16, MaterialModel)>,
    /// Point loads it sets (carriers' and traction points'), by point id in ascending
    /// order (force: N; N/m in 2D, x y z).
    pub loads: Vec<(u32, [f64; 3])>,
    /// The face conditions it sets, in place of those in force.
    pub faces: Option<Vec<FaceHold>>,
    /// Gravity it sets (its ramp starts with the stage).
    pub gravity: Option<Gravity>,
    /// The water it sets (its surfaces), if it moves it.
    pub water: Option<crate::water::Water>,
    /// Zero every point's accumulated displacement when it begins (after a geostatic stage).
    pub reset_displacements: bool,
}

/// The static state that ended a stage (`stages.csv`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StageResult {
    /// The stage.
    pub name: String,
    /// Step of its static state.
    pub step: u64,
    /// Simulated time (s).
    pub time: f64,
    /// K_F (the stopping rule's norm) and K_E at the end.
    pub force_ratio: f64,
    /// K_E at the end.
    pub energy_ratio: f64,
    /// Kinetic-damping resets so far.
    pub resets: u64,
}

/// A prescribed motion of grid nodes: the velocity its nodes are held at and the force
/// they exert on the body. The system that drives it (`systems::prescribed_motion`) sets
/// the velocity; `boundary` holds the nodes to it and sums the reaction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Drive {
    /// Name given in the scene.
    pub name: String,
    /// The axes the motion drives (bit `a` for axis `a`); its nodes' other held axes are
    /// fixed by a face condition.
    pub axes: u8,
    /// Velocity of the driven components this step (m/s, x y z; zero while holding).
    pub velocity: [f64; 3],
    /// Force the driven nodes exert on the body this step, Σ −(f_int + f_ext) over their
    /// driven components (N; N per metre of thickness in 2D).
    pub reaction: [f64; 3],
    /// Distance travelled along the motion so far (m).
    pub travel: f64,
    /// Increments finished, each ending at a static state.
    pub increments: u32,
}

/// A prescribed motion of grid nodes (`motions: [...]` in a scene), driven by
/// `systems::prescribed_motion`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    /// Name: `curve.csv` rows and `history.csv` columns carry it.
    pub name: String,
    /// Lower corner of the box of driven nodes (m).
    pub min: Vec<f64>,
    /// Upper corner of the box of driven nodes (m); nodes on its faces are inside.
    pub max: Vec<f64>,
    /// Velocity per axis (m/s); `None` leaves that axis free (a smooth footing moves
    /// only vertically).
    pub velocity: Vec<Option<f64>>,
    /// Distance to travel along the velocity (m).
    pub travel: f64,
    /// Distance of one increment (m), each ending at a static state: a row of
    /// `curve.csv`. Default: the whole travel in one.
    #[serde(default)]
    pub increment: Option<f64>,
    /// Loaded area (m²; m per metre of thickness in 2D), for the mean pressure in
    /// `curve.csv` and `limit_pressure` in summary.json.
    #[serde(default)]
    pub area: Option<f64>,
}

impl MotionSpec {
    /// The velocity as a vector (m/s, x y z; free axes 0).
    pub fn vector(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.velocity.get(a).copied().flatten().unwrap_or(0.0))
    }

    /// True when a node at `x` (m, x y z) is one the motion drives, in a scene of `n`
    /// dimensions with cells of `h` (m): on or inside its box, to a billionth of a cell.
    pub fn holds_node(&self, x: [f64; 3], n: usize, h: f64) -> bool {
        let slack = 1e-9 * h;
        (0..n).all(|a| x[a] >= self.min[a] - slack && x[a] <= self.max[a] + slack)
    }

    /// Speed along the motion (m/s).
    pub fn speed(&self) -> f64 {
        self.vector().iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// The motion's state at the start of a run: moving.
    pub fn drive(&self) -> Drive {
        Drive {
            name: self.name.clone(),
            axes: self
                .velocity
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_some())
                .fold(0, |mask, (a, _)| mask | 1 << a),
            velocity: self.vector(),
            ..Drive::default()
        }
    }

    /// Checks the fields for a scene of `dimension`: or the [`Refusal`] of the field.
    pub fn check(&self, dimension: usize) -> Result<(), Refusal> {
        for (field, v) in [("min", &self.min), ("max", &self.max)] {
            if v.len() != dimension {
                return Err(Refusal::new(
                    field,
                    format!("needs {dimension} entries, one per axis"),
                ));
            }
        }
        for (field, v) in [("min", &self.min), ("max", &self.max)] {
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(Refusal::new(
                    field,
                    format!("entry {k} must be a finite coordinate (m), found {}", v[k]),
                ));
            }
        }
        if self.min.iter().zip(&self.max).any(|(lo, hi)| lo > hi) {
            return Err(Refusal::new("max", "every entry must be at least min's".into()));
        }
        if self.velocity.len() != dimension {
            return Err(Refusal::new(
                "velocity",
                format!("needs {dimension} entries (Some(m/s) or None)"),
            ));
        }
        if self.velocity.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Refusal::new("velocity", "must be finite".into()));
        }
        if self.speed() <= 0.0 {
            return Err(Refusal::new(
                "velocity",
                "must move: at least one entry Some and not zero".into(),
            ));
        }
        if !(self.travel.is_finite() && self.travel > 0.0) {
            return Err(Refusal::new("travel", "must be above 0 (m)".into()));
        }
        if let Some(inc) = self.increment {
            if !(inc.is_finite() && inc > 0.0 && inc <= self.travel) {
                return Err(Refusal::new(
                    "increment",
                    "must be above 0 and at most travel (m)".into(),
                ));
            }
        }
        if let Some(a) = self.area {
            if !(a.is_finite() && a > 0.0) {
                return Err(Refusal::new("area", "must be above 0".into()));
            }
        }
        Ok(())
    }
}

/// One static state of a load–displacement curve (`curve.csv`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Name of the motion or load.
    pub name: String,
    /// Step of the static state.
    pub step: u64,
    /// Simulated time (s).
    pub time: f64,
    /// Displacement along the motion (m).
    pub displacement: f64,
    /// Force on the body (N; N/m in 2D, x y z).
    pub force: [f64; 3],
    /// Mean pressure against the motion over the loaded area (Pa), when the scene gives
    /// the area (left out of summary.json otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
}

/// What the control systems keep: prescribed motions and their curve, stages, loads
/// under load control.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Control {
    /// Prescribed motions, in scene order (a node's [`NodeFixity::driver`]).
    ///
    /// [`NodeFixity::driver`]: crate::components::NodeFixity::driver
    pub drives: Vec<Drive>,
    /// Rigid bodies, in scene order.
    pub bodies: Vec<crate::rigid::BodyState>,
    /// The nodes in contact with a body this step, in node order (rebuilt each step by
    /// `rigid_contact` before anything reads it; not checkpointed).
    pub contacts: crate::rigid::contact::Contacts,
    /// Each contact's normal impulse at the end of the last step's `rigid_contact` solve,
    /// by key: the next one's warm start.
    pub contact_memory: crate::rigid::contact::Memory,
    /// Static states of the load–displacement curve so far.
    pub curve: Vec<CurvePoint>,
    /// The loading stage under way (index in [`Model::stages`]).
    pub stage: usize,
    /// Stages finished so far.
    pub stages: Vec<StageResult>,
    /// Increments each load under load control has finished ([`Model::load_steps`]).
    pub load_increments: Vec<u32>,
    /// True when a control system consumed a static state in this step (an increment or a
    /// stage ended): snapshot writers take one.
    pub milestone: bool,
}

impl Control {
    /// True while a prescribed motion or a rigid body under displacement control moves: not
    /// a static state, however balanced (a body under load control moves until it is
    /// balanced: [`Control::unbalanced`]).
    pub fn driving(&self) -> bool {
        self.drives.iter().any(|d| d.velocity != [0.0; 3])
            || self
                .bodies
                .iter()
                .any(|b| b.velocity != [0.0; 3] && b.load == [0.0; 3])
    }

    /// The largest out-of-balance force along its load of a body under load control, over
    /// the load (0 when no body carries one): a static state needs it within the
    /// tolerance as K_F is.
    pub fn unbalanced(&self) -> f64 {
        self.bodies
            .iter()
            .filter(|b| b.load != [0.0; 3])
            .map(|b| {
                let f2: f64 = b.load.iter().map(|c| c * c).sum();
                // The load plus the soil's resistance (−reaction), along the load.
                let net: f64 = (0..3).map(|a| (b.load[a] - b.reaction[a]) * b.load[a]).sum();
                net.abs() / f2
            })
            .fold(0.0, f64::max)
    }
}
