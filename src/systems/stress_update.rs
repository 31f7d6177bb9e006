//! Constitutive update with the Jaumann stress rate, eqs. (7)–(10) (paper step 6).

use crate::columns::{col, col_mut, points_with};
use crate::components::*;
use crate::dim::Dim;
use crate::error::StepError;
use crate::materials::Material;
use crate::parallel::CHUNK;
use crate::schedule::System;
use crate::simulation::Context;
use crate::tensor::StoredSym;
use rayon::prelude::*;

/// For each point: Δε = sym(L)Δt and ΔW = skew(L)Δt; the stress is first rotated by ΔW
/// (objective Jaumann term) and then integrated by the point's material over Δε.
#[derive(Debug, Default)]
pub struct StressUpdate;

impl<D: Dim> System<D> for StressUpdate {
    fn name(&self) -> &str {
        "stress_update"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if ctx.state.reset_this_step {
            return Ok(());
        }
        let dt = ctx.state.dt;
        let materials = &ctx.materials;
        let kernel = |stress: &mut [Stress<D::Stress>],
                      l: &[VelocityGradient<D::Mat>],
                      mat: &[MaterialId],
                      mut plastic: Option<&mut [PlasticStrain]>| {
            for p in 0..stress.len() {
                let (de, w) = D::strain_spin(&l[p].0, dt);
                let mut s = D::jaumann_rotate(&stress[p].0.to_sym3(), w);
                let eps = plastic.as_mut().map(|e| &mut e[p].0);
                materials[mat[p].0 as usize].update(&mut s, &de, eps);
                stress[p].0 = D::Stress::from_sym3(&s);
            }
        };
        for arch in points_with::<Stress<D::Stress>>(&ctx.world) {
            let (lg, mg) = (col::<VelocityGradient<D::Mat>>(arch), col::<MaterialId>(arch));
            let mut sg = col_mut::<Stress<D::Stress>>(arch);
            let chunks = sg
                .par_chunks_mut(CHUNK)
                .zip(lg.par_chunks(CHUNK))
                .zip(mg.par_chunks(CHUNK));
            // Plastic state exists only on plastic points.
            match arch.get::<&mut PlasticStrain>() {
                Some(mut pg) => chunks
                    .zip(pg.par_chunks_mut(CHUNK))
                    .for_each(|(((s, l), m), e)| kernel(s, l, m, Some(e))),
                None => chunks.for_each(|((s, l), m)| kernel(s, l, m, None)),
            }
        }
        Ok(())
    }
}
