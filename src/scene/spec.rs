//! The scene's schema: every part of a scene as serde reads it from RON, with the defaults
//! of its fields. The rules each field holds are checked in `validate`.

pub use super::initial_stress::InitialStress;
use crate::grid::Face;
use crate::materials::MaterialSpec;
use crate::model::MotionSpec;
use crate::shape::ShapeKind;
use crate::state::{AntiLocking, Damping, ForceNorm, Scheme, StaticCheck};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A scene's dimension: `2`, `3` or `Axisymmetric`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(try_from = "DimensionText")]
pub enum Dimension {
    /// Plane strain, unit thickness.
    Two,
    /// Three dimensions.
    Three,
    /// Axisymmetric about the y axis: x is the radius, volumes and forces are per radian.
    Axisymmetric,
}

impl Dimension {
    /// Axes of the grid and the points (2 or 3).
    pub fn axes(self) -> usize {
        match self {
            Dimension::Three => 3,
            _ => 2,
        }
    }
}

impl std::fmt::Display for Dimension {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Dimension::Two => f.write_str("2"),
            Dimension::Three => f.write_str("3"),
            Dimension::Axisymmetric => f.write_str("Axisymmetric"),
        }
    }
}

impl Serialize for Dimension {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Dimension::Two => s.serialize_u8(2),
            Dimension::Three => s.serialize_u8(3),
            Dimension::Axisymmetric => s.serialize_unit_variant("Dimension", 2, "Axisymmetric"),
        }
    }
}

/// How a scene writes its dimension: a number, or the name `Axisymmetric` (RON hands an
/// untagged enum a bare name as text, where a plain visitor would see a unit value).
#[derive(Deserialize)]
#[serde(untagged)]
enum DimensionText {
    Number(i64),
    Name(DimensionName),
}

#[derive(Deserialize)]
enum DimensionName {
    Axisymmetric,
}

impl TryFrom<DimensionText> for Dimension {
    type Error = String;
    fn try_from(t: DimensionText) -> Result<Self, String> {
        match t {
            DimensionText::Number(2) => Ok(Dimension::Two),
            DimensionText::Number(3) => Ok(Dimension::Three),
            DimensionText::Number(n) => Err(format!("must be 2, 3 or Axisymmetric, found {n}")),
            DimensionText::Name(DimensionName::Axisymmetric) => Ok(Dimension::Axisymmetric),
        }
    }
}

/// A whole problem: grid, materials, bodies, boundary conditions, loads and solver settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// `2` (plane strain, unit thickness), `3`, or `Axisymmetric` (x the radius, y the axis).
    pub dimension: Dimension,
    /// Background grid.
    pub grid: GridSpec,
    /// Shape functions.
    #[serde(default)]
    pub shape: ShapeKind,
    /// Materials by name; a name given twice is an error.
    #[serde(deserialize_with = "crate::unique_map::deserialize")]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Bodies filled with material points.
    pub bodies: Vec<BodySpec>,
    /// Conditions on grid faces.
    #[serde(default)]
    pub boundaries: Vec<BoundarySpec>,
    /// Gravity, if any.
    #[serde(default)]
    pub gravity: Option<GravitySpec>,
    /// A hydrostatic water table (drained pore pressure, effective stress), if any.
    #[serde(default)]
    pub water: Option<crate::water::WaterSpec>,
    /// Concentrated loads, each carried by a massless point that moves with the body.
    #[serde(default)]
    pub point_loads: Vec<PointLoadSpec>,
    /// Prescribed motions of grid nodes (displacement control), each with its reaction and
    /// a load–displacement curve of static states.
    #[serde(default)]
    pub motions: Vec<MotionSpec>,
    /// Rigid bodies that travel through the soil (displacement control), each with its
    /// interface, its reaction and a load–displacement curve of static states.
    #[serde(default)]
    pub rigid_bodies: Vec<crate::rigid::RigidBodySpec>,
    /// Loading stages, each run to its static stop (the first names the scene as built).
    #[serde(default)]
    pub stages: Vec<StageSpec>,
    /// Factor of safety by strength reduction (`kdmpm fos`).
    #[serde(default)]
    pub strength_reduction: Option<StrengthReductionSpec>,
    /// Distributed loads on a body's surface, carried by its outermost points.
    #[serde(default)]
    pub tractions: Vec<TractionSpec>,
    /// Points whose displacement is recorded each output step and reported at the end.
    #[serde(default)]
    pub traced: Vec<TracedSpec>,
    /// Solver settings.
    pub solver: SolverSpec,
    /// Output settings.
    #[serde(default)]
    pub output: OutputSpec,
}

/// Background grid of square (cubic) cells.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Lower corner (m), one entry per axis.
    pub origin: Vec<f64>,
    /// Cell edge length h (m), > 0.
    pub cell_size: f64,
    /// Number of cells per axis, ≥ 1.
    pub cells: Vec<usize>,
}

/// A region filled with material points.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Name of a material in `materials`.
    pub material: String,
    /// The region.
    pub region: Region,
    /// Points per cell along each axis, ≥ 1 (placed at the centres of equal sub-cells).
    pub points_per_cell: Vec<usize>,
    /// The stress the points start at: `Isotropic(p)` or `Geostatic(k0: …)`
    /// ([`InitialStress`]). Default: none.
    #[serde(default)]
    pub initial_stress: Option<InitialStress>,
}

/// The shape of a body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Region {
    /// Axis-aligned box (m).
    Box {
        /// Lower corner.
        min: Vec<f64>,
        /// Upper corner.
        max: Vec<f64>,
    },
    /// A simple polygon in the x-y plane (m), extruded over `z` in 3D.
    Polygon {
        /// Vertices `[x, y]` in order (either orientation).
        vertices: Vec<Vec<f64>>,
        /// Extent `[z_min, z_max]` along z in 3D (m); ignored in 2D.
        #[serde(default)]
        z: Option<Vec<f64>>,
    },
}

/// A loading stage: what changes when it begins.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageSpec {
    /// Name (a row of `stages.csv`).
    pub name: String,
    /// Materials replaced, by name (each must be in `materials`).
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// Point loads' new forces, by name (N; N/m in 2D).
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub point_loads: BTreeMap<String, Vec<f64>>,
    /// The face conditions from this stage on, replacing the scene's (nodes a motion drives
    /// keep its axes).
    #[serde(default)]
    pub boundaries: Option<Vec<BoundarySpec>>,
    /// Gravity from this stage on (its ramp starts with the stage); the scene must have
    /// gravity.
    #[serde(default)]
    pub gravity: Option<GravitySpec>,
    /// Tractions' new values, by name (Pa).
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub tractions: BTreeMap<String, Vec<f64>>,
    /// The piezometric surfaces from this stage on (filling a reservoir, a drawdown); the
    /// scene must have `water`.
    #[serde(default)]
    pub water: Option<crate::water::StageWaterSpec>,
    /// Zero the accumulated displacements when the stage begins.
    #[serde(default)]
    pub reset_displacements: bool,
}

/// How `kdmpm fos` brackets the factor of safety (see [`crate::fos`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrengthReductionSpec {
    /// Two factors: the slope must stand at the first and fail at the second.
    pub bracket: Vec<f64>,
    /// Bisect until the bracket is this narrow (default 0.02).
    #[serde(default = "default_fos_tolerance")]
    pub tolerance: f64,
    /// A trial fails when a point moves farther than this (m), or when it finds no static
    /// state by `max_time` or `max_steps`.
    pub failure_displacement: f64,
    /// Steps between looks at the largest displacement (default 50).
    #[serde(default = "default_fos_check_every")]
    pub check_every: u64,
}

fn default_fos_tolerance() -> f64 {
    0.02
}

fn default_fos_check_every() -> u64 {
    50
}

/// Condition on a grid face.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Condition {
    /// All velocity components zero.
    Fixed,
    /// Normal velocity component zero (free sliding).
    Roller,
    /// Normal velocity component zero, and Coulomb friction along the face: the soil slides
    /// once its shear force reaches tan δ times the force it presses on the face with,
    /// δ in degrees (0 ≤ δ < 90; 0 is a roller). A rough base under a slope, a block
    /// pushed along a base.
    Friction(f64),
}

/// A boundary condition on one face of the grid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// The face.
    pub face: Face,
    /// The condition.
    pub condition: Condition,
}

/// Gravity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GravitySpec {
    /// Acceleration (m/s²), one entry per axis.
    pub acceleration: Vec<f64>,
    /// Time to ramp from zero to full gravity (s); 0 (default) applies it at once.
    #[serde(default)]
    pub ramp_time: f64,
}

/// A concentrated load.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLoadSpec {
    /// Name (for messages and tracing).
    pub name: String,
    /// Where it acts (m); it must lie inside a body's cells.
    pub position: Vec<f64>,
    /// The force (N; N per metre of thickness in 2D).
    pub force: Vec<f64>,
}

/// A traction (force per unit area) on the surface of the bodies inside a box, carried by
/// the outermost point of each column of points along the surface's normal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TractionSpec {
    /// Name (for messages).
    pub name: String,
    /// The surface: a side of the bodies named as the grid face it looks towards (`YMax`
    /// loads a top surface), or a circular `Arc`.
    pub surface: TractionSurface,
    /// Lower corner of the box that holds the loaded part of the surface (m).
    pub min: Vec<f64>,
    /// Upper corner (m).
    pub max: Vec<f64>,
    /// Force per unit area of the surface projected on the plane normal to `surface`
    /// (Pa), one entry per axis: `[0.0, -50e3]` presses a top surface down. It keeps its
    /// direction and size however the surface moves. Give it or `pressure`.
    #[serde(default)]
    pub traction: Vec<f64>,
    /// A pressure (Pa, compression positive) that follows the surface: normal to it and in
    /// proportion to its size as it deforms (a surcharge on ground that heaves, a fluid;
    /// [`crate::SurfacePressures`]). Instead of `traction`.
    #[serde(default)]
    pub pressure: Option<f64>,
    /// Apply it in this many equal increments, each to its static stop and a row of
    /// `curve.csv` (load control); default: all at once.
    #[serde(default)]
    pub increments: Option<u32>,
}

/// The surface a traction loads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum TractionSurface {
    /// The bodies' side facing −x.
    XMin,
    /// The side facing +x.
    XMax,
    /// The side facing −y.
    YMin,
    /// The side facing +y (a top surface).
    YMax,
    /// The side facing −z.
    ZMin,
    /// The side facing +z.
    ZMax,
    /// The part inside the traction's box of the circle of `centre` and `radius` (m) in the
    /// x-y plane, under a pressure: the wall of a hole when the bodies lie outside it, the
    /// rim of a disc when they lie inside. In plane strain a cylinder along z; in
    /// axisymmetry a sphere (centre on the axis) or a ring. 2D and axisymmetric scenes.
    Arc {
        /// The circle's centre `[x, y]` (m).
        centre: Vec<f64>,
        /// Its radius (m, > 0).
        radius: f64,
    },
}

impl TractionSurface {
    /// The grid face this surface is, if it is one.
    pub fn face(&self) -> Option<Face> {
        Some(match self {
            Self::XMin => Face::XMin,
            Self::XMax => Face::XMax,
            Self::YMin => Face::YMin,
            Self::YMax => Face::YMax,
            Self::ZMin => Face::ZMin,
            Self::ZMax => Face::ZMax,
            Self::Arc { .. } => return None,
        })
    }
}

impl TractionSpec {
    /// Whether the place `x` (m, one entry an axis of the box) lies in its box, faces
    /// included.
    pub fn holds(&self, x: &[f64]) -> bool {
        (0..self.min.len()).all(|a| x[a] >= self.min[a] && x[a] <= self.max[a])
    }

    /// Whether it loads at all: a non-zero pressure or traction entry.
    pub fn loads(&self) -> bool {
        match self.pressure {
            Some(p) => p != 0.0,
            None => self.traction.iter().any(|&t| t != 0.0),
        }
    }

    /// What a value of this traction (a stage's new one) stands for at set-up (Pa), x y z,
    /// on a piece of surface of outward normal `normal` (unit): a traction's entries as
    /// given, a pressure's one entry p as −p n.
    pub fn load_at(&self, value: &[f64], normal: [f64; 3]) -> [f64; 3] {
        match self.pressure {
            // Components across the normal stay +0.
            Some(_) => normal.map(|n| if n == 0.0 { 0.0 } else { -value[0] * n }),
            None => pad3(value),
        }
    }
}

/// A traced point: the material point nearest to `position`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TracedSpec {
    /// Name, used as a column prefix in `history.csv`.
    pub name: String,
    /// Where to look (m); the nearest point within one cell is taken.
    pub position: Vec<f64>,
}

/// How the time step is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum TimeStep {
    /// A fixed step (s).
    Fixed(f64),
    /// Δt = α·h / c_p with c_p the largest P-wave speed of the scene's materials.
    Courant(f64),
}

/// Solver settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Damping (default `Kinetic`).
    #[serde(default)]
    pub damping: Damping,
    /// Update scheme (default `Musl`).
    #[serde(default)]
    pub scheme: Scheme,
    /// Time step.
    pub time_step: TimeStep,
    /// Tolerance for K_F and K_E (default 0.01).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Norm of K_F used to stop (default `Max`, the paper's eq. 3).
    #[serde(default)]
    pub force_norm: ForceNorm,
    /// The systems of one step, in order, replacing the default schedule of `scheme`
    /// (see `kdmpm check` for the default list, `systems::SYSTEM_NAMES` for every name).
    #[serde(default)]
    pub schedule: Option<Vec<String>>,
    /// A node lighter than this fraction of a full node's mass (ρ·h^D of the lightest
    /// material, halved per grid face the node lies on) carries no degrees of freedom
    /// (default 0.001). See `Settings::min_node_mass`.
    #[serde(default = "default_node_mass_cutoff")]
    pub node_mass_cutoff: f64,
    /// Virtual mass floor for nodal accelerations, as a fraction of a full node's mass
    /// (halved per grid face the node lies on; default 0.01). See `Settings::virtual_mass_floor`.
    #[serde(default = "default_virtual_mass_floor")]
    pub virtual_mass_floor: f64,
    /// A rigid-body contact solve stops when no sweep changes a contact's velocity by more
    /// than this fraction of the solve's scale (default 1e-5; at most 1e-3). Looser is
    /// fewer sweeps and a less exact contact: see docs/performance.md.
    #[serde(default = "default_contact_tolerance")]
    pub contact_tolerance: f64,
    /// FLIP fraction α of the point velocity update: 1 (default) is FLIP, 0 is PIC, which
    /// damps the velocity noise of the points.
    #[serde(default = "default_flip")]
    pub flip: f64,
    /// The volumetric treatment against locking (default `Off`): `StrainSmoothing`
    /// smooths the volumetric strain rate through the nodes (isochoric flow only),
    /// `CellMean` takes cell means of it and of the mean stress (any flow).
    #[serde(default)]
    pub anti_locking: AntiLocking,
    /// Put the points back in cell order every this many steps so that neighbours in space
    /// stay neighbours in memory (default 100; 0 never sorts).
    #[serde(default = "default_sort_every")]
    pub sort_every: u64,
    /// Kinetic damping only: reset at the peak of a parabola through the last three kinetic
    /// energies, moving the points back (or on) to it, instead of where the drop was seen.
    #[serde(default)]
    pub peak_interpolation: bool,
    /// Take the time step from the slowest P-wave speed of the materials in use and give
    /// stiffer materials a fictitious inertia (c_m/c_ref)² times their mass, for the
    /// acceleration only: dynamic relaxation's mass matrix is free, the static answer is not
    /// changed, the path may be.
    #[serde(default)]
    pub mass_scaling: bool,
    /// Confirm a converged state is static before stopping: `(window: s, max_displacement: m)`.
    #[serde(default)]
    pub static_check: Option<StaticCheck>,
    /// Step limit.
    #[serde(default)]
    pub max_steps: Option<u64>,
    /// Simulated-time limit (s).
    #[serde(default)]
    pub max_time: Option<f64>,
    /// Write the whole state to `checkpoint.kdc` in the output directory this often, so
    /// that `kdmpm resume DIR` can continue the run bit for bit (default: never, except on
    /// Ctrl-C).
    #[serde(default)]
    pub checkpoint_every: Option<CheckpointEvery>,
}

/// How often a run writes its checkpoint.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum CheckpointEvery {
    /// Every this many steps (≥ 1).
    Steps(u64),
    /// Every this many seconds of wall time (> 0).
    Seconds(f64),
}

/// A scene vector (one entry per axis) as x y z, the missing axes 0.
pub(crate) fn pad3(v: &[f64]) -> [f64; 3] {
    [
        v[0],
        v.get(1).copied().unwrap_or(0.0),
        v.get(2).copied().unwrap_or(0.0),
    ]
}

fn default_node_mass_cutoff() -> f64 {
    1e-3
}

fn default_virtual_mass_floor() -> f64 {
    0.01
}

fn default_contact_tolerance() -> f64 {
    crate::rigid::contact::TOLERANCE
}

fn default_sort_every() -> u64 {
    100
}

fn default_flip() -> f64 {
    1.0
}

fn default_tolerance() -> f64 {
    0.01
}

/// Output settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Write a `history.csv` row every this many steps (and at the last step), ≥ 1.
    #[serde(default = "default_every")]
    pub history_every: u64,
    /// Measure the free-surface angle at the end (see `measure::surface_angle`).
    #[serde(default)]
    pub surface_angle: bool,
    /// Keep every point's displacement from its start (default true; 16 bytes a point in
    /// 2D, 24 in 3D): the maximum displacements in `summary.json` and the displacement field
    /// of `points.vtu` need it. Traced points do not.
    #[serde(default = "default_true")]
    pub displacements: bool,
    /// Point snapshots during the run, as a ParaView series (`points.pvd`): every N steps,
    /// every T seconds of simulated time and/or at each kinetic-damping reset.
    #[serde(default)]
    pub snapshots: Option<crate::output::SnapshotSpec>,
}

fn default_true() -> bool {
    true
}

fn default_every() -> u64 {
    1
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            history_every: 1,
            surface_angle: false,
            displacements: true,
            snapshots: None,
        }
    }
}

pub(super) fn ron_options() -> ron::Options {
    use ron::extensions::Extensions;
    // A material is a newtype variant around its model's entry (`crate::materials`), written
    // `MohrCoulomb(density: ..)` as if the variant held the fields.
    ron::Options::default()
        .with_default_extension(Extensions::IMPLICIT_SOME | Extensions::UNWRAP_VARIANT_NEWTYPES)
}

impl Scene {
    /// Every material entry, the scene's then those its stages set, in order, by name.
    pub fn every_material(&self) -> impl Iterator<Item = (&String, &MaterialSpec)> {
        let staged = self.stages.iter().flat_map(|st| st.materials.iter());
        self.materials.iter().chain(staged)
    }

    /// [`Scene::every_material`], to change them (strength reduction).
    pub fn every_material_mut(&mut self) -> impl Iterator<Item = (&String, &mut MaterialSpec)> {
        let staged = self.stages.iter_mut().flat_map(|st| st.materials.iter_mut());
        self.materials.iter_mut().chain(staged)
    }

    /// True when a motion or a rigid body has a loaded `area`: the run then has a
    /// `limit_pressure`.
    pub fn has_limit_pressure(&self) -> bool {
        self.motions.iter().any(|m| m.area.is_some()) || self.rigid_bodies.iter().any(|b| b.area.is_some())
    }

    /// The names of `curve.csv`'s rows that carry a pressure: motions and rigid bodies with
    /// an `area`, and parts with one (`body.part`).
    pub fn pressure_rows(&self) -> Vec<String> {
        let motions = self
            .motions
            .iter()
            .filter(|m| m.area.is_some())
            .map(|m| m.name.clone());
        let bodies = self.rigid_bodies.iter().flat_map(|b| {
            let whole = b.area.map(|_| b.name.clone());
            let parts = b
                .parts
                .iter()
                .filter(|p| p.area.is_some())
                .map(move |p| format!("{}.{}", b.name, p.name));
            whole.into_iter().chain(parts)
        });
        motions.chain(bodies).collect()
    }

    /// Why the mean pressure of `curve.csv`'s rows `row` from a displacement of `from` (m)
    /// on cannot be measured, if it cannot: the window starts at a displacement ≥ 0 and the
    /// row carries a pressure ([`Self::pressure_rows`]). For `kdmpm study`'s and
    /// `--refine`'s mean pressures alike.
    pub fn pressure_window_fault(&self, row: &str, from: f64) -> Option<String> {
        if !(from.is_finite() && from >= 0.0) {
            return Some(format!(
                "the displacement from which rows count must be ≥ 0 m, found {from}"
            ));
        }
        let rows = self.pressure_rows();
        (!rows.iter().any(|r| r == row)).then(|| {
            format!(
                "no curve row `{row}` has a pressure: the rows with an `area` are {}",
                rows.join(", ")
            )
        })
    }
}
