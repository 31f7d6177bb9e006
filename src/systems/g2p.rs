//! Grid-to-particle velocity update and the kinetic energy of eq. (5) (paper step 4).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::CHUNK;
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::kinematics::gradient_and_velocity;
use crate::systems::{g2p_gathers, Gathered};
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
/// Where only the peak watch runs between g2p and the system that moves the points
/// ([`g2p_gathers`]), the same visit of a point's nodes also gathers what that system
/// would: the nodal velocity at the point, Σ_i w_ip v_i, into
/// [`Context::point_grid_velocity`], which it then moves the point by unless the peak watch
/// resets the step, and for USL's kinematics the velocity gradient L_p = Σ_i v_i ⊗ ∇w_ip
/// into its column. The sums are that system's own, so the bits are those of two passes.
#[derive(Debug)]
pub struct G2p<D, S> {
    gathers: Gathered,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D, S> Default for G2p<D, S> {
    fn default() -> Self {
        G2p {
            gathers: Gathered::Nothing,
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for G2p<D, S> {
    fn name(&self) -> &str {
        "g2p"
    }
    fn schedule_changed(&mut self, names: &[String]) {
        self.gathers = g2p_gathers(names);
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let (grid, dt) = (&ctx.grid, ctx.numerics.dt);
        let n = nodes(&ctx.world);
        let nag = col::<NodeAcceleration<D::Vec>>(n);
        let na: &[NodeAcceleration<D::Vec>] = &nag;
        let nvg = col::<NodeVelocity<D::Vec>>(n);
        let nv: &[NodeVelocity<D::Vec>] = &nvg;
        let flip = ctx.numerics.flip;
        // Pure FLIP (the default) never reads the interpolated nodal velocity.
        let pic = flip < 1.0;
        let (gathers, strain) = (self.gathers, self.gathers == Gathered::Strain);
        let carry = gathers != Gathered::Nothing;
        let carried = &mut ctx.point_grid_velocity;
        if carry {
            let rows = points_with::<Velocity<D::Vec>>(&ctx.world)
                .map(|a| a.len() as usize)
                .sum();
            carried.resize(rows, D::Vec::ZERO);
        }
        let mut carried: &mut [D::Vec] = carried;
        let mut twice_ek = 0.0;
        for arch in points_with::<Velocity<D::Vec>>(&ctx.world) {
            let (xg, mg) = (col::<Position<D::Vec>>(arch), col::<Mass>(arch));
            let fields = Fields::<D, S> {
                grid,
                x: &xg,
                m: &mg,
                na,
                nv,
                dt,
                flip,
                shape: PhantomData,
            };
            let mut vg = col_mut::<Velocity<D::Vec>>(arch);
            // Kinematics' columns, written only with `strain`.
            let mut lg = strain.then(|| col_mut::<VelocityGradient<D::Mat>>(arch));
            let (mine, rest) = std::mem::take(&mut carried).split_at_mut(if carry { vg.len() } else { 0 });
            carried = rest;
            let parts = match lg.as_deref_mut() {
                Some(l) if !pic => fields.velocities_and_strain(&mut vg, l, mine),
                None if carry => fields.velocities_and_nodal(&mut vg, mine),
                l => {
                    let parts = fields.velocities(&mut vg);
                    // PIC keeps its own sums; kinematics' follow in a pass of their own.
                    if let Some(l) = l {
                        fields.strain(l, mine);
                    }
                    parts
                }
            };
            // Partial sums added in chunk order: the same bits for any thread count.
            twice_ek += parts.iter().sum::<f64>();
        }
        // A NaN or infinite velocity shows in the energy's sum. Stop here, before any point
        // moves with it: positions, stresses and the solver state stay those of the last
        // finite step (the velocities do not, so the final points are not written).
        // Over MPI the energy is the ranks' sum (a NaN on one rank reaches all, so that every
        // rank stops alike).
        let mut twice_ek = [twice_ek];
        ctx.comm.sum(&mut twice_ek);
        let [twice_ek] = twice_ek;
        if !twice_ek.is_finite() {
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
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let (w, n) = (&ctx.world, ctx.state.active_nodes.len());
        let t = Traffic::NONE
            .read_points::<Position<D::Vec>>(w)
            .read_points::<Mass>(w)
            .update_points::<Velocity<D::Vec>>(w)
            .read_nodes::<NodeAcceleration<D::Vec>>(n);
        // PIC's share and the motion's gathers read the nodal velocity too.
        let t = if ctx.numerics.flip < 1.0 || self.gathers != Gathered::Nothing {
            t.read_nodes::<NodeVelocity<D::Vec>>(n)
        } else {
            t
        };
        Some(match self.gathers {
            Gathered::Nothing => t,
            Gathered::Velocity => t.write_per_point::<Velocity<D::Vec>, D::Vec>(w),
            Gathered::Strain => t
                .write_points::<VelocityGradient<D::Mat>>(w)
                .write_per_point::<Velocity<D::Vec>, D::Vec>(w),
        })
    }
}

/// What g2p reads for one archetype of points: the grid, their positions and masses, the
/// nodal accelerations and velocities, Δt and the FLIP share.
struct Fields<'a, D: Dim, S> {
    grid: &'a Grid<D>,
    x: &'a [Position<D::Vec>],
    m: &'a [Mass],
    na: &'a [NodeAcceleration<D::Vec>],
    nv: &'a [NodeVelocity<D::Vec>],
    dt: f64,
    flip: f64,
    shape: PhantomData<S>,
}

impl<D: Dim, S: Shape> Fields<'_, D, S> {
    /// The velocity update of the points `v`; each chunk's Σ m v·v.
    fn velocities(&self, v: &mut [Velocity<D::Vec>]) -> Vec<f64> {
        let (grid, x, m, na, nv, dt, flip) =
            (self.grid, self.x, self.m, self.na, self.nv, self.dt, self.flip);
        // Pure FLIP (the default) never reads the interpolated nodal velocity.
        let pic = flip < 1.0;
        v.par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, v)| {
                let mut e = 0.0;
                for (k, vp) in v.iter_mut().enumerate() {
                    let p = c * CHUNK + k;
                    let mut a = D::Vec::ZERO;
                    vp.0 = if pic {
                        let mut vg = D::Vec::ZERO;
                        for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                            a = na[i].0.madd(w, a);
                            vg = nv[i].0.madd(w, vg);
                        });
                        (vp.0 + a * dt) * flip + vg * (1.0 - flip)
                    } else {
                        for_each_node::<D, S>(grid, x[p].0, |i, w, _| a = na[i].0.madd(w, a));
                        vp.0 + a * dt
                    };
                    e += m[p].0 * vp.0.dot(vp.0);
                }
                e
            })
            .collect()
    }

    /// The velocity update of the points `v` and, in the same visit of each point's nodes,
    /// the nodal velocity `g` at each (node by node, as `move_points` sums it); each
    /// chunk's Σ m v·v.
    fn velocities_and_nodal(&self, v: &mut [Velocity<D::Vec>], g: &mut [D::Vec]) -> Vec<f64> {
        let (grid, x, m, na, nv, dt, flip) =
            (self.grid, self.x, self.m, self.na, self.nv, self.dt, self.flip);
        let pic = flip < 1.0;
        v.par_chunks_mut(CHUNK)
            .zip(g.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(c, (v, g))| {
                let mut e = 0.0;
                for (k, vp) in v.iter_mut().enumerate() {
                    let p = c * CHUNK + k;
                    let (mut a, mut vg) = (D::Vec::ZERO, D::Vec::ZERO);
                    for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                        a = na[i].0.madd(w, a);
                        vg = nv[i].0.madd(w, vg);
                    });
                    vp.0 = if pic {
                        (vp.0 + a * dt) * flip + vg * (1.0 - flip)
                    } else {
                        vp.0 + a * dt
                    };
                    g[k] = vg;
                    e += m[p].0 * vp.0.dot(vp.0);
                }
                e
            })
            .collect()
    }

    /// The FLIP velocity update of the points `v` and, in the same visit of each point's
    /// rows of nodes, kinematics' velocity gradient `l` and nodal velocity `g`; each
    /// chunk's Σ m v·v.
    fn velocities_and_strain(
        &self,
        v: &mut [Velocity<D::Vec>],
        l: &mut [VelocityGradient<D::Mat>],
        g: &mut [D::Vec],
    ) -> Vec<f64> {
        let (grid, x, m, na, nv, dt) = (self.grid, self.x, self.m, self.na, self.nv, self.dt);
        v.par_chunks_mut(CHUNK)
            .zip(l.par_chunks_mut(CHUNK).zip(g.par_chunks_mut(CHUNK)))
            .enumerate()
            .map(|(c, (v, (l, g)))| {
                let mut e = 0.0;
                for (k, vp) in v.iter_mut().enumerate() {
                    let p = c * CHUNK + k;
                    let (mut lp, vel, a) =
                        S::gather_with_gradient_and(grid, x[p].0, |i| nv[i].0, |i| na[i].0);
                    D::complete_gradient(&mut lp, x[p].0, vel);
                    (l[k].0, g[k], vp.0) = (lp, vel, vp.0 + a * dt);
                    e += m[p].0 * vp.0.dot(vp.0);
                }
                e
            })
            .collect()
    }

    /// Kinematics' velocity gradient `l` and nodal velocity `g` of every point, on their own.
    fn strain(&self, l: &mut [VelocityGradient<D::Mat>], g: &mut [D::Vec]) {
        let (grid, x, nv) = (self.grid, self.x, self.nv);
        l.par_chunks_mut(CHUNK)
            .zip(g.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (l, g))| {
                for k in 0..l.len() {
                    let p = c * CHUNK + k;
                    (l[k].0, g[k]) = gradient_and_velocity::<D, S>(grid, x[p].0, nv);
                }
            });
    }
}
