//! Constitutive update with the Jaumann stress rate, eqs. (7)–(10) (paper step 6).

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, points_with};
use crate::infra::lanes::{gather, F64x4, LANES};
use crate::infra::traffic::Traffic;
use crate::materials::{update_lane_by_lane, visit_states, MaterialModel, MaterialState, StateVisitor};
use crate::parallel::{optional_chunks, CHUNK};
use crate::schedule::System;
use crate::systems::volume_update::volume_ratio;
use crate::tensor::{StoredSym, Sym3x4};
use hecs::{Archetype, ArchetypeColumnMut};
use rayon::prelude::*;
use std::marker::PhantomData;

/// For each point: Δε = sym(L)Δt and ΔW = skew(L)Δt; the stress is first rotated by ΔW
/// (objective Jaumann term) and then integrated by the point's material over Δε.
///
/// Points go four at a time, one per SIMD lane ([`crate::infra::lanes`]): the rotation always, and
/// the material's update when the four share a material (each gets the bits it would get
/// alone); the gain is in docs/performance.md ("Figures behind the code").
///
/// In a schedule without `volume_update` it also updates each point's volume,
/// V ← V det(I + LΔt), in the same pass over L (`volume_update` does it on its own
/// otherwise, with the same arithmetic and bits; `systems::volume_read_after_stress` says
/// when the default schedule holds it).
#[derive(Debug, Default)]
pub struct StressUpdate {
    volume: bool,
}

impl<D: Dim> System<D> for StressUpdate {
    fn name(&self) -> &str {
        "stress_update"
    }
    fn schedule_changed(&mut self, names: &[String]) {
        self.volume = !names.iter().any(|n| n == "volume_update");
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let Some(dt) = ctx.motion_dt() else {
            return Ok(());
        };
        for arch in points_with::<Stress<D::Stress>>(&ctx.world) {
            // Each archetype carries one material state column, or none (`()`).
            let mut update = ArchetypeUpdate::<D> {
                arch,
                materials: &ctx.materials,
                dt,
                volume: self.volume,
                done: false,
                dim: PhantomData,
            };
            visit_states(&mut update);
            if !update.done {
                update.run::<()>(None);
            }
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        if ctx.motion_dt().is_none() {
            return Some(Traffic::NONE);
        }
        let w = &ctx.world;
        let traffic = Traffic::NONE
            .read_points::<VelocityGradient<D::Mat>>(w)
            .read_points::<MaterialId>(w)
            .update_points::<Stress<D::Stress>>(w);
        let traffic = if self.volume {
            traffic.update_points::<Volume>(w)
        } else {
            traffic
        };
        // Each archetype's material state column, read and written.
        let mut states = StateTraffic { world: w, traffic };
        visit_states(&mut states);
        Some(states.traffic)
    }
}

/// Adds the material state columns of every point archetype to `traffic`.
struct StateTraffic<'a> {
    world: &'a hecs::World,
    traffic: Traffic,
}

impl StateVisitor for StateTraffic<'_> {
    fn visit<S: MaterialState>(&mut self) {
        if std::mem::size_of::<S>() > 0 {
            self.traffic = self.traffic.update_points::<S>(self.world);
        }
    }
}

/// The stress update of one archetype, with the state column it carries.
struct ArchetypeUpdate<'a, D> {
    arch: &'a Archetype,
    materials: &'a [MaterialModel],
    dt: f64,
    /// Update the volumes too.
    volume: bool,
    /// True once the archetype's state column was found and the update ran.
    done: bool,
    dim: PhantomData<D>,
}

impl<D: Dim> StateVisitor for ArchetypeUpdate<'_, D> {
    fn visit<S: MaterialState>(&mut self) {
        if !self.done && std::mem::size_of::<S>() > 0 {
            if let Some(states) = self.arch.get::<&mut S>() {
                self.run(Some(states));
                self.done = true;
            }
        }
    }
}

impl<D: Dim> ArchetypeUpdate<'_, D> {
    /// Updates every point of the archetype, in chunks across threads; `states` is its
    /// state column, `None` for points without state (then `S` is `()`).
    fn run<S: MaterialState>(&self, states: Option<ArchetypeColumnMut<'_, S>>) {
        let (materials, dt) = (self.materials, self.dt);
        let kernel = |stress: &mut [Stress<D::Stress>],
                      l: &[VelocityGradient<D::Mat>],
                      mat: &[MaterialId],
                      state: &mut [S],
                      mut vol: Option<&mut [Volume]>| {
            // Each group's volumes beside its stresses, while their L is in the cache.
            let mut volumes = |at: std::ops::Range<usize>| {
                if let Some(vol) = vol.as_deref_mut() {
                    for (v, l) in vol[at.clone()].iter_mut().zip(&l[at]) {
                        v.0 *= volume_ratio::<D>(&l.0, dt);
                    }
                }
            };
            let full = stress.len() / LANES * LANES;
            for g in (0..full).step_by(LANES) {
                let at = g..g + LANES;
                volumes(at.clone());
                update_group::<D, S>(
                    materials,
                    dt,
                    (&mut stress[at.clone()]).try_into().expect("four points"),
                    l[at.clone()].try_into().expect("four points"),
                    mat[at.clone()].try_into().expect("four points"),
                    (&mut state[at]).try_into().expect("four points"),
                );
            }
            let n = stress.len() - full;
            volumes(full..stress.len());
            if n > 0 {
                // The last few points; the spare lanes repeat the last one, and their results
                // are dropped.
                let at = |q: usize| full + q.min(n - 1);
                let mut s4: [Stress<D::Stress>; LANES] = std::array::from_fn(|q| stress[at(q)]);
                let l4 = std::array::from_fn(|q| l[at(q)]);
                let m4 = std::array::from_fn(|q| mat[at(q)]);
                let mut e4: [S; LANES] = std::array::from_fn(|q| state[at(q)]);
                update_group::<D, S>(materials, dt, &mut s4, &l4, &m4, &mut e4);
                stress[full..].copy_from_slice(&s4[..n]);
                state[full..].copy_from_slice(&e4[..n]);
            }
        };
        let arch = self.arch;
        let (lg, mg) = (col::<VelocityGradient<D::Mat>>(arch), col::<MaterialId>(arch));
        let mut sg = col_mut::<Stress<D::Stress>>(arch);
        let mut vg = self.volume.then(|| col_mut::<Volume>(arch));
        // One entry a chunk: its volumes, or nothing when `volume_update` does them.
        let vol_chunks = optional_chunks(vg.as_deref_mut(), sg.len());
        let chunks = sg
            .par_chunks_mut(CHUNK)
            .zip(lg.par_chunks(CHUNK))
            .zip(mg.par_chunks(CHUNK))
            .zip(vol_chunks.into_par_iter());
        match states {
            Some(mut e) => chunks
                .zip(e.par_chunks_mut(CHUNK))
                .for_each(|((((s, l), m), v), e)| kernel(s, l, m, e, v)),
            None => chunks.for_each(|(((s, l), m), v)| {
                // A state of no size: the slice costs no memory.
                kernel(s, l, m, &mut vec![S::default(); s.len()], v)
            }),
        }
    }
}

/// Four points: strain and spin increments, the Jaumann rotation in lanes, and the material
/// update, in lanes when the four share a material and point by point otherwise.
#[inline(always)]
fn update_group<D: Dim, S: MaterialState>(
    materials: &[MaterialModel],
    dt: f64,
    stress: &mut [Stress<D::Stress>; LANES],
    l: &[VelocityGradient<D::Mat>; LANES],
    mat: &[MaterialId; LANES],
    state: &mut [S; LANES],
) {
    let (de, w) = D::strain_spin(|i, j| gather(|q| D::mat_entry(&l[q].0, i, j)), F64x4::splat(dt));
    let mut s = D::jaumann_rotate(&Sym3x4::gather(|q| stress[q].0.to_sym3()), w);
    let id = mat[0].0;
    if mat.iter().all(|m| m.0 == id) {
        materials[id as usize].update4(&mut s, &de, state.each_mut());
    } else {
        update_lane_by_lane(&mut s, &de, state.each_mut(), |q, s, de, st| {
            materials[mat[q].0 as usize].update(s, de, st)
        });
    }
    for (stress, s) in stress.iter_mut().zip(&s.lanes()) {
        stress.0 = D::Stress::from_sym3(s);
    }
}
