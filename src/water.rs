//! Pore water (`water` in a scene): a hydrostatic water table, drained and static.
//!
//! Below the table a point carries pore pressure u = γ_w (z_w − z) (Pa, compression
//! positive), where z is its current height along gravity's axis; above it, u = 0 (no
//! suction). The points' `Stress` is the effective stress σ′, on which the materials act;
//! the total stress is σ = σ′ − u I (tension positive). So the pore water enters the
//! balance only through the internal force: the system `pore_pressure` adds
//! Σ_p V_p u_p ∇w_ip to the nodal forces, the −V (−u I)·∇w part of −V σ·∇w. Points below the
//! table at set-up weigh their material's saturated density.
//!
//! What this does not do yet: open water above the ground (a table above the soil surface
//! is refused at set-up, since the water's pressure on the surface would be missing), a
//! sloping table, and stages that move the table.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The water as the scene gives it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterSpec {
    /// Unit weight of water γ_w (N/m³).
    #[serde(default = "default_unit_weight")]
    pub unit_weight: f64,
    /// Height of the water table, measured up the axis gravity points down (m).
    pub table: f64,
    /// Saturated density of each material that has points below the table (kg/m³, at
    /// least its dry density).
    pub saturated_density: BTreeMap<String, f64>,
}

fn default_unit_weight() -> f64 {
    9810.0
}

/// The water table as the run uses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Water {
    /// γ_w (N/m³).
    pub unit_weight: f64,
    /// Height of the table along `axis` (m).
    pub table: f64,
    /// Gravity's axis (gravity points along −axis).
    pub axis: usize,
}

impl Water {
    /// Pore pressure at `x` (Pa, compression positive): γ_w times the depth below the table.
    #[inline(always)]
    pub fn pore_pressure(&self, x: [f64; 3]) -> f64 {
        self.unit_weight * (self.table - x[self.axis]).max(0.0)
    }

    /// True when `x` lies below the table.
    pub fn below(&self, x: [f64; 3]) -> bool {
        self.pore_pressure(x) > 0.0
    }
}

impl WaterSpec {
    /// The checked water of a scene whose gravity is `gravity` (one entry an axis): gravity
    /// must point along one axis. As (field, rule) on failure.
    pub fn checked(&self, gravity: Option<&[f64]>) -> Result<Water, (String, String)> {
        let bad = |f: &str, r: String| Err((f.to_string(), r));
        if !(self.unit_weight.is_finite() && self.unit_weight > 0.0) {
            return bad(
                "water.unit_weight",
                format!("must be above 0 N/m³, found {}", self.unit_weight),
            );
        }
        if !self.table.is_finite() {
            return bad(
                "water.table",
                format!("must be a finite height (m), found {}", self.table),
            );
        }
        let Some(g) = gravity else {
            return bad(
                "water",
                "pore pressure is hydrostatic: the scene needs gravity".into(),
            );
        };
        let along: Vec<usize> = (0..g.len()).filter(|&a| g[a] != 0.0).collect();
        match along[..] {
            [axis] if g[axis] < 0.0 => Ok(Water {
                unit_weight: self.unit_weight,
                table: self.table,
                axis,
            }),
            _ => bad(
                "gravity.acceleration",
                "with water, gravity points down one axis (a negative entry, the others 0): the \
                 table is level across the others and heights are measured up that axis"
                    .into(),
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pore_pressure_is_hydrostatic_below_the_table_and_zero_above() {
        let w = WaterSpec {
            unit_weight: 10.0e3,
            table: 5.0,
            saturated_density: BTreeMap::new(),
        }
        .checked(Some(&[0.0, -9.81]))
        .unwrap();
        assert_eq!(w.pore_pressure([0.0, 2.0, 0.0]), 30.0e3);
        assert_eq!(w.pore_pressure([0.0, 6.0, 0.0]), 0.0);
        assert!(w.below([0.0, 4.9, 0.0]) && !w.below([0.0, 5.0, 0.0]));
    }
}
