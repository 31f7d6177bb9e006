//! Grid reset: every step starts from the undeformed, empty background grid (paper step 8).

use crate::columns::{col_mut, nodes};
use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::schedule::System;
use crate::simulation::Context;

/// Zeroes nodal mass, momentum and forces.
#[derive(Debug, Default)]
pub struct GridReset;

impl<D: Dim> System<D> for GridReset {
    fn name(&self) -> &str {
        "grid_reset"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let n = nodes(&ctx.world);
        col_mut::<NodeMass>(n).fill(NodeMass(0.0));
        col_mut::<NodeMomentum<D::Vec>>(n).fill(NodeMomentum(D::Vec::ZERO));
        col_mut::<NodeForce<D::Vec>>(n).fill(NodeForce(D::Vec::ZERO));
        col_mut::<NodeExternalForce<D::Vec>>(n).fill(NodeExternalForce(D::Vec::ZERO));
        Ok(())
    }
}
