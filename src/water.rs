//! Pore water (`water` in a scene): piezometric surfaces, drained and static.
//!
//! Below its material's piezometric surface a point carries the pore pressure
//! u = γ_w (h(x) − z) (Pa, compression positive), where z is its current height along
//! gravity's axis and h(x) the surface's height above the point's place across it (the
//! convention of limit-equilibrium programs); above it, u = 0 (no suction). The points'
//! `Stress` is the effective stress σ′, on which the materials act; the total stress is
//! σ = σ′ − u I (tension positive).
//!
//! Balance. With σ = σ′ − u I, the weak form's −∫ σ:∇w dV splits into −∫ σ′:∇w dV (what
//! `p2g` maps) and +∫ u ∇·w dV = ∮ u w·n dS − ∫ w·∇u dV. The surface term is the pressure of
//! open water on the ground wherever the surface stands above it; with it applied as load,
//! what is left is the body force −∇u = γ_w (e_z − ∇h) below the surface: buoyancy, plus a
//! seepage force where the surface slopes. `p2g` maps that body force (Σ_p V_p w_ip (−∇u_p))
//! with the stress, as applied load. So a submerged slope face carries γ_w · depth
//! normal to itself without the engine having to find the face, exactly as
//! Archimedes has it, and a table below the ground leaves its surface load-free. On the
//! grid's held faces the same term is part of the reaction.
//!
//! A point astride its surface counts as submerged by the share of its height below it,
//! for its buoyancy and its weight alike. Points below their surface at set-up weigh their
//! material's saturated density; a stage that moves a surface weighs again the points it
//! crosses ([`Water::density_ratio`]). A point that moves keeps its mass: soil that settles
//! below a table is buoyed up, but not wetted.

use crate::error::Refusal;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::Arc;

/// A piezometric surface: the height (m, up gravity's axis) the water stands at above each
/// place across that axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Surface {
    /// Level at this height.
    Level(f64),
    /// In 2D: the heights at increasing x, [x, height] each, straight between them. It must
    /// span the grid across.
    Polyline(Vec<Vec<f64>>),
    /// In 3D: heights on a regular grid over the two axes across gravity's (in axis order:
    /// for gravity along z, x then y), bilinear between its nodes. It must span the grid
    /// across.
    Heights {
        /// The first node's place (m), two entries.
        origin: Vec<f64>,
        /// Node spacing along each axis (m), two entries.
        spacing: Vec<f64>,
        /// Heights (m): one row per node along the second axis, each row along the first.
        heights: Vec<Vec<f64>>,
    },
}

/// The water as the scene gives it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterSpec {
    /// Unit weight of water γ_w (N/m³).
    #[serde(default = "default_unit_weight")]
    pub unit_weight: f64,
    /// The piezometric surface of every material `material_tables` leaves out.
    pub table: Surface,
    /// Materials with their own piezometric surface (a perched table in a clay layer), by
    /// material name.
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub material_tables: BTreeMap<String, Surface>,
    /// Saturated density of each material that has points below its surface (kg/m³, at
    /// least its dry density).
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub saturated_density: BTreeMap<String, f64>,
}

/// What a stage changes of the water: every surface (the unit weight and the saturated
/// densities stay the scene's).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageWaterSpec {
    /// The piezometric surface of every material `material_tables` leaves out.
    pub table: Surface,
    /// Materials with their own piezometric surface, by material name.
    #[serde(default, deserialize_with = "crate::unique_map::deserialize")]
    pub material_tables: BTreeMap<String, Surface>,
}

fn default_unit_weight() -> f64 {
    9810.0
}

/// A checked surface, ready to evaluate.
#[derive(Clone, Debug, PartialEq)]
enum Head {
    Level(f64),
    /// The knots' places (strictly increasing) and each segment's start height and slope
    /// (segment j runs from knot j to knot j + 1).
    Polyline {
        x: Vec<f64>,
        segments: Vec<[f64; 2]>,
    },
    /// Origin, 1/spacing, node counts, heights row-major (second axis outer).
    Heights {
        origin: [f64; 2],
        inv_spacing: [f64; 2],
        nodes: [usize; 2],
        h: Vec<f64>,
    },
}

impl Head {
    /// The lowest and highest height (m) and the steepest slope of the surface.
    fn extremes(&self) -> (f64, f64, f64) {
        let span = |h: &mut dyn Iterator<Item = f64>| {
            h.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
        };
        match self {
            Head::Level(h) => (*h, *h, 0.0),
            Head::Polyline { x, segments } => {
                let ends = segments
                    .iter()
                    .zip(x.windows(2))
                    .flat_map(|(s, k)| [s[0], s[0] + s[1] * (k[1] - k[0])]);
                let (lo, hi) = span(&mut ends.into_iter());
                (lo, hi, segments.iter().fold(0.0f64, |m, s| m.max(s[1].abs())))
            }
            Head::Heights {
                inv_spacing,
                nodes,
                h,
                ..
            } => {
                let (lo, hi) = span(&mut h.iter().copied());
                let mut steep = 0.0f64;
                for j in 0..nodes[1] {
                    for i in 0..nodes[0] {
                        let at = |i: usize, j: usize| h[j * nodes[0] + i];
                        if i + 1 < nodes[0] {
                            steep = steep.max(((at(i + 1, j) - at(i, j)) * inv_spacing[0]).abs());
                        }
                        if j + 1 < nodes[1] {
                            steep = steep.max(((at(i, j + 1) - at(i, j)) * inv_spacing[1]).abs());
                        }
                    }
                }
                (lo, hi, steep)
            }
        }
    }

    /// The height h and its slope ∂h/∂s along each axis across, at the place `s`.
    #[inline(always)]
    fn at(&self, s: [f64; 2]) -> (f64, [f64; 2]) {
        match self {
            Head::Level(h) => (*h, [0.0; 2]),
            Head::Polyline { x, segments } => {
                // The segment holding s (checked: the knots span the grid). A scan, not a
                // search: a polyline has few knots, and points come in cell order, so the
                // branch is predicted.
                let mut j = 0;
                while j + 1 < segments.len() && x[j + 1] <= s[0] {
                    j += 1;
                }
                let [h0, slope] = segments[j];
                (slope.mul_add(s[0] - x[j], h0), [slope, 0.0])
            }
            Head::Heights {
                origin,
                inv_spacing,
                nodes,
                h,
            } => {
                let mut cell = [0usize; 2];
                let mut t = [0.0; 2];
                for a in 0..2 {
                    let u = ((s[a] - origin[a]) * inv_spacing[a]).clamp(0.0, (nodes[a] - 1) as f64);
                    cell[a] = (u.floor() as usize).min(nodes[a] - 2);
                    t[a] = u - cell[a] as f64;
                }
                let at = |i: usize, j: usize| h[(cell[1] + j) * nodes[0] + cell[0] + i];
                let (h00, h10, h01, h11) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
                let value = h00 * (1.0 - t[0]) * (1.0 - t[1])
                    + h10 * t[0] * (1.0 - t[1])
                    + h01 * (1.0 - t[0]) * t[1]
                    + h11 * t[0] * t[1];
                let d0 = ((h10 - h00) * (1.0 - t[1]) + (h11 - h01) * t[1]) * inv_spacing[0];
                let d1 = ((h01 - h00) * (1.0 - t[0]) + (h11 - h10) * t[0]) * inv_spacing[1];
                (value, [d0, d1])
            }
        }
    }
}

/// The water as the run uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct Water {
    /// γ_w (N/m³).
    pub unit_weight: f64,
    /// Gravity's axis (gravity points along −axis).
    pub axis: usize,
    /// The axes across gravity's, in order (the third is unused in 2D).
    across: [usize; 2],
    /// 2 or 3.
    dims: usize,
    /// Volumes are per radian (axisymmetry, x the radius): a point's height comes from its
    /// area, V / r.
    axisymmetric: bool,
    /// The surfaces, and each material's (by `MaterialId`).
    heads: Arc<[Head]>,
    of_material: Arc<[u16]>,
    /// Density ratio ρ_sat/ρ_dry of each material (1 without a saturated density).
    wet_ratio: Arc<[f64]>,
    /// Saturated density of each material (kg/m³; 0 without one): a stage that changes a
    /// material's dry density keeps it.
    saturated: Arc<[f64]>,
    /// γ_w as the scene gives it (N/m³), under the scene's gravity, whose entry along
    /// `axis` is `given_gravity` (m/s², negative): γ_w = ρ_w |g| follows the gravity in
    /// force ([`Water::follow_gravity`]).
    given_unit_weight: f64,
    given_gravity: f64,
}

/// The largest pore pressure or seepage force (Pa, N/m³) a surface may give: the bound on
/// any stiffness a scene takes (a Young's modulus of 1e15 Pa).
const MOST_PRESSURE: f64 = 1e15;

impl Water {
    /// Sets γ_w for the gravity `g` (m/s², x y z) in force: the scene's γ_w times
    /// g_axis / g_axis of the scene's gravity (the check refuses a gravity that turns from
    /// the water's axis). Idempotent: from the scene's γ_w each time.
    pub fn follow_gravity(&mut self, g: [f64; 3]) {
        let ratio = g[self.axis] / self.given_gravity;
        self.unit_weight = if ratio == 1.0 {
            self.given_unit_weight
        } else {
            self.given_unit_weight * ratio
        };
    }

    /// Why gravity `g` (m/s², one entry an axis) cannot act on this water, if it cannot:
    /// it points down the water's axis, as the scene's does, or is 0. The surfaces are
    /// heights up that axis and do not turn; γ_w follows |g| ([`Self::follow_gravity`]).
    pub fn gravity_fault(&self, g: &[f64]) -> Option<String> {
        let axis = self.axis;
        let turned = (0..g.len()).any(|a| if a == axis { g[a] > 0.0 } else { g[a] != 0.0 });
        turned.then(|| {
            format!(
                "{g:?} under the scene's water: gravity points down axis {axis}, as the scene's \
                 does, or is 0 (the piezometric surfaces are heights up that axis, and γ_w \
                 follows |g|)"
            )
        })
    }

    /// The surface's height above `x` and its slopes, for a point of `material`.
    #[inline(always)]
    fn head(&self, material: u16, x: [f64; 3]) -> (f64, [f64; 2]) {
        let s = [x[self.across[0]], x[self.across[1]]];
        self.heads[self.of_material[material as usize] as usize].at(s)
    }

    /// The height (m, up gravity's axis) of `material`'s piezometric surface above the place
    /// across gravity of `x`.
    pub fn table_height(&self, material: u16, x: [f64; 3]) -> f64 {
        self.head(material, x).0
    }

    /// Pore pressure at `x` in `material` (Pa, compression positive): γ_w times the depth
    /// below its piezometric surface, 0 above it.
    #[inline(always)]
    pub fn pore_pressure(&self, material: u16, x: [f64; 3]) -> f64 {
        self.unit_weight * (self.head(material, x).0 - x[self.axis]).max(0.0)
    }

    /// The share of a point of volume `volume` whose centre lies `depth` below its surface
    /// that is below it: 0 to 1, linear across the point's height (its volume taken as a
    /// square, a cube in 3D) with the surface taken level across the point, so that a point
    /// crossing the surface gains its buoyancy gradually rather than all at once.
    #[inline(always)]
    fn submerged(&self, depth: f64, volume: f64, x: [f64; 3]) -> f64 {
        let volume = if self.axisymmetric { volume / x[0] } else { volume };
        // |depth| ≥ side/2 without the root: 4 d² ≥ V in 2D, 8 |d|³ ≥ V in 3D.
        let clear = if self.dims == 2 {
            4.0 * depth * depth >= volume
        } else {
            8.0 * (depth * depth * depth).abs() >= volume
        };
        if clear {
            return if depth > 0.0 { 1.0 } else { 0.0 };
        }
        let side = if self.dims == 2 {
            volume.sqrt()
        } else {
            volume.cbrt()
        };
        (depth / side + 0.5).clamp(0.0, 1.0)
    }

    /// The body force −∇u (N/m³) on a point at `x` in `material` of volume `volume` (m³;
    /// m² in 2D): γ_w (e_axis − ∇h) times its submerged share (buoyancy and seepage), zero
    /// above the surface.
    #[inline(always)]
    pub fn body_force(&self, material: u16, x: [f64; 3], volume: f64) -> [f64; 3] {
        let (h, slope) = self.head(material, x);
        let mut f = [0.0; 3];
        let share = self.submerged(h - x[self.axis], volume, x);
        if share > 0.0 {
            let g = self.unit_weight * share;
            f[self.axis] = g;
            f[self.across[0]] = -g * slope[0];
            if self.dims == 3 {
                f[self.across[1]] = -g * slope[1];
            }
        }
        f
    }

    /// True when some of a point at `x` of volume `volume` lies below its surface.
    pub fn wets(&self, material: u16, x: [f64; 3], volume: f64) -> bool {
        self.submerged(self.head(material, x).0 - x[self.axis], volume, x) > 0.0
    }

    /// A point's density over its material's dry density: 1 + s (ρ_sat/ρ_dry − 1) for its
    /// submerged share s at `x` (volume `volume`).
    pub fn density_factor(&self, material: u16, x: [f64; 3], volume: f64) -> f64 {
        let share = self.submerged(self.head(material, x).0 - x[self.axis], volume, x);
        1.0 + share * (self.wet_ratio[material as usize] - 1.0)
    }

    /// The factor a point's mass changes by when its material's dry density goes from `old`
    /// to `new` (kg/m³) and its saturated density stays: (ρ′ + s (ρ_sat − ρ′)) / (ρ + s
    /// (ρ_sat − ρ)) for its submerged share s at its current place `x` (volume `volume`);
    /// ρ′/ρ for a material without a saturated density.
    pub fn reweigh_ratio(&self, material: u16, x: [f64; 3], volume: f64, old: f64, new: f64) -> f64 {
        let sat = self.saturated[material as usize];
        if sat == 0.0 {
            return new / old;
        }
        let share = self.submerged(self.head(material, x).0 - x[self.axis], volume, x);
        (new + share * (sat - new)) / (old + share * (sat - old))
    }

    /// The saturated density of `material` (kg/m³), if it has one.
    pub fn saturated_density(&self, material: u16) -> Option<f64> {
        Some(self.saturated[material as usize]).filter(|&s| s > 0.0)
    }

    /// The factor a point's mass changes by when the water goes from `self` to `next`, judged
    /// at the point's current place `x` (volume `volume`).
    pub fn density_ratio(&self, next: &Water, material: u16, x: [f64; 3], volume: f64) -> f64 {
        next.density_factor(material, x, volume) / self.density_factor(material, x, volume)
    }

    /// The same water with the surfaces of `stage`.
    pub fn with_surfaces(&self, stage: &Water) -> Water {
        Water {
            heads: stage.heads.clone(),
            of_material: stage.of_material.clone(),
            ..self.clone()
        }
    }
}

/// Checks `surface` for a grid spanning `lo..hi` across gravity (`across` axes, `n` of them)
/// and turns it into a [`Head`].
fn head(surface: &Surface, n: usize, lo: [f64; 2], hi: [f64; 2]) -> Result<Head, Refusal> {
    let bad = |f: &str, r: String| Err(Refusal::new(f.to_string(), r));
    match surface {
        Surface::Level(h) if h.is_finite() => Ok(Head::Level(*h)),
        Surface::Level(h) => bad("", format!("must be a finite height (m), found {h}")),
        Surface::Polyline(_) if n != 1 => bad(
            "",
            "a Polyline is a 2D surface: in 3D give Heights (a height grid) or a Level".into(),
        ),
        Surface::Polyline(k) => {
            if k.len() < 2 || k.iter().any(|p| p.len() != 2) || k.iter().flatten().any(|v| !v.is_finite()) {
                return bad("", "needs at least two points [x, height], finite numbers".into());
            }
            let k: Vec<[f64; 2]> = k.iter().map(|p| [p[0], p[1]]).collect();
            if let Some(j) = (1..k.len()).find(|&j| k[j][0] <= k[j - 1][0]) {
                return bad(
                    "",
                    format!(
                        "is not a function of x: point {j} (x = {}) does not lie to the right of \
                         point {} (x = {}); give the points at strictly increasing x",
                        k[j][0],
                        j - 1,
                        k[j - 1][0]
                    ),
                );
            }
            let (first, last) = (k[0][0], k[k.len() - 1][0]);
            if first > lo[0] || last < hi[0] {
                return bad(
                    "",
                    format!(
                        "spans x = {first} to {last} m but the grid spans {} to {} m: the \
                         surface must reach across the whole grid",
                        lo[0], hi[0]
                    ),
                );
            }
            Ok(Head::Polyline {
                x: k.iter().map(|p| p[0]).collect(),
                segments: k
                    .windows(2)
                    .map(|w| [w[0][1], (w[1][1] - w[0][1]) / (w[1][0] - w[0][0])])
                    .collect(),
            })
        }
        Surface::Heights { .. } if n != 2 => bad(
            "",
            "a height grid is a 3D surface: in 2D give a Polyline or a Level".into(),
        ),
        Surface::Heights {
            origin,
            spacing,
            heights,
        } => {
            let rows = heights.len();
            let cols = heights.first().map_or(0, Vec::len);
            if rows < 2 || cols < 2 || heights.iter().any(|r| r.len() != cols) {
                return bad(
                    "heights",
                    "needs at least two rows of at least two heights, every row as long".into(),
                );
            }
            if origin.len() != 2 || spacing.len() != 2 {
                return bad("origin", "origin and spacing need two entries each".into());
            }
            if heights.iter().flatten().any(|h| !h.is_finite()) || !origin.iter().all(|o| o.is_finite()) {
                return bad("heights", "heights and origin must be finite".into());
            }
            if !spacing.iter().all(|s| s.is_finite() && *s > 0.0) {
                return bad("spacing", format!("must be above 0 m, found {:?}", spacing));
            }
            let nodes = [cols, rows];
            for a in 0..2 {
                let end = origin[a] + spacing[a] * (nodes[a] - 1) as f64;
                if origin[a] > lo[a] || end < hi[a] {
                    return bad(
                        "",
                        format!(
                            "spans {} to {end} m along its axis {a} but the grid spans {} to {} \
                             m: the surface must reach across the whole grid",
                            origin[a], lo[a], hi[a]
                        ),
                    );
                }
            }
            Ok(Head::Heights {
                origin: [origin[0], origin[1]],
                inv_spacing: [1.0 / spacing[0], 1.0 / spacing[1]],
                nodes,
                h: heights.iter().flatten().copied().collect(),
            })
        }
    }
}

/// The axis gravity `g` (m/s², one entry an axis) points down, when it points down exactly
/// one (a negative entry, the others 0): the vertical that heights, and the weight of the
/// ground above a point, are measured along.
pub fn down_axis(g: &[f64]) -> Option<usize> {
    let mut along = (0..g.len()).filter(|&a| g[a] != 0.0);
    match (along.next(), along.next()) {
        (Some(a), None) if g[a] < 0.0 => Some(a),
        _ => None,
    }
}

/// What checking the water needs to know of the scene.
pub struct Frame<'a> {
    /// The scene's gravity (one entry an axis), if any.
    pub gravity: Option<&'a [f64]>,
    /// The grid's lowest corner (m), one entry an axis.
    pub lo: &'a [f64],
    /// The grid's highest corner (m).
    pub hi: &'a [f64],
    /// The materials' names and dry densities, in `MaterialId` order.
    pub materials: &'a [(&'a str, f64)],
    /// The scene is axisymmetric (volumes per radian).
    pub axisymmetric: bool,
}

impl Frame<'_> {
    /// Gravity's axis: gravity must point down one axis.
    fn axis(&self) -> Result<usize, Refusal> {
        let Some(g) = self.gravity else {
            return Err(Refusal::new(
                String::new(),
                "pore pressure is hydrostatic: the scene needs gravity".into(),
            ));
        };
        down_axis(g).ok_or_else(|| {
            Refusal::new(
                "gravity.acceleration",
                "with water, gravity points down one axis (a negative entry, the others 0): \
                 heights are measured up that axis"
                    .into(),
            )
        })
    }

    /// The surfaces `table` and `material_tables` checked against the grid and the
    /// materials: (heads, each material's head). Fields are relative to the water.
    fn heads(
        &self,
        axis: usize,
        unit_weight: f64,
        table: &Surface,
        material_tables: &BTreeMap<String, Surface>,
    ) -> Result<(Vec<Head>, Vec<u16>), Refusal> {
        let n = self.lo.len();
        let across: Vec<usize> = (0..n).filter(|&a| a != axis).collect();
        let (mut lo, mut hi) = ([0.0; 2], [0.0; 2]);
        for (k, &a) in across.iter().enumerate() {
            (lo[k], hi[k]) = (self.lo[a], self.hi[a]);
        }
        // Pore pressures and seepage forces a run can hold: γ_w |h − z| and γ_w |∇h| at
        // most 1e15 (a table 1e306 m up would write pore pressures of inf).
        let bounded = |f: &str, h: Head| -> Result<Head, Refusal> {
            let (low, high, steep) = h.extremes();
            let base = self.lo[axis];
            let depth = (high - base).abs().max((low - base).abs());
            let (pressure, seepage) = (unit_weight * depth, unit_weight * steep);
            let within = |v: f64| v.is_finite() && v <= MOST_PRESSURE;
            if !within(pressure) || !within(seepage) {
                return Err(Refusal::new(
                    f.to_string(),
                    format!(
                        "a pore pressure γ_w |h − z| or seepage force γ_w |∇h| above 1e15 (the \
                         surface reaches {high} m, {} m above the grid's bottom, and slopes up to \
                         {steep}): give heights near the ground",
                        high - base
                    ),
                ));
            }
            Ok(h)
        };
        let first = head(table, n - 1, lo, hi).map_err(|e| e.under("table"))?;
        let mut heads = vec![bounded("table", first)?];
        let mut of_material = vec![0u16; self.materials.len()];
        for (name, surface) in material_tables {
            let field = format!("material_tables.{name}");
            let Some(m) = self.materials.iter().position(|(n, _)| n == name) else {
                return Err(Refusal::new(
                    field,
                    format!("the scene has no material \"{name}\""),
                ));
            };
            of_material[m] = heads.len() as u16;
            let h = head(surface, n - 1, lo, hi).map_err(|e| e.under(&field))?;
            heads.push(bounded(&field, h)?);
        }
        Ok((heads, of_material))
    }

    fn across(axis: usize, n: usize) -> [usize; 2] {
        let a: Vec<usize> = (0..3).filter(|&a| a != axis).collect();
        // In 2D the second axis across is z, which no point moves along.
        if n == 2 {
            [a[0], 2]
        } else {
            [a[0], a[1]]
        }
    }
}

impl WaterSpec {
    /// The checked water of a scene framed by `frame`, or the [`Refusal`] of a field under
    /// `water` (one that starts with `gravity` is the scene's own).
    pub fn checked(&self, frame: &Frame) -> Result<Water, Refusal> {
        if !(self.unit_weight.is_finite() && self.unit_weight > 0.0) {
            return Err(Refusal::new(
                "unit_weight",
                format!("must be above 0 N/m³, found {}", self.unit_weight),
            ));
        }
        let axis = frame.axis()?;
        let water_density = self.unit_weight / frame.gravity.expect("gravity has an axis")[axis].abs();
        let mut wet_ratio = vec![1.0; frame.materials.len()];
        let mut saturated = vec![0.0; frame.materials.len()];
        for (name, &rho) in &self.saturated_density {
            let field = format!("saturated_density.{name}");
            let Some(m) = frame.materials.iter().position(|(n, _)| n == name) else {
                return Err(Refusal::new(
                    field,
                    format!("the scene has no material \"{name}\""),
                ));
            };
            let dry = frame.materials[m].1;
            if !(rho.is_finite() && rho >= dry) {
                return Err(Refusal::new(
                    field,
                    format!("must be at least the material's dry density ({dry} kg/m³), found {rho}"),
                ));
            }
            // ρ_sat = ρ_d + n ρ_w with a porosity n ≤ 1; ρ_w = γ_w/|g|.
            let most = dry + water_density;
            if rho > most {
                return Err(Refusal::new(
                    field,
                    format!(
                        "must be at most the dry density plus the water's, {dry} + {water_density} = \
                         {most} kg/m³ (a soil holds at most its own volume of water), found {rho}"
                    ),
                ));
            }
            wet_ratio[m] = rho / dry;
            saturated[m] = rho;
        }
        let (heads, of_material) = frame.heads(axis, self.unit_weight, &self.table, &self.material_tables)?;
        Ok(Water {
            unit_weight: self.unit_weight,
            axis,
            across: Frame::across(axis, frame.lo.len()),
            dims: frame.lo.len(),
            axisymmetric: frame.axisymmetric,
            heads: heads.into(),
            of_material: of_material.into(),
            wet_ratio: wet_ratio.into(),
            saturated: saturated.into(),
            given_unit_weight: self.unit_weight,
            given_gravity: frame.gravity.map_or(-1.0, |g| g[axis]),
        })
    }
}

impl StageWaterSpec {
    /// The scene's `water` with this stage's surfaces, or the [`Refusal`] of a field under
    /// the stage's `water`.
    pub fn checked(&self, water: &Water, frame: &Frame) -> Result<Water, Refusal> {
        let (heads, of_material) = frame.heads(
            water.axis,
            water.given_unit_weight,
            &self.table,
            &self.material_tables,
        )?;
        Ok(Water {
            heads: heads.into(),
            of_material: of_material.into(),
            ..water.clone()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_2d<'a>(materials: &'a [(&'a str, f64)]) -> Frame<'a> {
        Frame {
            gravity: Some(&[0.0, -9.81]),
            lo: &[0.0, 0.0],
            hi: &[20.0, 10.0],
            materials,
            axisymmetric: false,
        }
    }

    fn spec(table: Surface) -> WaterSpec {
        WaterSpec {
            unit_weight: 10.0e3,
            table,
            material_tables: BTreeMap::new(),
            saturated_density: BTreeMap::new(),
        }
    }

    #[test]
    fn the_pore_pressure_is_hydrostatic_below_a_level_table_and_zero_above() {
        let m = [("soil", 2000.0)];
        let w = spec(Surface::Level(5.0)).checked(&frame_2d(&m)).unwrap();
        assert_eq!(w.pore_pressure(0, [0.0, 2.0, 0.0]), 30.0e3);
        assert_eq!(w.pore_pressure(0, [0.0, 6.0, 0.0]), 0.0);
        assert_eq!(w.body_force(0, [3.0, 2.0, 0.0], 0.25), [0.0, 10.0e3, 0.0]);
        assert_eq!(w.body_force(0, [3.0, 6.0, 0.0], 0.25), [0.0; 3]);
        // A point astride the table: a quarter of it below, a quarter of its buoyancy.
        assert_eq!(w.body_force(0, [3.0, 5.125, 0.0], 0.25), [0.0, 2.5e3, 0.0]);
    }

    /// A polyline's pressure is γ_w times the vertical height below it; its slope adds a
    /// seepage force −γ_w dh/dx across.
    #[test]
    fn a_sloping_polyline_gives_vertical_head_and_a_seepage_force() {
        let m = [("soil", 2000.0)];
        let line = Surface::Polyline(vec![vec![-1.0, 8.0], vec![10.0, 8.0], vec![21.0, 2.5]]);
        let w = spec(line).checked(&frame_2d(&m)).unwrap();
        assert_eq!(w.pore_pressure(0, [5.0, 3.0, 0.0]), 50.0e3);
        assert!((w.pore_pressure(0, [15.5, 1.0, 0.0]) - 42.5e3).abs() < 1e-9);
        let f = w.body_force(0, [15.5, 1.0, 0.0], 0.25);
        assert!(
            (f[0] - 5.0e3).abs() < 1e-9 && f[1] == 10.0e3 && f[2] == 0.0,
            "{f:?}"
        );
    }

    #[test]
    fn a_height_grid_is_bilinear_between_its_nodes() {
        let m = [("soil", 2000.0)];
        let frame = Frame {
            gravity: Some(&[0.0, 0.0, -9.81]),
            lo: &[0.0, 0.0, 0.0],
            hi: &[2.0, 2.0, 10.0],
            materials: &m,
            axisymmetric: false,
        };
        let grid = Surface::Heights {
            origin: vec![0.0, 0.0],
            spacing: vec![2.0, 2.0],
            heights: vec![vec![4.0, 6.0], vec![8.0, 10.0]],
        };
        let w = spec(grid).checked(&frame).unwrap();
        // h(1, 1) = 7, ∂h/∂x = 1, ∂h/∂y = 2.
        assert!((w.pore_pressure(0, [1.0, 1.0, 0.0]) - 70.0e3).abs() < 1e-9);
        let f = w.body_force(0, [1.0, 1.0, 0.0], 0.125);
        assert!((f[0] + 10.0e3).abs() < 1e-9 && (f[1] + 20.0e3).abs() < 1e-9 && f[2] == 10.0e3);
    }

    #[test]
    fn surfaces_that_are_not_functions_or_do_not_span_the_grid_are_refused() {
        let m = [("soil", 2000.0)];
        let f = frame_2d(&m);
        let back = spec(Surface::Polyline(vec![
            vec![0.0, 5.0],
            vec![12.0, 5.0],
            vec![11.0, 4.0],
            vec![20.0, 4.0],
        ]));
        let Refusal { field, rule } = back.checked(&f).unwrap_err();
        assert_eq!(field, "table");
        assert!(rule.contains("not a function of x"), "{rule}");
        let short = spec(Surface::Polyline(vec![vec![0.0, 5.0], vec![15.0, 5.0]]));
        assert!(short
            .checked(&f)
            .unwrap_err()
            .rule
            .contains("reach across the whole grid"));
    }
}
