//! A pore-pressure filter on a rigid body: the piezocone's u2 element, or any place on a
//! body's surface where the water pressure of the soil beside it is read.
//!
//! A filter lies on one part's surface, and at every static state it reads the pore
//! pressure u (Pa, compression positive) of the soil beside that part within one cell of
//! its place: the volume-weighted mean, over the points within a cell whose nearest part
//! of the body is the filter's, of the hydrostatic pressure of their water table (`water`,
//! 0 above it or without one) plus the excess pore pressure an undrained material holds
//! (`systems/pore_pressure_field.rs`). Reading one part's side keeps a filter on a cone's
//! shaft just above the shoulder (a field piezocone's u2 element) from taking in the clay
//! beside the face below, which a cell-wide ball about it would reach on a coarse grid. A
//! place where two parts meet would read both, so it is refused. An undrained clay's
//! pressure is one value a cell, so a reading is the mean of the few cells about the
//! filter; a cell is the resolution of the field. The row `body.filter` of `curve.csv`
//! carries it in the `pressure` column (its force columns are 0); with no such soil within
//! a cell of the filter the row leaves it empty.

use super::PartSpec;
use crate::error::Refusal;
use serde::{Deserialize, Serialize};

/// A filter as the scene gives it (`rigid_bodies[i].filters`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterSpec {
    /// Name, unique among the body's parts and filters: its row of `curve.csv` is
    /// `body.name`.
    pub name: String,
    /// Its place on one part's surface at the start (m, one entry per axis; r and z when
    /// axisymmetric): it moves with the body.
    pub at: Vec<f64>,
}

impl FilterSpec {
    /// Its place at the start (m, x y z; 0 past the scene's axes).
    pub fn place(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.at.get(a).copied().unwrap_or(0.0))
    }

    /// The index of the part whose soil the filter reads, among the body's `parts` in `n`
    /// dimensions: the part nearest its place, the one it lies on ([`FilterSpec::check`]).
    pub fn part(&self, parts: &[PartSpec], n: usize) -> usize {
        super::distance(parts, self.place(), n).2
    }

    /// The rules a filter holds on a body of these `parts`, whose largest extent is `size`
    /// (m), in `n` dimensions: its place has n finite entries and lies on the body's
    /// surface and on one part's only (each within a thousandth of the body's size). Field
    /// names are relative to the filter.
    pub fn check(&self, n: usize, parts: &[PartSpec], size: f64) -> Result<(), Refusal> {
        if self.at.len() != n || !self.at.iter().all(|c| c.is_finite()) {
            return Err(Refusal::new(
                "at",
                format!("a place has {n} finite entries, found {:?}", self.at),
            ));
        }
        let x = self.place();
        let tolerance = 1e-3 * size;
        let phi = super::distance(parts, x, n).0;
        if phi.abs() > tolerance {
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
        let on: Vec<&str> = (parts.iter())
            .filter(|p| p.geometry.distance(x, n).0.abs() <= tolerance)
            .map(|p| p.name.as_str())
            .collect();
        if on.len() > 1 {
            return Err(Refusal::new(
                "at",
                format!(
                    "a filter reads the soil beside one part; {:?} lies where the parts {on:?} \
                     meet: move it onto one of them",
                    self.at
                ),
            ));
        }
        Ok(())
    }
}
