//! The log of a cone penetration test (`rigid_bodies[i].cpt`): a pushed body read as a
//! piezocone, its cone resistance q_t, sleeve friction f_s and shoulder pore pressure u2
//! at every static state set against the ground it entered, as an engineer reads a CPTu.
//!
//! The three readings are rows `curve.csv` already holds: the tip part's mean pressure
//! along the motion (q_t), the sleeve part's (f_s: its axial force over its lateral area),
//! and the filter's pore pressure (u2); the recorder hands them here ([`Readings`]). Against them the log sets the ground as it was when
//! the push began ([`InSitu`], recorded by `systems/rigid_control.rs` the step the body sets
//! off): in slices one cell thick across the motion, the volume-weighted means of the total
//! stress along the motion σ_v0 (the effective stress, the excess pore pressure and the
//! water table's pressure together), of the water table's pressure u0, and of the
//! undrained strength s_u of the points whose material has one
//! ([`crate::materials::Material::undrained_strength`]). With these (Lunne, Robertson &
//! Powell 1997, *Cone Penetration Testing in Geotechnical Practice*, §2 and §5):
//!
//! N_kt = (q_t − σ_v0)/s_u,   N_Δu = (u2 − u0)/s_u,   B_q = (u2 − u0)/(q_t − σ_v0),
//!
//! with σ_v0 and s_u at the depth of the cone's apex and u0 at the filter's, each
//! interpolated between the slices' centres. The depth is the apex's below the ground's
//! surface along the motion when the push began (the face of the first slice that held
//! soil: exact where the ground's top lies on a cell face, as a region filling whole cells
//! does). In the engine the tip's force is the whole cone face's, so q_t is the corrected
//! cone resistance with no unequal-area term. `cpt.csv` holds the log (a cell left empty
//! where a quantity is undefined: no s_u, q_t at or below σ_v0) and `cpt.svg` draws q_t,
//! f_s and u2 against depth ([`crate::output::plots`]).

use super::{Geometry, RigidBodySpec};
use crate::error::Refusal;
use serde::{Deserialize, Serialize};

/// The log's file in a run's directory.
pub const LOG_FILE: &str = "cpt.csv";

/// A body read as a piezocone, as the scene gives it: the names of its tip part, its
/// sleeve part and its u2 filter.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CptSpec {
    /// The part whose mean pressure is q_t (it needs an `area`: the cone's projected area).
    pub tip: String,
    /// The part whose mean pressure is f_s (its `area` the sleeve's lateral area).
    #[serde(default)]
    pub sleeve: Option<String>,
    /// The filter that reads u2.
    #[serde(default)]
    pub u2: Option<String>,
}

/// A checked [`CptSpec`]: the indices of its tip and sleeve among the body's parts and of
/// its filter among the body's filters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cpt {
    /// The tip part.
    pub tip: usize,
    /// The sleeve part.
    pub sleeve: Option<usize>,
    /// The u2 filter.
    pub filter: Option<usize>,
}

impl CptSpec {
    /// The rules on `body`: it is pushed (a `motion`), the tip and the sleeve name parts
    /// with an area, other than each other, and `u2` names a filter. Field names are
    /// relative to the `cpt` entry.
    pub fn check(&self, body: &RigidBodySpec) -> Result<Cpt, Refusal> {
        if body.motion.is_none() {
            return Err(Refusal::new(
                "tip",
                "a penetrometer's log follows its push: the body needs a `motion`".into(),
            ));
        }
        let part = |field: &str, name: &str| -> Result<usize, Refusal> {
            let names: Vec<&str> = body.parts.iter().map(|p| p.name.as_str()).collect();
            let k = names.iter().position(|n| *n == name).ok_or_else(|| {
                Refusal::new(
                    field,
                    format!("\"{name}\" is not a part of the body (its parts: {names:?})"),
                )
            })?;
            if body.parts[k].area.is_none() {
                return Err(Refusal::new(
                    field,
                    format!("part \"{name}\" has no `area`: its mean pressure needs one"),
                ));
            }
            Ok(k)
        };
        let tip = part("tip", &self.tip)?;
        let sleeve = match &self.sleeve {
            Some(s) if *s == self.tip => {
                return Err(Refusal::new(
                    "sleeve",
                    format!("\"{s}\" is the tip: the sleeve is another part"),
                ))
            }
            Some(s) => Some(part("sleeve", s)?),
            None => None,
        };
        let filter = match &self.u2 {
            Some(f) => Some(body.filters.iter().position(|o| o.name == *f).ok_or_else(|| {
                let names: Vec<&str> = body.filters.iter().map(|o| o.name.as_str()).collect();
                Refusal::new(
                    "u2",
                    format!("\"{f}\" is not a filter of the body (its filters: {names:?})"),
                )
            })?),
            None => None,
        };
        Ok(Cpt { tip, sleeve, filter })
    }
}

impl Cpt {
    /// In an axisymmetric scene (the body pushed along the axis, forces per radian), the
    /// `area` of the tip and of the sleeve against their shapes: the tip's projected area
    /// ∫ r dr over the radii it spans, (r₁² − r₀²)/2, and the sleeve's lateral area ∫ r ds
    /// over its edges that do not lie across the axis (its ends meet the tip and the
    /// shaft). An area more than 1 % from its shape's would scale q_t or f_s by the ratio;
    /// the field is the part's `area`. Elsewhere the areas are the scene's to give.
    pub fn check_areas(&self, body: &RigidBodySpec) -> Result<(), Refusal> {
        let checks = [
            (
                Some(self.tip),
                "the tip's area is its projected area across the axis, ∫ r dr",
                "q_t is the tip's force over it",
                tip_area as fn(&Geometry) -> Option<(f64, String)>,
            ),
            (
                self.sleeve,
                "the sleeve's area is its lateral area, ∫ r ds",
                "f_s is the sleeve's force over it",
                sleeve_area,
            ),
        ];
        for (k, what, why, of) in checks {
            let Some(k) = k else { continue };
            let part = &body.parts[k];
            let (Some(given), Some((area, how))) = (part.area, of(&part.geometry)) else {
                continue;
            };
            if (given - area).abs() > 0.01 * area {
                return Err(Refusal::new(
                    format!("parts[{k}].area"),
                    format!(
                        "{what} {how}, {area:.4e} m² per radian, found {given:e} (more than 1 % \
                         off): {why}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// (r₁² − r₀²)/2 over the radii [r₀, r₁] a section spans (m² per radian), and how.
fn tip_area(g: &Geometry) -> Option<(f64, String)> {
    let (lo, hi) = g.bounds(2);
    let (r0, r1) = (lo[0].max(0.0), hi[0]);
    Some((0.5 * (r1 * r1 - r0 * r0), format!("over r = {r0} to {r1} m")))
}

/// ∫ r ds along a section's edges that do not lie across the axis (m² per radian), and
/// how; none for a circle, whose section has no ends.
fn sleeve_area(g: &Geometry) -> Option<(f64, String)> {
    let corners: Vec<[f64; 2]> = match g {
        Geometry::Polygon { vertices } => vertices.iter().map(|v| [v[0], v[1]]).collect(),
        Geometry::Box { min, max } => vec![
            [min[0], min[1]],
            [max[0], min[1]],
            [max[0], max[1]],
            [min[0], max[1]],
        ],
        _ => return None,
    };
    let (lo, hi) = g.bounds(2);
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut area = 0.0;
    for (k, a) in corners.iter().enumerate() {
        let b = corners[(k + 1) % corners.len()];
        let (dr, dz) = (b[0] - a[0], b[1] - a[1]);
        if dz.abs() > 1e-9 * size {
            area += (dr * dr + dz * dz).sqrt() * 0.5 * (a[0] + b[0]);
        }
    }
    Some((area, "along its edges but its ends".to_string()))
}

/// Volume-weighted sums over one slice of the ground: Σ V, Σ V σ_v0, Σ V u0, and over the
/// points with an undrained strength Σ V and Σ V s_u (m³, or m² per radian; stresses Pa).
pub type SliceSums = [f64; 5];

/// The ground a penetrometer enters, as it was the step its push began: per slice one
/// cell thick across the motion, [`SliceSums`] (checkpointed with the body).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InSitu {
    /// The slices' thickness (m): the cell size.
    pub width: f64,
    /// Where the first slice starts along the motion (m, s = x · m̂).
    pub start: f64,
    /// The slices, in order along the motion.
    pub slices: Vec<SliceSums>,
}

/// The ground at one place along the motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    /// σ_v0: total stress along the motion, compression positive (Pa).
    pub total_stress: f64,
    /// u0: the water table's pore pressure (Pa).
    pub pore_pressure: f64,
    /// s_u (Pa), where the soil has one.
    pub undrained_strength: Option<f64>,
}

impl InSitu {
    /// Empty slices of `width` (m) from `start` (m) to `end` (m) along the motion.
    pub fn new(width: f64, start: f64, end: f64) -> Self {
        let n = (((end - start) / width).floor() as usize + 1).max(1);
        InSitu {
            width,
            start,
            slices: vec![[0.0; 5]; n],
        }
    }

    /// Adds a point at `s` (m along the motion) of volume `v` with its σ_v0, u0 and s_u.
    pub fn add(&mut self, s: f64, v: f64, total_stress: f64, pore_pressure: f64, strength: Option<f64>) {
        let k = ((s - self.start) / self.width)
            .floor()
            .clamp(0.0, (self.slices.len() - 1) as f64) as usize;
        let slice = &mut self.slices[k];
        slice[0] += v;
        slice[1] += v * total_stress;
        slice[2] += v * pore_pressure;
        if let Some(su) = strength {
            slice[3] += v;
            slice[4] += v * su;
        }
    }

    /// Where the ground's surface stood along the motion (m): the start of the first slice
    /// that held soil; `None` when none did.
    pub fn surface(&self) -> Option<f64> {
        let k = self.slices.iter().position(|s| s[0] > 0.0)?;
        Some(self.start + k as f64 * self.width)
    }

    /// The ground at `s` (m along the motion): each mean interpolated linearly between the
    /// centres of the nearest slices that hold it, the end slices' beyond them; `None`
    /// where no slice held soil.
    pub fn at(&self, s: f64) -> Option<Ground> {
        let mean = |weight: usize, value: usize| -> Option<f64> {
            let centre = |k: usize| self.start + (k as f64 + 0.5) * self.width;
            let held = |k: usize| self.slices[k][weight] > 0.0;
            let value_of = |k: usize| self.slices[k][value] / self.slices[k][weight];
            let above = (0..self.slices.len()).rev().find(|&k| held(k) && centre(k) <= s);
            let below = (0..self.slices.len()).find(|&k| held(k) && centre(k) > s);
            match (above, below) {
                (Some(a), Some(b)) => {
                    let t = (s - centre(a)) / (centre(b) - centre(a));
                    Some(value_of(a) + t * (value_of(b) - value_of(a)))
                }
                (Some(k), None) | (None, Some(k)) => Some(value_of(k)),
                (None, None) => None,
            }
        };
        Some(Ground {
            total_stress: mean(0, 1)?,
            pore_pressure: mean(0, 2)?,
            undrained_strength: mean(3, 4),
        })
    }
}

/// One static state of the log (`cpt.csv`).
#[derive(Clone, Debug, PartialEq)]
pub struct LogRow {
    /// Step of the static state.
    pub step: u64,
    /// Travel (m).
    pub travel: f64,
    /// The apex's depth below the ground's surface (m).
    pub depth: f64,
    /// q_t (Pa).
    pub tip_resistance: f64,
    /// f_s (Pa).
    pub sleeve_friction: Option<f64>,
    /// u2 (Pa).
    pub pore_pressure: Option<f64>,
    /// The ground at the apex (σ_v0, s_u) and at the filter (u0).
    pub ground: Ground,
    /// N_kt, N_Δu, B_q.
    pub factors: [Option<f64>; 3],
}

/// A piezocone's three readings at one static state, as `curve.csv` holds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readings {
    /// Step of the static state.
    pub step: u64,
    /// Travel (m).
    pub travel: f64,
    /// q_t (Pa): the tip's mean pressure along the motion.
    pub tip: f64,
    /// f_s (Pa): the sleeve's.
    pub sleeve: Option<f64>,
    /// u2 (Pa): the filter's pore pressure.
    pub u2: Option<f64>,
}

/// The row of the log of `body` read as `cpt` at a static state with these `readings`,
/// against the ground it entered (`in_situ`), in `n` dimensions; `None` where the ground
/// held no soil.
pub fn log_row(
    body: &RigidBodySpec,
    cpt: &Cpt,
    in_situ: &InSitu,
    n: usize,
    readings: &Readings,
) -> Option<LogRow> {
    let m = body.motion.as_ref()?;
    let surface = in_situ.surface()?;
    let speed = m.speed();
    let unit: [f64; 3] = m.vector().map(|c| c / speed);
    let along = |x: [f64; 3]| -> f64 { (0..3).map(|a| x[a] * unit[a]).sum() };
    // The apex: the tip's farthest extent along the motion (its bounds' corner: exact for
    // a motion along an axis, as a cone's is).
    let (lo, hi) = body.parts[cpt.tip].geometry.bounds(n);
    let apex = (0..8)
        .map(|c| {
            along(std::array::from_fn(
                |a| if c >> a & 1 == 1 { hi[a] } else { lo[a] },
            ))
        })
        .fold(f64::NEG_INFINITY, f64::max);
    let at_apex = in_situ.at(apex + readings.travel)?;
    let u0 = match cpt.filter {
        Some(k) => {
            let s = along(body.filters[k].place());
            in_situ
                .at(s + readings.travel)
                .map_or(at_apex.pore_pressure, |g| g.pore_pressure)
        }
        None => at_apex.pore_pressure,
    };
    let ground = Ground {
        pore_pressure: u0,
        ..at_apex
    };
    let net = readings.tip - ground.total_stress;
    let excess = readings.u2.map(|u| u - u0);
    let su = ground.undrained_strength.filter(|s| *s > 0.0);
    Some(LogRow {
        step: readings.step,
        travel: readings.travel,
        depth: apex + readings.travel - surface,
        tip_resistance: readings.tip,
        sleeve_friction: readings.sleeve,
        pore_pressure: readings.u2,
        ground,
        factors: [
            su.map(|s| net / s),
            su.zip(excess).map(|(s, e)| e / s),
            excess.filter(|_| net > 0.0).map(|e| e / net),
        ],
    })
}

/// `cpt.csv`: one row a static state; a cell empty where its quantity is undefined.
pub fn log_csv(rows: &[LogRow]) -> String {
    let mut t = String::from("step,travel,depth,q_t,f_s,u2,sigma_v0,u0,s_u,N_kt,N_du,B_q\n");
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.9e}"));
    for r in rows {
        t += &format!(
            "{},{:.9e},{:.9e},{:.9e},{},{},{:.9e},{:.9e},{},{},{},{}\n",
            r.step,
            r.travel,
            r.depth,
            r.tip_resistance,
            opt(r.sleeve_friction),
            opt(r.pore_pressure),
            r.ground.total_stress,
            r.ground.pore_pressure,
            opt(r.ground.undrained_strength),
            opt(r.factors[0]),
            opt(r.factors[1]),
            opt(r.factors[2]),
        );
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ground_between_slices_is_interpolated_and_held_beyond_them() {
        let mut g = InSitu::new(1.0, -10.0, -5.0);
        // Slices [-10,-9) empty, [-9,-8) 100 kPa, [-8,-7) 200 kPa with s_u 20 kPa.
        g.add(-8.5, 2.0, 100e3, 10e3, None);
        g.add(-7.5, 1.0, 200e3, 20e3, Some(20e3));
        assert_eq!(g.surface(), Some(-9.0));
        let mid = g.at(-8.0).unwrap();
        assert!((mid.total_stress - 150e3).abs() < 1e-9);
        assert!((mid.pore_pressure - 15e3).abs() < 1e-9);
        assert_eq!(mid.undrained_strength, Some(20e3));
        assert_eq!(g.at(-20.0).unwrap().total_stress, 100e3);
        assert_eq!(g.at(0.0).unwrap().total_stress, 200e3);
        assert_eq!(InSitu::new(1.0, 0.0, 3.0).at(1.0), None);
    }

    /// A cone pushed down y: the apex's depth below the ground's top, σ_v0 and s_u at the
    /// apex, u0 at the filter (higher, so less), and the three factors from them; B_q
    /// left out where q_t does not exceed σ_v0.
    #[test]
    fn a_row_of_the_log_reads_the_ground_at_the_apex_and_u0_at_the_filter() {
        let body: RigidBodySpec = ron::from_str(
            r#"(name: "cone", parts: [
                (name: "tip", geometry: Polygon(vertices: [[0.0, 9.0], [0.5, 10.0], [0.0, 10.0]]), area: Some(0.125)),
                (name: "sleeve", geometry: Polygon(vertices: [[0.0, 10.0], [0.5, 10.0], [0.5, 12.0], [0.0, 12.0]]), area: Some(1.0))],
                filters: [(name: "u2", at: [0.5, 10.0])],
                motion: Some((velocity: [0.0, -0.1], travel: 2.0)),
                cpt: Some((tip: "tip", sleeve: Some("sleeve"), u2: Some("u2"))))"#,
        )
        .unwrap();
        let cpt = body.cpt.as_ref().unwrap().check(&body).unwrap();
        assert_eq!((cpt.tip, cpt.sleeve, cpt.filter), (0, Some(1), Some(0)));
        // Ground from y = 10.5 (s = −10.5) down: σ_v0 = 20 kPa a metre, u0 = 10 kPa a metre,
        // s_u = 5 kPa a metre, one point at each slice's centre.
        let mut g = InSitu::new(0.5, -10.5, 0.0);
        for k in 0..21 {
            let s = -10.5 + 0.5 * (k as f64 + 0.5);
            let depth = s + 10.5;
            g.add(s, 1.0, 20e3 * depth, 10e3 * depth, Some(5e3 * depth));
        }
        let readings = Readings {
            step: 7,
            travel: 1.0,
            tip: 500e3,
            sleeve: Some(10e3),
            u2: Some(100e3),
        };
        let row = log_row(&body, &cpt, &g, 2, &readings).unwrap();
        // Apex at y = 9 − 1 = 8: 2.5 m below the top; the filter at y = 9: 1.5 m.
        assert!((row.depth - 2.5).abs() < 1e-12);
        assert!((row.ground.total_stress - 50e3).abs() < 1e-6);
        assert!((row.ground.pore_pressure - 15e3).abs() < 1e-6);
        assert!((row.ground.undrained_strength.unwrap() - 12.5e3).abs() < 1e-6);
        let [n_kt, n_du, b_q] = row.factors.map(Option::unwrap);
        assert!((n_kt - 450e3 / 12.5e3).abs() < 1e-9);
        assert!((n_du - 85e3 / 12.5e3).abs() < 1e-9);
        assert!((b_q - 85e3 / 450e3).abs() < 1e-12);
        let below = Readings {
            tip: 40e3,
            ..readings
        };
        assert_eq!(log_row(&body, &cpt, &g, 2, &below).unwrap().factors[2], None);
    }
}
