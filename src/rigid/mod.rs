//! Rigid bodies that travel through the ground (`rigid_bodies` in a scene): a footing, a
//! T-bar, a wall, a pile, with an interface to the soil and a displacement control.
//!
//! A body is a [`Geometry`] that moves with its control's velocity. It meets the soil at
//! the grid (`systems::rigid_contact`): at each node the soil touches it, the soil may not
//! move into the body along the geometry's normal, and the tangential motion is free
//! (smooth), limited by Coulomb friction and an adhesion cap, or the body's until the shear
//! reaches the soil's own strength beside it (rough). The
//! force this takes is summed per body in node order (its reaction is the opposite).
//!
//! A body is driven one of two ways (`systems::rigid_control`), in increments each relaxed
//! to a static state and recorded as a row of `curve.csv`: under displacement control
//! (`motion`) it travels at a velocity, as `motions` do, and kinetic damping never stops
//! it; under load control (`load`) a force acts on it and it finds its own place along
//! the force, moving as a mass the soil's resistance decelerates, its velocity zeroed with
//! the soil's at each kinetic-energy peak.

pub mod contact;
pub mod corners;
pub mod cpt;
pub mod exposed;
pub mod filter;
pub mod geometry;
pub mod mesh;
pub mod reach;
pub mod sampling;
pub mod stl;

pub use contact::Contact;
pub use corners::{CornerTest, Corners, Located};
pub use cpt::{Cpt, CptSpec, InSitu};
pub use exposed::Exposed;
pub use filter::FilterSpec;
pub use geometry::{Geometry, Sample};
pub use reach::Reach;

use crate::error::Refusal;
use serde::{Deserialize, Serialize};

/// Where a body's contacts take the soil's surface to be (`soil_surface` of a rigid body
/// in a scene).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum SoilSurface {
    /// Wherever soil reaches the nodes a constraint holds: the soil there is held off the
    /// body whether its points touch the body or not.
    #[default]
    Nodes,
    /// At the surface of the soil's points in front of a constraint: soil that stands off
    /// the body may come back until its points' surface meets the body's.
    Points,
}

/// A rigid body as the scene gives it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidBodySpec {
    /// Name: `curve.csv` rows carry it (and `name.part` for each part's share).
    pub name: String,
    /// Its shape at the start: one or more named parts (a cone's `tip` and `shaft`), whose
    /// union is the body; the resistance is summed per part as well as per body.
    pub parts: Vec<PartSpec>,
    /// How the soil slides along it (along every part that does not give its own).
    #[serde(default)]
    pub interface: Interface,
    /// Whether its contact samples hold the soil past its corners (`Held`, the default) or
    /// let it go (`Released`, [`corners`]).
    #[serde(default)]
    pub corners: Corners,
    /// Where its contacts take the soil's surface to be: where soil reaches the nodes they
    /// hold (`Nodes`, the default) or at the surface of the soil's points in front of them
    /// (`Points`, [`crate::systems::soil_gap`]).
    #[serde(default)]
    pub soil_surface: SoilSurface,
    /// How it moves; without one the body holds its place (a rigid base, a wall at rest)
    /// and its reaction is recorded at every static state another control reaches.
    #[serde(default)]
    pub motion: Option<BodyMotion>,
    /// Load control instead of `motion`: a force on the body, in increments.
    #[serde(default)]
    pub load: Option<BodyLoad>,
    /// Loaded area (m²; m per metre of thickness in 2D; m² per radian when axisymmetric),
    /// for the mean pressure in `curve.csv` and `limit_pressure` in summary.json.
    #[serde(default)]
    pub area: Option<f64>,
    /// Pore-pressure filters on its surface (the piezocone's u2), each read at every
    /// static state ([`filter`]).
    #[serde(default)]
    pub filters: Vec<FilterSpec>,
    /// The body read as a piezocone: its tip, sleeve and u2 filter by name, logged against
    /// the ground it enters in `cpt.csv` ([`cpt`]).
    #[serde(default)]
    pub cpt: Option<CptSpec>,
}

/// A body's surface samples in its starting frame, each with the index of its part.
pub type Samples = Vec<(Sample, usize)>;

/// A rigid body as a run holds it: the scene's body, checked and with its meshes read; the
/// samples of its surface at which contact is held, cut once at set-up; and each part's
/// interface law.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidBody {
    /// The body as the scene gives it (a body under load control without a mass of its own
    /// has the soil's it displaces, filled in by set-up).
    pub spec: RigidBodySpec,
    /// Its surface samples in its starting frame, each with its part's index
    /// ([`RigidBodySpec::samples`]).
    pub samples: Samples,
    /// Per part: its interface as the contact holds it ([`Interface::law`]).
    pub interfaces: Vec<InterfaceLaw>,
    /// Its piezocone readings, checked ([`CptSpec::check`]).
    pub cpt: Option<Cpt>,
}

impl RigidBody {
    /// The body of `spec` with the surface `samples` cut for the run's grid.
    pub fn new(spec: RigidBodySpec, samples: Samples) -> Self {
        let interfaces = (0..spec.parts.len())
            .map(|k| spec.interface_of(k).law())
            .collect();
        let cpt = (spec.cpt.as_ref()).map(|c| {
            c.check(&spec)
                .expect("a scene's bodies are checked before set-up")
        });
        RigidBody {
            spec,
            samples,
            interfaces,
            cpt,
        }
    }
}

/// A named part of a rigid body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    /// Name, unique within the body.
    pub name: String,
    /// Its shape at the start (m).
    pub geometry: Geometry,
    /// Loaded area, as the body's, for the part's mean pressure.
    #[serde(default)]
    pub area: Option<f64>,
    /// The part's own interface (a cone's rough tip below a smooth sleeve); the body's
    /// when absent.
    #[serde(default)]
    pub interface: Option<Interface>,
}

/// The soil–structure interface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Interface {
    /// No shear: the soil slides freely along the body.
    #[default]
    Smooth,
    /// As strong as the soil beside it: the soil moves with the body until the shear
    /// reaches the soil's own strength on the surface, c + σ_n tan φ (c_u on Tresca clay,
    /// the fully rough interface of the plasticity solutions), and then slips
    /// (`systems/soil_strength.rs`). No slip on a soil without strength (elastic).
    Rough,
    /// Coulomb friction τ ≤ tan δ · σ_n + a, δ in degrees, the adhesion a in Pa (α·c_u on
    /// clay).
    Frictional {
        /// Interface friction angle δ (degrees, 0 ≤ δ < 90).
        angle: f64,
        /// Adhesion a (Pa, ≥ 0): shear the interface carries without normal stress.
        #[serde(default)]
        adhesion: f64,
    },
}

/// Displacement control: a constant velocity, a travel, and increments each ending at a
/// static state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyMotion {
    /// Velocity (m/s, one entry per axis).
    pub velocity: Vec<f64>,
    /// Distance to travel along it (m).
    pub travel: f64,
    /// Distance of one increment (m). Default: the whole travel in one.
    #[serde(default)]
    pub increment: Option<f64>,
    /// The stage (by name) at whose start the body sets off; until then it holds its
    /// place (a geostatic stage, then penetration). Default: from the start of the run.
    #[serde(default)]
    pub stage: Option<String>,
}

/// Load control: a force on the body applied in equal increments; the body moves along it
/// (guided: across it and in rotation it holds) until the soil's resistance balances it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyLoad {
    /// The force on the body at the last increment (N; N/m in 2D; N/rad when
    /// axisymmetric), one entry per axis.
    pub force: Vec<f64>,
    /// Equal increments it is applied in, each relaxed to a static state (default 1).
    #[serde(default = "one")]
    pub increments: u32,
    /// The stage (by name) at whose start the load comes on. Default: from the start.
    #[serde(default)]
    pub stage: Option<String>,
    /// The body's mass (kg; kg/m in 2D; kg/rad when axisymmetric), which sets how fast it
    /// moves as the soil relaxes, not where it ends. Default: the mass of the soil it
    /// displaces, its volume in the grid times the densest material's density.
    #[serde(default)]
    pub mass: Option<f64>,
}

fn one() -> u32 {
    1
}

impl BodyLoad {
    /// The force as x y z (N).
    pub fn vector(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.force.get(a).copied().unwrap_or(0.0))
    }

    /// The force during increment `k` (0-based): its (k + 1)/increments share (N, x y z).
    pub fn at(&self, k: u32) -> [f64; 3] {
        let share = f64::from(k.min(self.increments - 1) + 1) / f64::from(self.increments);
        self.vector().map(|f| f * share)
    }

    /// The unit vector along the force. The force is scaled by its largest entry first, so
    /// that the squares neither overflow (1e160 N) nor vanish (1e-170 N).
    pub fn direction(&self) -> [f64; 3] {
        let f = self.vector();
        let big = f.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        let f = f.map(|c| c / big);
        let l = f.iter().map(|c| c * c).sum::<f64>().sqrt();
        f.map(|c| c / l)
    }
}

impl BodyMotion {
    /// The velocity as x y z (m/s).
    pub fn vector(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.velocity.get(a).copied().unwrap_or(0.0))
    }

    /// Speed (m/s).
    pub fn speed(&self) -> f64 {
        self.vector().iter().map(|v| v * v).sum::<f64>().sqrt()
    }
}

/// An interface as the contact holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InterfaceLaw {
    /// Coulomb's: the shear at most tan δ times the normal stress plus the adhesion;
    /// both 0 when smooth.
    Coulomb {
        /// tan δ.
        friction: f64,
        /// Adhesion a (Pa).
        adhesion: f64,
    },
    /// The soil's own strength beside each sample, found each step (`Rough`).
    Soil,
}

impl Interface {
    /// The law the contact holds.
    pub fn law(&self) -> InterfaceLaw {
        match *self {
            Interface::Smooth => InterfaceLaw::Coulomb {
                friction: 0.0,
                adhesion: 0.0,
            },
            Interface::Rough => InterfaceLaw::Soil,
            Interface::Frictional { angle, adhesion } => InterfaceLaw::Coulomb {
                friction: angle.to_radians().tan(),
                adhesion,
            },
        }
    }

    /// The rules an interface holds by itself (the friction angle and the adhesion).
    pub fn check(&self) -> Result<(), String> {
        if let Interface::Frictional { angle, adhesion } = *self {
            check_friction_angle(angle)?;
            if !(adhesion.is_finite() && adhesion >= 0.0) {
                return Err(format!("the adhesion is ≥ 0 Pa, found {adhesion}"));
            }
        }
        Ok(())
    }
}

/// The rule for a friction angle δ (degrees) between soil and a structure, a body's or a
/// `Friction` face's: 0 ≤ δ < 90°.
pub fn check_friction_angle(angle: f64) -> Result<(), String> {
    if angle.is_finite() && (0.0..90.0).contains(&angle) {
        Ok(())
    } else {
        Err(format!("the friction angle is 0 ≤ δ < 90°, found {angle}"))
    }
}

/// [`RigidBodySpec::distance`] over `parts`: the nearest part's signed distance (m),
/// outward normal and index.
pub(crate) fn distance(parts: &[PartSpec], x: [f64; 3], n: usize) -> (f64, [f64; 3], usize) {
    let mut best = (f64::INFINITY, [0.0; 3], 0);
    for (k, p) in parts.iter().enumerate() {
        let (phi, normal) = p.geometry.distance(x, n);
        if phi < best.0 {
            best = (phi, normal, k);
        }
    }
    best
}

impl RigidBodySpec {
    /// The interface along part `k`: its own, or the body's.
    pub fn interface_of(&self, k: usize) -> Interface {
        self.parts[k].interface.unwrap_or(self.interface)
    }

    /// Signed distance φ (m, negative inside) from `x` (m, in the body's starting frame) to
    /// the body, the unit outward normal there and the part it belongs to (the nearest
    /// surface; inside, the part that holds `x` deepest).
    pub fn distance(&self, x: [f64; 3], n: usize) -> (f64, [f64; 3], usize) {
        distance(&self.parts, x, n)
    }

    /// Axis-aligned bounds (m) of the body at its starting position.
    pub fn bounds(&self, n: usize) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &self.parts {
            let (l, h) = p.geometry.bounds(n);
            for a in 0..3 {
                lo[a] = lo[a].min(l[a]);
                hi[a] = hi[a].max(h[a]);
            }
        }
        (lo, hi)
    }

    /// The rules a body holds by itself in `n` dimensions (`axisymmetric`: (r, z)), or the
    /// [`Refusal`] of the field. Its place in the grid is checked with the grid
    /// (`scene::validate::rigid_bodies`).
    pub fn check(&self, n: usize, axisymmetric: bool) -> Result<(), Refusal> {
        let bad = |f: &str, r: String| Err(Refusal::new(f.to_string(), r));
        if self.parts.is_empty() {
            return bad("parts", "a body needs at least one part".into());
        }
        for (k, p) in self.parts.iter().enumerate() {
            if let Some(j) = self.parts[..k].iter().position(|o| o.name == p.name) {
                return bad(
                    &format!("parts[{k}].name"),
                    format!(
                        "\"{}\" is also the name of parts[{j}]: each part needs its own name",
                        p.name
                    ),
                );
            }
            if let Some(a) = p.area {
                if !(a.is_finite() && a > 0.0) {
                    return bad(&format!("parts[{k}].area"), format!("must be above 0, found {a}"));
                }
            }
            p.geometry
                .check(n, axisymmetric)
                .map_err(|r| r.under(&format!("parts[{k}]")))?;
            if let Some(i) = p.interface {
                i.check()
                    .map_err(|r| Refusal::new(format!("parts[{k}].interface"), r))?;
            }
        }
        let (lo, hi) = self.bounds(n);
        let size = (0..n).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        for (k, f) in self.filters.iter().enumerate() {
            let taken = self.parts.iter().any(|p| p.name == f.name)
                || self.filters[..k].iter().any(|o| o.name == f.name);
            if taken {
                return bad(
                    &format!("filters[{k}].name"),
                    format!(
                        "\"{}\" is already the name of a part or a filter of the body: its row of \
                         curve.csv needs its own",
                        f.name
                    ),
                );
            }
            f.check(n, &self.parts, size)
                .map_err(|r| r.under(&format!("filters[{k}]")))?;
        }
        if let Some(c) = &self.cpt {
            let cpt = c.check(self).map_err(|r| r.under("cpt"))?;
            if axisymmetric {
                cpt.check_areas(self)?;
            }
        }
        self.check_interface_and_motion(n, axisymmetric)
    }

    /// The interface, the area and the control; in an axisymmetric scene the body, a solid
    /// of revolution, moves along the axis only (a radial motion of its section would open
    /// it into a ring, which no rigid body does).
    fn check_interface_and_motion(&self, n: usize, axisymmetric: bool) -> Result<(), Refusal> {
        let bad = |f: &str, r: String| Err(Refusal::new(f.to_string(), r));
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        // The radial entry `along_r` (in `unit`) of a control: none in an axisymmetric scene.
        let radial = |field: &str, along_r: f64, unit: &str| {
            if axisymmetric && along_r != 0.0 {
                return bad(
                    field,
                    format!(
                        "{along_r} {unit} along r: an axisymmetric body moves along the axis only \
                         (y); the radial entry (x) must be 0"
                    ),
                );
            }
            Ok(())
        };
        self.interface.check().map_err(|r| Refusal::new("interface", r))?;
        if let Some(a) = self.area {
            if !(a.is_finite() && a > 0.0) {
                return bad("area", format!("must be above 0, found {a}"));
            }
        }
        if let Some(l) = &self.load {
            if self.motion.is_some() {
                return bad(
                    "load",
                    "a body is driven by a motion or by a load, not both: drop one".into(),
                );
            }
            if l.force.len() != n || !finite(&l.force) {
                return bad(
                    "load.force",
                    format!("needs {n} finite entries (N), found {:?}", l.force),
                );
            }
            if l.vector() == [0.0; 3] {
                return bad("load.force", "the load is zero: give it a force".into());
            }
            radial("load.force", l.force[0], "N")?;
            if !(1..=1_000_000).contains(&l.increments) {
                return bad(
                    "load.increments",
                    format!("must be 1 to a million, found {}", l.increments),
                );
            }
            if let Some(m) = l.mass {
                if !(m.is_finite() && m > 0.0) {
                    return bad("load.mass", format!("must be above 0 kg, found {m}"));
                }
            }
        }
        let Some(m) = &self.motion else {
            return Ok(());
        };
        if m.velocity.len() != n || !finite(&m.velocity) {
            return bad(
                "motion.velocity",
                format!("needs {n} finite entries (m/s), found {:?}", m.velocity),
            );
        }
        if m.speed() <= 0.0 {
            return bad(
                "motion.velocity",
                "the body does not move: give it a velocity".into(),
            );
        }
        radial("motion.velocity", m.velocity[0], "m/s")?;
        if !(m.travel.is_finite() && m.travel > 0.0) {
            return bad("motion.travel", format!("must be above 0 m, found {}", m.travel));
        }
        if let Some(inc) = m.increment {
            if !(inc.is_finite() && inc > 0.0) {
                return bad("motion.increment", format!("must be above 0 m, found {inc}"));
            }
            if m.travel / inc > 1e6 {
                return bad("motion.increment", "more than a million increments".into());
            }
        }
        Ok(())
    }

    /// Its parts drawn at displacement `offset` (m), body index `body`, 3D surfaces sampled
    /// every `spacing` m where they lie in `grid` (lower and upper corner, m; the
    /// snapshots' `bodies_*.vtu`).
    pub fn outlines(
        &self,
        body: u32,
        offset: [f64; 3],
        spacing: f64,
        grid: ([f64; 3], [f64; 3]),
    ) -> Vec<Outline> {
        let reach = Reach {
            lo: std::array::from_fn(|a| grid.0[a] - offset[a]),
            hi: std::array::from_fn(|a| grid.1[a] - offset[a]),
        };
        (0u32..)
            .zip(&self.parts)
            .map(|(part, p)| {
                let (points, closed) = p.geometry.outline(spacing, &reach);
                Outline {
                    body,
                    part,
                    points: points
                        .into_iter()
                        .map(|x| std::array::from_fn(|a| x[a] + offset[a]))
                        .collect(),
                    closed,
                }
            })
            .collect()
    }

    /// The box (m, in the body's starting frame) its surface can reach the grid
    /// `lo`..`hi` (m, `n` axes) from over its travel, `margin` wider on every side (the
    /// shape functions' support): the grid shifted back along its motion, or under a load
    /// by the grid's own size along each axis the load acts on.
    pub fn reach(&self, n: usize, lo: [f64; 3], hi: [f64; 3], margin: f64) -> Reach {
        let mut reach = Reach {
            lo: std::array::from_fn(|a| if a < n { lo[a] - margin } else { f64::NEG_INFINITY }),
            hi: std::array::from_fn(|a| if a < n { hi[a] + margin } else { f64::INFINITY }),
        };
        for a in 0..n {
            if let Some(m) = &self.motion {
                let moved = m.vector()[a] / m.speed() * m.travel;
                reach.lo[a] -= moved.max(0.0);
                reach.hi[a] -= moved.min(0.0);
            }
            if self.load.as_ref().is_some_and(|l| l.vector()[a] != 0.0) {
                reach.lo[a] -= hi[a] - lo[a];
                reach.hi[a] += hi[a] - lo[a];
            }
        }
        reach
    }

    /// Its contact samples in a grid of cell size `cell` spanning `lo`..`hi` (m): its
    /// surface every half cell where it can reach the grid over its travel (the shape
    /// functions' support, two cells, around it), each with its part, less those on a face
    /// two parts share (a cone's tip against its shaft: inside the body, not on its
    /// surface).
    pub fn samples(&self, n: usize, cell: f64, (lo, hi): ([f64; 3], [f64; 3])) -> Samples {
        let reach = self.reach(n, lo, hi, 2.0 * cell);
        let spacing = 0.5 * cell;
        let inner = 1e-9 * cell;
        self.parts
            .iter()
            .enumerate()
            .flat_map(|(k, p)| {
                p.geometry
                    .samples(spacing, &reach)
                    .into_iter()
                    .map(move |s| (s, k))
            })
            .filter(|(s, k)| {
                self.parts
                    .iter()
                    .enumerate()
                    .all(|(j, q)| j == *k || q.geometry.distance(s.x, n).0 > inner)
            })
            .collect()
    }

    /// Reads its parts' STL meshes (`dir`: the scene file's directory), or the
    /// [`Refusal`] of the file's field.
    pub fn read_meshes(&mut self, dir: &std::path::Path) -> Result<(), Refusal> {
        for (k, p) in self.parts.iter_mut().enumerate() {
            p.geometry
                .read(dir)
                .map_err(|r| r.under(&format!("parts[{k}]")))?;
        }
        Ok(())
    }

    /// The increments its control drives it in (0 for a body that holds its place).
    pub fn increments(&self) -> u32 {
        match (&self.motion, &self.load) {
            (Some(m), _) => match m.increment {
                Some(inc) => ((m.travel / inc) * (1.0 - 1e-9)).ceil().max(1.0) as u32,
                None => 1,
            },
            (_, Some(l)) => l.increments,
            _ => 0,
        }
    }

    /// Sets the body off at the start of its control (its stage, or the run): moving at its
    /// motion's velocity, or carrying its load's first increment.
    pub fn set_off(&self, state: &mut BodyState) {
        if let Some(m) = &self.motion {
            state.velocity = m.vector();
        }
        if let Some(l) = &self.load {
            state.load = l.at(0);
        }
    }

    /// The kinetic energy it carries as a mass of its own (J; J/m in 2D; J/rad
    /// axisymmetric): ½ M V² under load control with a `mass`, else 0.
    pub fn kinetic_energy(&self, state: &BodyState) -> f64 {
        let mass = self.load.as_ref().and_then(|l| l.mass).unwrap_or(0.0);
        0.5 * mass * state.velocity.iter().map(|c| c * c).sum::<f64>()
    }

    /// The stage its control waits for (`motion.stage` or `load.stage`), if any.
    pub fn stage(&self) -> Option<&String> {
        match (&self.motion, &self.load) {
            (Some(m), _) => m.stage.as_ref(),
            (_, Some(l)) => l.stage.as_ref(),
            _ => None,
        }
    }

    /// The first stage (index into `stages`, the scene's stage names in order; none for a
    /// scene without stages) in which the body is driven: 0 unless its control waits for a
    /// later stage. `None` for a body with neither a motion nor a load, or one waiting for
    /// a stage the scene does not have (validation refuses that).
    pub fn first_stage(&self, stages: &[&str]) -> Option<usize> {
        if self.motion.is_none() && self.load.is_none() {
            return None;
        }
        match self.stage() {
            None => Some(0),
            Some(s) => stages.iter().position(|t| t == s),
        }
    }

    /// Its volume inside the grid (m³; m² in 2D; m² per radian when axisymmetric, ∫ r dA),
    /// by the midpoint rule over the grid's cells (`origin`, `cell` size, `cells` per axis):
    /// the default mass of a body under load control.
    pub fn volume(
        &self,
        n: usize,
        axisymmetric: bool,
        origin: [f64; 3],
        cell: f64,
        cells: [usize; 3],
    ) -> f64 {
        let (lo, hi) = self.bounds(n);
        let range = |a: usize| -> (usize, usize) {
            if a >= n {
                return (0, 1);
            }
            let first = ((lo[a] - origin[a]) / cell).floor().max(0.0) as usize;
            let last = (((hi[a] - origin[a]) / cell).ceil().max(0.0) as usize).min(cells[a]);
            (first.min(last), last)
        };
        let (rx, ry, rz) = (range(0), range(1), range(2));
        let mut volume = 0.0;
        for k in rz.0..rz.1 {
            for j in ry.0..ry.1 {
                for i in rx.0..rx.1 {
                    let c = [i, j, k].map(|c| c as f64 + 0.5);
                    let x: [f64; 3] =
                        std::array::from_fn(|a| if a < n { origin[a] + c[a] * cell } else { 0.0 });
                    if self.distance(x, n).0 < 0.0 {
                        volume += if axisymmetric { x[0] } else { 1.0 };
                    }
                }
            }
        }
        volume * cell.powi(n as i32)
    }

    /// The body's state at the start of a run (`first`: its [`Self::first_stage`]):
    /// moving, unless it holds its place or waits for a later stage.
    pub fn state(&self, first: Option<usize>) -> BodyState {
        let mut state = BodyState {
            name: self.name.clone(),
            parts: vec![[0.0; 3]; self.parts.len()],
            ..BodyState::default()
        };
        if first == Some(0) {
            self.set_off(&mut state);
        }
        state
    }
}

/// A part of a body as drawn in a snapshot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outline {
    /// Index of the body (scene order).
    pub body: u32,
    /// Index of the part in the body.
    pub part: u32,
    /// Its points where it is now (m, x y z).
    pub points: Vec<[f64; 3]>,
    /// True for a closed outline (2D, axisymmetric), false for a cloud of surface points.
    pub closed: bool,
}

/// A body's state during a run (checkpointed).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BodyState {
    /// Name given in the scene.
    pub name: String,
    /// Velocity this step (m/s, x y z; zero while holding).
    pub velocity: [f64; 3],
    /// Under load control, the force on the body this increment (N, x y z); zero while it
    /// waits for its stage, and always for a body without a load.
    pub load: [f64; 3],
    /// Σ m̃ over the nodes its contacts reached this step (kg; 0 without a load): under load control, the
    /// soil that moves with the body, added to its mass in its equation of motion (set by
    /// `rigid_contact` each step, not kept in checkpoints).
    pub contact_mass: f64,
    /// Displacement from its scene position (m, x y z).
    pub offset: [f64; 3],
    /// Distance travelled (m).
    pub travel: f64,
    /// Increments finished, each ending at a static state.
    pub increments: u32,
    /// Force the body exerts on the soil this step, Σ f_c over its contacts (N; N/m in
    /// 2D; N/rad when axisymmetric); the soil's resistance on the body is the opposite.
    pub reaction: [f64; 3],
    /// The same, per part (in the order of `parts`).
    pub parts: Vec<[f64; 3]>,
    /// Points put back on the surface after a step ended with their centre inside
    /// (counted once per step each).
    pub entries: u64,
    /// The deepest such entry (m).
    pub deepest_entry: f64,
    /// For a body read as a piezocone, the ground as it was the step its push began
    /// (`systems/rigid_control.rs`); `None` before.
    pub in_situ: Option<InSitu>,
}
