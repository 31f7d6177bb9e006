//! The stress a body's points start at (`bodies[i].initial_stress`): an isotropic pressure
//! (a weightless soil under a confining pressure) or a geostatic state (the K0 procedure of
//! geotechnical codes: the weight of the ground above, the water's pressure taken off).
//!
//! Geostatic: at a point at height z (up gravity's axis) the total vertical stress is
//!
//!   σ_v = s + γ_w max(0, H_top − z_top) + Σ_bodies ∫_z^top ρ(z′) |g| dz′,
//!
//! s the surcharge, z_top the ground above the point (the highest body surface on the
//! vertical through it) and H_top the piezometric height of that ground's material; ρ is a
//! body's dry density above its material's piezometric surface and its saturated density
//! below (`water.saturated_density`). The pore pressure u is the water's at the point
//! ([`crate::water::Water::pore_pressure`]), σ′_v = σ_v − u (floored at 0) and every axis
//! across gravity's carries σ′_h = K0 σ′_v (in plane strain the out-of-plane stress, in
//! axisymmetry the hoop stress, too); no shear. The points' `Stress` is effective, so this
//! is what they hold. On level ground it balances gravity and the water at once; under a
//! slope or a step it does not (no K0 state does), and the first stage's relaxation finds
//! the balance from it. Rigid bodies are not ground: the soil under a body placed at the
//! surface starts as if the body were not there.

use crate::error::Refusal;
use crate::scene::region::region_contains;
use crate::scene::spec::Region;
use crate::tensor::Sym3;
use crate::water::Water;
use serde::{Deserialize, Serialize};

/// The stress a body's points start at.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum InitialStress {
    /// σ = −p I (Pa, compression positive): a weightless soil under a confining pressure;
    /// balance it with a traction on the free faces.
    Isotropic(f64),
    /// The ground's own weight (K0 procedure, see the module): σ′_v from the soil above,
    /// buoyant below the water table, σ′_h = K0 σ′_v. The scene needs gravity, at full
    /// strength from the start.
    Geostatic {
        /// K0 = σ′_h/σ′_v (> 0): 1 − sin φ′ for a normally consolidated soil (Jáky), times
        /// OCR^sin φ′ for an overconsolidated one (Mayne & Kulhawy 1982).
        k0: f64,
        /// A vertical stress on the ground's surface (Pa, ≥ 0), carried all the way down;
        /// balance it with a traction or a pressure on the surface.
        #[serde(default)]
        surcharge: f64,
    },
}

impl InitialStress {
    /// The rules the stress holds by itself, fields relative to it.
    pub fn check(&self) -> Result<(), Refusal> {
        match *self {
            InitialStress::Isotropic(p) if !(p.is_finite() && p >= 0.0) => Err(Refusal::new(
                "",
                format!("an Isotropic pressure is a finite pressure ≥ 0 Pa, found {p}"),
            )),
            InitialStress::Geostatic { k0, .. } if !(k0.is_finite() && k0 > 0.0 && k0 <= 10.0) => {
                Err(Refusal::new(
                    "k0",
                    format!("K0 = σ′_h/σ′_v is a finite ratio in (0, 10], found {k0}"),
                ))
            }
            InitialStress::Geostatic { surcharge, .. } if !(surcharge.is_finite() && surcharge >= 0.0) => {
                Err(Refusal::new(
                    "surcharge",
                    format!("a finite vertical stress ≥ 0 Pa, found {surcharge}"),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// One body as the ground above a point sees it.
pub(super) struct Layer<'a> {
    /// Its region.
    pub region: &'a Region,
    /// Its material (`MaterialId`) and dry density (kg/m³).
    pub material: u16,
    pub density: f64,
}

/// What the geostatic states of a scene's bodies are worked out from: every body, gravity
/// and the water.
pub(super) struct Ground<'a> {
    /// Every body of the scene.
    pub layers: Vec<Layer<'a>>,
    /// Gravity's axis (gravity points down it) and |g| (m/s²).
    pub axis: usize,
    pub gravity: f64,
    /// The water, if any.
    pub water: Option<&'a Water>,
    /// 2 or 3 axes.
    pub n: usize,
}

impl Ground<'_> {
    /// The stress (Pa, tension positive) a point of `material` at `x` starts at.
    pub fn stress(&self, spec: &InitialStress, material: u16, x: [f64; 3]) -> Sym3 {
        match *spec {
            InitialStress::Isotropic(p) => Sym3 {
                xx: -p,
                yy: -p,
                zz: -p,
                ..Sym3::ZERO
            },
            InitialStress::Geostatic { k0, surcharge } => {
                let v = self.effective_vertical(material, x, surcharge);
                let mut s = Sym3 {
                    xx: -k0 * v,
                    yy: -k0 * v,
                    zz: -k0 * v,
                    ..Sym3::ZERO
                };
                match self.axis {
                    0 => s.xx = -v,
                    1 => s.yy = -v,
                    _ => s.zz = -v,
                }
                s
            }
        }
    }

    /// σ′_v (Pa, compression positive, ≥ 0) at `x` in `material` under `surcharge` (Pa).
    fn effective_vertical(&self, material: u16, x: [f64; 3], surcharge: f64) -> f64 {
        let z = x[self.axis];
        let mut total = surcharge;
        // The ground above x: its highest surface and that body's material.
        let mut top: Option<(f64, u16)> = None;
        for layer in &self.layers {
            let table = self.water.map(|w| w.table_height(layer.material, x));
            let wet = self
                .water
                .and_then(|w| w.saturated_density(layer.material))
                .unwrap_or(layer.density);
            for (lo, hi) in self.segments(layer.region, x) {
                if hi <= z {
                    continue;
                }
                if top.is_none_or(|(t, _)| hi > t) {
                    top = Some((hi, layer.material));
                }
                let lo = lo.max(z);
                // The part below the material's piezometric surface weighs its saturated
                // density.
                let below = table.map_or(0.0, |h| (h.min(hi) - lo).max(0.0));
                total += self.gravity * (wet * below + layer.density * (hi - lo - below));
            }
        }
        let Some(w) = self.water else {
            return total.max(0.0);
        };
        if let Some((t, m)) = top {
            // Open water standing on the ground.
            total += w.unit_weight * (w.table_height(m, x) - t).max(0.0);
        }
        (total - w.pore_pressure(material, x)).max(0.0)
    }

    /// The intervals (lo, hi) of gravity's axis that `region` holds on the vertical through
    /// `x`.
    fn segments(&self, region: &Region, x: [f64; 3]) -> Vec<(f64, f64)> {
        let (u, n) = (self.axis, self.n);
        match region {
            Region::Box { min, max } => {
                let across = (0..n).filter(|&a| a != u).all(|a| x[a] > min[a] && x[a] < max[a]);
                if across {
                    vec![(min[u], max[u])]
                } else {
                    vec![]
                }
            }
            Region::Polygon { vertices, z } => {
                if u == 2 {
                    // Extruded along gravity's axis: the whole prism's height, or nothing.
                    let inside = region_contains(region, [x[0], x[1], 0.5 * (z_lo(z) + z_hi(z))], n);
                    return if inside { vec![(z_lo(z), z_hi(z))] } else { vec![] };
                }
                if n == 3 && !(x[2] > z_lo(z) && x[2] < z_hi(z)) {
                    return vec![];
                }
                // The line through x along axis u (0 or 1) crosses the polygon's edges.
                let o = 1 - u;
                let mut at: Vec<f64> = Vec::new();
                for (i, a) in vertices.iter().enumerate() {
                    let b = &vertices[(i + 1) % vertices.len()];
                    if (a[o] <= x[o]) != (b[o] <= x[o]) {
                        let t = (x[o] - a[o]) / (b[o] - a[o]);
                        at.push(a[u] + t * (b[u] - a[u]));
                    }
                }
                at.sort_by(f64::total_cmp);
                at.chunks_exact(2).map(|c| (c[0], c[1])).collect()
            }
        }
    }
}

fn z_lo(z: &Option<Vec<f64>>) -> f64 {
    z.as_ref().map_or(f64::NEG_INFINITY, |z| z[0])
}

fn z_hi(z: &Option<Vec<f64>>) -> f64 {
    z.as_ref().map_or(f64::INFINITY, |z| z[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ground(region: &Region) -> Ground<'_> {
        Ground {
            layers: vec![Layer {
                region,
                material: 0,
                density: 2000.0,
            }],
            axis: 1,
            gravity: 10.0,
            water: None,
            n: 2,
        }
    }

    #[test]
    fn a_point_in_level_ground_carries_the_weight_above_it_and_k0_across() {
        let region = Region::Box {
            min: vec![0.0, 0.0],
            max: vec![4.0, 10.0],
        };
        let spec = InitialStress::Geostatic {
            k0: 0.5,
            surcharge: 1.0e3,
        };
        let s = ground(&region).stress(&spec, 0, [1.0, 6.0, 0.0]);
        // 4 m of 2 000 kg/m³ at 10 m/s² plus 1 kPa.
        assert_eq!(s.yy, -81.0e3);
        assert_eq!((s.xx, s.zz, s.xy), (-40.5e3, -40.5e3, 0.0));
    }

    #[test]
    fn under_a_slope_the_ground_above_is_the_polygon_s_height_there() {
        // A slope from 10 m high at x ≤ 2 down to 5 m at x ≥ 7.
        let region = Region::Polygon {
            vertices: vec![
                vec![0.0, 0.0],
                vec![12.0, 0.0],
                vec![12.0, 5.0],
                vec![7.0, 5.0],
                vec![2.0, 10.0],
                vec![0.0, 10.0],
            ],
            z: None,
        };
        let spec = InitialStress::Geostatic {
            k0: 1.0,
            surcharge: 0.0,
        };
        let g = ground(&region);
        // At x = 4.5 the surface stands at 7.5 m: 6.5 m above a point at 1 m.
        assert!((g.stress(&spec, 0, [4.5, 1.0, 0.0]).yy + 130.0e3).abs() < 1e-6);
        assert!((g.stress(&spec, 0, [10.0, 1.0, 0.0]).yy + 80.0e3).abs() < 1e-6);
    }

    #[test]
    fn bad_k0_and_surcharge_are_refused_at_their_fields() {
        let bad = |k0, surcharge| {
            InitialStress::Geostatic { k0, surcharge }
                .check()
                .unwrap_err()
                .field
        };
        assert_eq!(bad(0.0, 0.0), "k0");
        assert_eq!(bad(f64::NAN, 0.0), "k0");
        assert_eq!(bad(0.5, -1.0), "surcharge");
        assert_eq!(InitialStress::Isotropic(-1.0).check().unwrap_err().field, "");
        assert!(InitialStress::Isotropic(0.0).check().is_ok());
    }
}
