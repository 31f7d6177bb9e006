//! Kinematics: velocity gradient and position update from one nodal velocity field
//! (paper steps 5–6).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::{optional_chunks, CHUNK};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::{g2p_gathers, Gathered};
use rayon::prelude::*;
use std::marker::PhantomData;

/// L_p = Σ_i v_i ⊗ ∇w_ip and x_p ← x_p + Δt Σ_i w_ip v_i, with v_i the `NodeVelocity` field.
///
/// Straining and moving the points with the same nodal velocity keeps the converged state
/// independent of the time step: with different fields (e.g. moving with the FLIP point
/// velocity) the displacement drifts from the strain at every kinetic-damping reset.
/// After a reset the points neither move nor strain.
///
/// The scatters' grouping of points ([`crate::SlabCache`]) depends on the cell of
/// each point alone, so it is dropped only when a point moved into another cell: in a body
/// near rest most steps keep it, and particle-to-grid skips its counting sort (a sixth of
/// its work a point; docs/performance.md).
#[derive(Debug)]
pub struct Kinematics<D, S> {
    gradient: bool,
    motion: bool,
    /// Move by the nodal velocity g2p gathered ([`Context::point_grid_velocity`]) instead of
    /// gathering it again, g2p having written the velocity gradient too where this pass
    /// has one ([`g2p_gathers`]).
    carried: bool,
    _marker: PhantomData<fn() -> (D, S)>,
}

/// The velocity gradient L_p = Σ_i v_i ⊗ ∇w_ip (with the hoop rate in axisymmetry) and the
/// nodal velocity at the point, Σ_i w_ip v_i, of the field `nv` at `x`: what kinematics
/// strains and moves a point with, and what g2p gathers in its place where it may.
#[inline(always)]
pub fn gradient_and_velocity<D: Dim, S: Shape>(
    grid: &crate::grid::Grid<D>,
    x: D::Vec,
    nv: &[NodeVelocity<D::Vec>],
) -> (D::Mat, D::Vec) {
    let (mut l, vel) = S::gather_with_gradient(grid, x, |i| nv[i].0);
    D::complete_gradient(&mut l, x, vel);
    (l, vel)
}

impl<D: Dim, S: Shape> Kinematics<D, S> {
    /// Velocity gradient and motion in one pass (USL, MUSL).
    pub fn both() -> Self {
        Kinematics {
            gradient: true,
            motion: true,
            carried: false,
            _marker: PhantomData,
        }
    }

    /// Velocity gradient only (USF, start of step).
    pub fn gradient_only() -> Self {
        Kinematics {
            gradient: true,
            motion: false,
            carried: false,
            _marker: PhantomData,
        }
    }
    /// Motion only (USF, end of step).
    pub fn motion_only() -> Self {
        Kinematics {
            gradient: false,
            motion: true,
            carried: false,
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for Kinematics<D, S> {
    fn name(&self) -> &str {
        self.name_static()
    }

    fn schedule_changed(&mut self, names: &[String]) {
        self.carried = self.motion
            && match g2p_gathers(names) {
                Gathered::Strain => self.gradient,
                Gathered::Velocity => !self.gradient,
                Gathered::Nothing => false,
            };
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let Some(dt) = ctx.motion_dt() else {
            return Ok(());
        };
        let (grid, step) = (&ctx.grid, ctx.state.clock.step);
        let name = self.name_static();
        let (gradient, motion, carried) = (self.gradient, self.motion, self.carried);
        let n = nodes(&ctx.world);
        let nvg = col::<NodeVelocity<D::Vec>>(n);
        let nv: &[NodeVelocity<D::Vec>] = &nvg;
        // g2p's gathers, in its order of the points (`points_with::<Velocity>`).
        let mut gathered: &[D::Vec] = &ctx.point_grid_velocity;
        let archs: Vec<_> = if carried {
            points_with::<Velocity<D::Vec>>(&ctx.world).collect()
        } else {
            points_with::<Position<D::Vec>>(&ctx.world).collect()
        };
        for arch in archs {
            let mut xg = col_mut::<Position<D::Vec>>(arch);
            let mut lg = col_mut::<VelocityGradient<D::Mat>>(arch);
            let mut ug = arch.get::<&mut Displacement<D::Vec>>();
            let mine: &[D::Vec] = if carried {
                let (mine, rest) = gathered.split_at(xg.len());
                gathered = rest;
                mine
            } else {
                &[]
            };
            // Displacements are kept only when the scene asks for them.
            let u_chunks = optional_chunks(ug.as_deref_mut(), xg.len());
            // Each chunk reports whether a point changed cell and the first point that left
            // the grid; the first in chunk order wins, so the error is the same for any
            // thread count.
            let chunks = xg
                .par_chunks_mut(CHUNK)
                .zip(lg.par_chunks_mut(CHUNK))
                .zip(u_chunks.into_par_iter())
                .enumerate()
                .map(|(c, ((x, l), mut u))| {
                    let mut crossed = false;
                    for k in 0..x.len() {
                        let mut vel = D::Vec::ZERO;
                        // One loop per case, so that the node loop holds no branch.
                        if carried {
                            vel = mine[c * CHUNK + k];
                        } else if gradient {
                            (l[k].0, vel) = gradient_and_velocity::<D, S>(grid, x[k].0, nv);
                        } else {
                            for_each_node::<D, S>(grid, x[k].0, |i, w, _| vel = nv[i].0.madd(w, vel));
                        }
                        if motion {
                            let du = vel * dt;
                            let xp = x[k].0 + du;
                            match grid.landing(x[k].0, xp) {
                                Some(left) => crossed |= left,
                                None => return (crossed, Some((c * CHUNK + k, D::vec_to3(xp)))),
                            }
                            x[k].0 = xp;
                            if let Some(u) = u.as_deref_mut() {
                                u[k].0 += du;
                            }
                        }
                    }
                    (crossed, None)
                })
                .collect::<Vec<_>>();
            if chunks
                .iter()
                .any(|&(crossed, escaped)| crossed || escaped.is_some())
            {
                ctx.slabs.invalidate();
            }
            if let Some((p, position)) = chunks.into_iter().find_map(|(_, escaped)| escaped) {
                let point = col::<PointId>(arch)[p].0;
                return Err(if position.iter().all(|c| c.is_finite()) {
                    StepError::PointLeftGrid {
                        step,
                        system: name,
                        point,
                        position,
                    }
                } else {
                    StepError::NonFinite {
                        step,
                        system: name,
                        what: "position",
                        location: format!("point {point}"),
                    }
                });
            }
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        if ctx.motion_dt().is_none() {
            return Some(Traffic::NONE);
        }
        let w = &ctx.world;
        let mut t = if self.carried {
            Traffic::NONE.read_per_point::<Velocity<D::Vec>, D::Vec>(w)
        } else {
            Traffic::NONE.read_nodes::<NodeVelocity<D::Vec>>(ctx.state.active_nodes.len())
        };
        if self.gradient && !self.carried {
            t = t.write_points::<VelocityGradient<D::Mat>>(w);
        }
        Some(if self.motion {
            t.update_points::<Position<D::Vec>>(w)
                .update_points::<Displacement<D::Vec>>(w)
        } else {
            t.read_points::<Position<D::Vec>>(w)
        })
    }
}

impl<D: Dim, S: Shape> Kinematics<D, S> {
    fn name_static(&self) -> &'static str {
        match (self.gradient, self.motion) {
            (true, true) => "kinematics",
            (true, false) => "velocity_gradient",
            _ => "move_points",
        }
    }
}
