//! Grid-to-particle velocity update and the kinetic energy of eq. (5) (paper step 4).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::{fill_box, scatter, ByPoint, Disjoint, CHUNK};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use rayon::prelude::*;
use std::marker::PhantomData;

/// The first point (by row) whose velocity is not finite, as "point <id>" for a message.
fn first_non_finite_velocity<D: Dim>(world: &hecs::World) -> String {
    for arch in points_with::<Velocity<D::Vec>>(world) {
        let (v, id) = (col::<Velocity<D::Vec>>(arch), col::<PointId>(arch));
        if let Some(r) = v
            .iter()
            .position(|v| !D::vec_to3(v.0).iter().all(|c| c.is_finite()))
        {
            return format!("point {}", id[r].0);
        }
    }
    "a point (the energy's sum overflowed)".into()
}

/// v_p ← α (v_p + Δt Σ_i w_ip a_i) + (1 − α) Σ_i w_ip v_i (FLIP for α = 1, PIC for α = 0),
/// then E_k = ½ Σ m_p v_p·v_p.
///
/// Under MUSL it also maps the new momentum, p_i = Σ_p w_ip m_p v_p, for the remap
/// ([`crate::systems::Remap`]) in the same pass: the points' columns and weights are read
/// once for both. The pass then goes slab by slab, as the remap's scatter does, so each
/// node's sum is the remap's to the bit; the kinetic energy is still summed in chunks of
/// points in storage order, so it is g2p's own to the bit. The momentum is marked as the
/// points' ([`Context::momentum_mapped`]) until a system that may change the points' motion
/// runs ([`System::changes_point_motion`]); the remap maps it itself otherwise.
#[derive(Debug)]
pub struct G2p<D, S> {
    remap: bool,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D, S> Default for G2p<D, S> {
    fn default() -> Self {
        G2p::new(false)
    }
}

impl<D, S> G2p<D, S> {
    /// A g2p that maps the new momentum for the MUSL remap when `remap`.
    pub fn new(remap: bool) -> Self {
        G2p {
            remap,
            _marker: PhantomData,
        }
    }
}

/// One point's new velocity (the expression of [`G2p`]).
#[inline(always)]
fn updated<D: Dim, S: Shape>(grid: &Grid<D>, x: D::Vec, v: D::Vec, nodes: NodeFields<'_, D>) -> D::Vec {
    let NodeFields { na, nv, flip, dt } = nodes;
    let mut a = D::Vec::ZERO;
    if flip < 1.0 {
        // PIC's share reads the interpolated nodal velocity; pure FLIP (the default) never
        // does.
        let mut vg = D::Vec::ZERO;
        for_each_node::<D, S>(grid, x, |i, w, _| {
            a = na[i].0.madd(w, a);
            vg = nv[i].0.madd(w, vg);
        });
        (v + a * dt) * flip + vg * (1.0 - flip)
    } else {
        for_each_node::<D, S>(grid, x, |i, w, _| a = na[i].0.madd(w, a));
        v + a * dt
    }
}

/// What [`updated`] reads besides the point: the nodal acceleration and velocity, the FLIP
/// fraction and the step.
#[derive(Clone, Copy)]
struct NodeFields<'a, D: Dim> {
    na: &'a [NodeAcceleration<D::Vec>],
    nv: &'a [NodeVelocity<D::Vec>],
    flip: f64,
    dt: f64,
}

/// Σ of `e` in chunks of [`CHUNK`] summed in order, then the chunks' sums in order: the same
/// bits for any thread count and whichever order the terms were made in.
fn chunked_sum(e: &[f64]) -> f64 {
    let parts: Vec<f64> = e
        .par_chunks(CHUNK)
        .map(|c| {
            let mut s = 0.0;
            for x in c {
                s += x;
            }
            s
        })
        .collect();
    parts.iter().sum::<f64>()
}

impl<D: Dim, S: Shape> System<D> for G2p<D, S> {
    fn name(&self) -> &str {
        "g2p"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let twice_ek = if self.remap {
            Self::map_with_momentum(ctx)
        } else {
            Self::map(ctx)
        };
        // A NaN or infinite velocity shows in the energy's sum. Stop here, before any point
        // moves with it: positions, stresses and the solver state stay those of the last
        // finite step (the velocities do not, so the final points are not written).
        // Over MPI the energy is the ranks' sum (a NaN on one rank reaches all, so that every
        // rank stops alike).
        let mut twice_ek = [twice_ek];
        ctx.comm.sum(&mut twice_ek);
        let [twice_ek] = twice_ek;
        if !twice_ek.is_finite() {
            ctx.momentum_mapped = false;
            return Err(StepError::NonFinite {
                step: ctx.state.clock.step,
                system: "g2p",
                what: "velocity",
                location: first_non_finite_velocity::<D>(&ctx.world),
            });
        }
        ctx.state.energy.set(0.5 * twice_ek);
        Ok(())
    }
    fn changes_point_motion(&self) -> bool {
        // It makes the velocities whose momentum it maps.
        false
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let (w, n) = (&ctx.world, ctx.state.active_nodes.len());
        let t = Traffic::NONE
            .read_points::<Position<D::Vec>>(w)
            .read_points::<Mass>(w)
            .update_points::<Velocity<D::Vec>>(w)
            .read_nodes::<NodeAcceleration<D::Vec>>(n);
        // PIC's share reads the nodal velocity too.
        let t = if ctx.numerics.flip < 1.0 {
            t.read_nodes::<NodeVelocity<D::Vec>>(n)
        } else {
            t
        };
        // The remap's momentum: zeroed, then summed; the slabs' order of the points and
        // each point's energy, written and read back.
        Some(if self.remap {
            t.write_nodes::<NodeMomentum<D::Vec>>(n)
                .update_nodes::<NodeMomentum<D::Vec>>(n)
                .read_order::<Velocity<D::Vec>>(w)
                .update_scratch::<Velocity<D::Vec>>(w, 8)
        } else {
            t
        })
    }
}

impl<D: Dim, S: Shape> G2p<D, S> {
    /// The velocities and twice the kinetic energy, in chunks of points.
    fn map(ctx: &mut Context<D>) -> f64 {
        let grid = &ctx.grid;
        let n = nodes(&ctx.world);
        let (nag, nvg) = (col::<NodeAcceleration<D::Vec>>(n), col::<NodeVelocity<D::Vec>>(n));
        let fields = NodeFields::<D> {
            na: &nag,
            nv: &nvg,
            flip: ctx.numerics.flip,
            dt: ctx.numerics.dt,
        };
        let mut twice_ek = 0.0;
        for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
            let (xg, mg) = (col::<Position<D::Vec>>(arch), col::<Mass>(arch));
            let (x, m): (&[Position<D::Vec>], &[Mass]) = (&xg, &mg);
            let mut vg = col_mut::<Velocity<D::Vec>>(arch);
            let parts: Vec<f64> = vg
                .par_chunks_mut(CHUNK)
                .enumerate()
                .map(|(c, v)| {
                    let mut e = 0.0;
                    for (k, vp) in v.iter_mut().enumerate() {
                        let p = c * CHUNK + k;
                        vp.0 = updated::<D, S>(grid, x[p].0, vp.0, fields);
                        e += m[p].0 * vp.0.dot(vp.0);
                    }
                    e
                })
                .collect();
            // Partial sums added in chunk order: the same bits for any thread count.
            twice_ek += parts.iter().sum::<f64>();
        }
        twice_ek
    }

    /// The velocities, the momentum they carry to the nodes (the remap's scatter) and twice
    /// the kinetic energy, slab by slab.
    fn map_with_momentum(ctx: &mut Context<D>) -> f64 {
        let grid = &ctx.grid;
        let n = nodes(&ctx.world);
        let (nag, nvg) = (col::<NodeAcceleration<D::Vec>>(n), col::<NodeVelocity<D::Vec>>(n));
        let fields = NodeFields::<D> {
            na: &nag,
            nv: &nvg,
            flip: ctx.numerics.flip,
            dt: ctx.numerics.dt,
        };
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        fill_box(grid, ctx.state.active_nodes, &mut np, NodeMomentum(D::Vec::ZERO));
        let mut reached = ctx.state.active_nodes;
        let mut twice_ek = 0.0;
        let mut energy = Vec::new();
        for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
            let (xg, mg) = (col::<Position<D::Vec>>(arch), col::<Mass>(arch));
            let (x, m): (&[Position<D::Vec>], &[Mass]) = (&xg, &mg);
            let mut vg = col_mut::<Velocity<D::Vec>>(arch);
            energy.clear();
            energy.resize(x.len(), 0.0);
            let (v, e) = (ByPoint::new(&mut vg), ByPoint::new(&mut energy));
            reached = reached.union(scatter(
                ctx.slabs.slabs(grid, x),
                grid,
                S::SUPPORT,
                &Disjoint::new(&mut np),
                |points, np, lo| {
                    for &p in points {
                        let p = p as usize;
                        // SAFETY: point p is in this slab alone, and its rows are taken for
                        // this iteration only.
                        let (vp, ep) = unsafe { (v.row(p), e.row(p)) };
                        vp.0 = updated::<D, S>(grid, x[p].0, vp.0, fields);
                        *ep = m[p].0 * vp.0.dot(vp.0);
                        let mv = vp.0 * m[p].0;
                        for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                            let n = &mut np[i - lo].0;
                            *n = mv.madd(w, *n);
                        });
                    }
                },
            ));
            twice_ek += chunked_sum(&energy);
        }
        ctx.state.active_nodes = reached;
        ctx.momentum_mapped = true;
        twice_ek
    }
}
