//! A pore-pressure filter on a rigid body: the piezocone's u2 element, or any place on a
//! body's surface where the water pressure of the soil beside it is read.
//!
//! At every static state the filter reads the pore pressure u (Pa, compression positive)
//! of the soil within one cell of its place: the volume-weighted mean over those points of
//! the hydrostatic pressure of their water table (`water`, 0 above it or without one) plus
//! the excess pore pressure an undrained material holds (`systems/pore_pressure_field.rs`).
//! An undrained clay's pressure is one value a cell, so a reading is the mean of the few
//! cells about the filter; a cell is the resolution of the field. The row
//! `body.filter` of `curve.csv` carries it in the `pressure` column (its force columns
//! are 0); with no soil within a cell of the filter the row leaves it empty.

use crate::error::Refusal;
use serde::{Deserialize, Serialize};

/// A filter as the scene gives it (`rigid_bodies[i].filters`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterSpec {
    /// Name, unique among the body's parts and filters: its row of `curve.csv` is
    /// `body.name`.
    pub name: String,
    /// Its place on the body's surface at the start (m, one entry per axis; r and z when
    /// axisymmetric): it moves with the body.
    pub at: Vec<f64>,
}

impl FilterSpec {
    /// The rules a filter holds on a body whose signed distance (m, negative inside) from a
    /// place in its starting frame is `distance`, and whose largest extent is `size` (m), in
    /// `n` dimensions: its place has n finite entries and lies on the body's surface (within
    /// a thousandth of the body's size). Field names are relative to the filter.
    pub fn check(&self, n: usize, distance: impl Fn([f64; 3]) -> f64, size: f64) -> Result<(), Refusal> {
        if self.at.len() != n || !self.at.iter().all(|c| c.is_finite()) {
            return Err(Refusal::new(
                "at",
                format!("a place has {n} finite entries, found {:?}", self.at),
            ));
        }
        let x = std::array::from_fn(|a| self.at.get(a).copied().unwrap_or(0.0));
        let phi = distance(x);
        if phi.abs() > 1e-3 * size {
            let side = if phi < 0.0 { "inside" } else { "outside" };
            return Err(Refusal::new(
                "at",
                format!(
                    "a filter lies on the body's surface; {:?} is {} m {side} it",
                    self.at,
                    phi.abs()
                ),
            ));
        }
        Ok(())
    }
}
