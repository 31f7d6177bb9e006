//! Volume (and so density ρ = m/V) update (paper step 6).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, points_with};
use crate::parallel::CHUNK;
use crate::schedule::System;
use rayon::prelude::*;

/// V_p ← V_p · det(I + L_p Δt). Density is not stored: it is m_p / V_p.
#[derive(Debug, Default)]
pub struct VolumeUpdate;

impl<D: Dim> System<D> for VolumeUpdate {
    fn name(&self) -> &str {
        "volume_update"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let Some(dt) = ctx.motion_dt() else {
            return Ok(());
        };
        for arch in points_with::<Volume>(&ctx.world) {
            let lg = col::<VelocityGradient<D::Mat>>(arch);
            let mut vol = col_mut::<Volume>(arch);
            vol.par_chunks_mut(CHUNK)
                .zip(lg.par_chunks(CHUNK))
                .for_each(|(vol, l)| {
                    for (v, l) in vol.iter_mut().zip(l) {
                        v.0 *= D::volume_ratio(&l.0, dt);
                    }
                });
        }
        Ok(())
    }
}
