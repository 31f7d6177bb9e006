//! Kinematics: velocity gradient and position update from one nodal velocity field
//! (paper steps 5–6).

use crate::columns::{col, col_mut, nodes, points_with};
use crate::components::*;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::simulation::Context;
use std::marker::PhantomData;

/// L_p = Σ_i v_i ⊗ ∇w_ip and x_p ← x_p + Δt Σ_i w_ip v_i, with v_i the `NodeVelocity` field.
///
/// Straining and moving the points with the same nodal velocity keeps the converged state
/// independent of the time step: with different fields (e.g. moving with the FLIP point
/// velocity) the displacement drifts from the strain at every kinetic-damping reset.
/// After a reset the points neither move nor strain.
#[derive(Debug)]
pub struct Kinematics<D, S> {
    gradient: bool,
    motion: bool,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S: Shape> Kinematics<D, S> {
    /// Velocity gradient and motion in one pass (USL, MUSL).
    pub fn both() -> Self {
        Kinematics {
            gradient: true,
            motion: true,
            _marker: PhantomData,
        }
    }
    /// Velocity gradient only (USF, start of step).
    pub fn gradient_only() -> Self {
        Kinematics {
            gradient: true,
            motion: false,
            _marker: PhantomData,
        }
    }
    /// Motion only (USF, end of step).
    pub fn motion_only() -> Self {
        Kinematics {
            gradient: false,
            motion: true,
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for Kinematics<D, S> {
    fn name(&self) -> &str {
        self.name_static()
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        if ctx.state.reset_this_step {
            return Ok(());
        }
        let (grid, dt, step) = (&ctx.grid, ctx.state.dt, ctx.state.step);
        let name = self.name_static();
        let n = nodes(&ctx.world);
        let nv = col::<NodeVelocity<D::Vec>>(n);
        let mut offset = 0;
        for arch in points_with::<Position<D::Vec>>(&ctx.world) {
            let mut x = col_mut::<Position<D::Vec>>(arch);
            let mut lgrad = if self.gradient {
                arch.get::<&mut VelocityGradient<D::Mat>>()
            } else {
                None
            };
            let mut disp = if self.motion {
                arch.get::<&mut Displacement<D::Vec>>()
            } else {
                None
            };
            for p in 0..x.len() {
                let mut l = D::MAT_ZERO;
                let mut vel = D::Vec::ZERO;
                for_each_node::<D, S>(grid, x[p].0, |i, w, grad| {
                    let vi = nv[i].0;
                    if self.gradient {
                        D::add_outer(&mut l, vi, grad);
                    }
                    vel += vi * w;
                });
                if let Some(lg) = lgrad.as_mut() {
                    lg[p].0 = l;
                }
                if self.motion {
                    let du = vel * dt;
                    let xp = x[p].0 + du;
                    if !grid.contains(xp) {
                        let position = D::vec_to3(xp);
                        return Err(if position.iter().all(|c| c.is_finite()) {
                            StepError::PointLeftGrid {
                                step,
                                system: name,
                                point: offset + p,
                                position,
                            }
                        } else {
                            StepError::NonFinite {
                                step,
                                system: name,
                                what: "position",
                                location: format!("point {}", offset + p),
                            }
                        });
                    }
                    x[p].0 = xp;
                    if let Some(u) = disp.as_mut() {
                        u[p].0 += du;
                    }
                }
            }
            offset += x.len();
        }
        Ok(())
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
