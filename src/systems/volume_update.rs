//! Volume (and so density ρ = m/V) update (paper step 6).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, points_with};
use crate::infra::traffic::Traffic;
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
                        v.0 *= volume_ratio::<D>(&l.0, dt);
                    }
                });
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        if ctx.motion_dt().is_none() {
            return Some(Traffic::NONE);
        }
        let w = &ctx.world;
        Some(
            Traffic::NONE
                .read_points::<VelocityGradient<D::Mat>>(w)
                .update_points::<Volume>(w),
        )
    }
}

/// det(I + L Δt) of one point (here and in `stress_update`, which does the volumes where
/// no `volume_update` is scheduled), kept out of line so that the loop above is not vectorised
/// across points: with the build's `target-cpu=native` the compiler loads four points'
/// gradients (72 bytes apart) into vector lanes by gathers, which on the AMD cores measured
/// here made the pass four times slower than one point at a time (docs/performance.md).
/// The arithmetic, and so the bits, are the same either way.
#[inline(never)]
pub(crate) fn volume_ratio<D: Dim>(l: &D::Mat, dt: f64) -> f64 {
    D::volume_ratio(l, dt)
}
