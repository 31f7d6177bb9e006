//! Particle-to-grid: mass, momentum and internal force mapped to the nodes (paper step 1).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::lanes::F64x4;
use crate::infra::traffic::Traffic;
use crate::parallel::{scatter, Disjoint};
use crate::schedule::System;
use crate::shape::{for_each_node, from_lanes, Shape, StressColumns};
use crate::systems::exchange::{exchange, MASS, MOMENTUM};
use crate::systems::point_forces::PointForces;
use crate::tensor::StoredSym;
use std::marker::PhantomData;

/// What a [`P2g`] pass maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum P2gPart {
    /// Mass, momentum and internal force in one pass (USL, MUSL).
    All,
    /// Mass and momentum only (first half of USF).
    MassMomentum,
    /// Internal force only (second half of USF, after the stress update).
    InternalForce,
}

/// Maps point mass m_p, momentum m_p v_p and internal force −V_p σ_p·∇w_ip to the grid.
///
/// The force pass also maps each point's other forces ([`PointForces`]: the pore water's
/// load, the hoop stress in axisymmetry), w_ip m_p a_p for a force a_p per unit mass, to
/// the nodal force and their applied part to the external force. They ride on the
/// stress's pass because the weights are already at hand there: a pass of their own would
/// cost as much again as the mapping of the stress.
///
/// Points are grouped in slabs of grid rows that scatter in parallel, slabs that share no
/// node at a time (see `parallel::scatter`).
#[derive(Debug)]
pub struct P2g<D: Dim, S> {
    part: P2gPart,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl P2gPart {
    /// Whether the pass maps (mass and momentum, internal force).
    fn maps(self) -> (bool, bool) {
        match self {
            P2gPart::All => (true, true),
            P2gPart::MassMomentum => (true, false),
            P2gPart::InternalForce => (false, true),
        }
    }
}

impl<D: Dim, S: Shape> P2g<D, S> {
    /// A pass that maps `part`.
    pub fn new(part: P2gPart) -> Self {
        P2g {
            part,
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for P2g<D, S> {
    fn name(&self) -> &str {
        match self.part {
            P2gPart::All => "p2g",
            P2gPart::MassMomentum => "p2g_momentum",
            P2gPart::InternalForce => "p2g_force",
        }
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        self.map(ctx);
        // Over MPI: the nodal mass and momentum are whole before anything reads them (the
        // internal force is summed with the external ones, before `boundary`).
        if self.part != P2gPart::InternalForce {
            exchange(ctx, MASS | MOMENTUM);
        }
        Ok(())
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        let (w, n) = (&ctx.world, ctx.state.active_nodes.len());
        let (mass_momentum, force) = self.part.maps();
        let mut t = Traffic::NONE
            .read_order::<Position<D::Vec>>(w)
            .read_points::<Position<D::Vec>>(w);
        if mass_momentum {
            t = t
                .read_points::<Mass>(w)
                .read_points::<Velocity<D::Vec>>(w)
                .update_nodes::<NodeMass>(n)
                .update_nodes::<NodeMomentum<D::Vec>>(n);
        }
        if force {
            t = t
                .read_points::<Stress<D::Stress>>(w)
                .read_points::<Volume>(w)
                .update_nodes::<NodeForce<D::Vec>>(n);
            // The point forces besides the stress (`PointForces`): the water reads the
            // points' materials; both read the mass and add to the external force.
            let water = ctx.model.water.is_some();
            if water || D::AXISYMMETRIC {
                t = t.update_nodes::<NodeExternalForce<D::Vec>>(n);
                if !mass_momentum {
                    t = t.read_points::<Mass>(w);
                }
            }
            if water {
                t = t.read_points::<MaterialId>(w);
            }
        }
        Some(t)
    }
}

impl<D: Dim, S: Shape> P2g<D, S> {
    /// The scatter of this pass's part into the nodes.
    fn map(&self, ctx: &mut Context<D>) {
        let grid = &ctx.grid;
        let mut reached = ctx.state.active_nodes;
        let n = nodes(&ctx.world);
        let mut nm = col_mut::<NodeMass>(n);
        let mut np = col_mut::<NodeMomentum<D::Vec>>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        let sources = PointForces::of(&ctx.model, ctx.numerics.dt, ctx.state.clock.time);
        let by_material = sources.need_materials();
        let (mass_momentum, force) = self.part.maps();
        for arch in points_with::<Position<D::Vec>>(&ctx.world) {
            let xg = col::<Position<D::Vec>>(arch);
            let mg = col::<Mass>(arch);
            let vg = col::<Velocity<D::Vec>>(arch);
            // Load carriers have no volume or stress and add no internal force.
            let sg = arch.get::<&Stress<D::Stress>>();
            let volg = arch.get::<&Volume>();
            let stressed = sg.as_deref().zip(volg.as_deref());
            let force = force && stressed.is_some();
            // The points' materials, where a source reads them.
            let idg = by_material.then(|| arch.get::<&MaterialId>()).flatten();
            let forces = sources.on(idg.as_deref());
            if !mass_momentum && !force {
                continue;
            }
            let (x, m, v) = (&xg[..], &mg[..], &vg[..]);
            let target = (
                (Disjoint::new(&mut nm), Disjoint::new(&mut np)),
                Disjoint::new(&mut nf),
                Disjoint::new(&mut ne),
            );
            reached = reached.union(scatter(
                ctx.slabs.slabs(grid, x),
                grid,
                S::SUPPORT,
                &target,
                |points, ((nm, np), nf, ne), lo| {
                    // The sources' few words copied here, so that the loop holds them in
                    // registers rather than reaching them through the closure's references.
                    let here = forces;
                    for &p in points {
                        let p = p as usize;
                        let (mp, mv) = (m[p].0, v[p].0 * m[p].0);
                        let f = match (stressed, force) {
                            (Some((s, vol)), true) => Some((&s[p].0, -vol[p].0)),
                            _ => None,
                        };
                        // Forces on the point besides its stress's divergence, per unit of its
                        // mass (N/kg): all of them, and the applied part.
                        let extra = match f {
                            Some((s, neg_vol)) => here.at::<D>(p, x[p].0, mp, -neg_vol, s),
                            _ => None,
                        };
                        // One loop per case, so that the node loop holds no branch.
                        match (mass_momentum, f) {
                            (true, Some((s, neg_vol))) if extra.is_some() => {
                                let (a, applied) = extra.expect("matched");
                                S::scatter_with_gradient(
                                    grid,
                                    x[p].0,
                                    mp,
                                    mv,
                                    &s.to_sym3(),
                                    neg_vol,
                                    |i, dm, dp, df| {
                                        // dm = w_ip m_p, so a dm = w_ip F_p.
                                        let k = i - lo;
                                        nm[k].0 += dm;
                                        np[k].0 += dp;
                                        nf[k].0 += a.madd(dm, df);
                                        ne[k].0 += applied * dm;
                                    },
                                )
                            }
                            (true, Some((s, neg_vol))) => S::scatter_with_gradient(
                                grid,
                                x[p].0,
                                mp,
                                mv,
                                &s.to_sym3(),
                                neg_vol,
                                |i, dm, dp, df| {
                                    let k = i - lo;
                                    nm[k].0 += dm;
                                    np[k].0 += dp;
                                    nf[k].0 += df;
                                },
                            ),
                            (true, None) => for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                                let k = i - lo;
                                nm[k].0 += w * mp;
                                np[k].0 += mv * w;
                            }),
                            (false, Some((s, neg_vol))) => {
                                let sigma = StressColumns::of(&s.to_sym3(), 1.0);
                                let neg_vol = F64x4::splat(neg_vol);
                                match extra {
                                    Some((a, applied)) => {
                                        let (a, applied) = (a * mp, applied * mp);
                                        for_each_node::<D, S>(grid, x[p].0, |i, w, grad| {
                                            let f = sigma.dot::<D>(grad) * neg_vol;
                                            nf[i - lo].0 += a.madd(w, from_lanes::<D>(f));
                                            ne[i - lo].0 += applied * w;
                                        })
                                    }
                                    None => for_each_node::<D, S>(grid, x[p].0, |i, _, grad| {
                                        let f = sigma.dot::<D>(grad) * neg_vol;
                                        nf[i - lo].0 += from_lanes::<D>(f);
                                    }),
                                }
                            }
                            (false, None) => {}
                        }
                    }
                },
            ));
        }
        ctx.state.active_nodes = reached;
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    use crate::infra::columns::col_mut;
    use crate::scene::{build, LoadedScene};
    use crate::shape::{Linear, QuadraticBSpline};
    use crate::simulation::{AnySimulation, Simulation};
    use crate::systems::GridReset;

    const SCENE: &str = r#"Scene(
        dimension: DIM,
        grid: (origin: ORIGIN, cell_size: 0.5, cells: CELLS),
        materials: { "m": LinearElastic(density: 1800.0, youngs_modulus: 1e7, poisson_ratio: 0.3) },
        bodies: [(material: "m", region: Box(min: MIN, max: MAX), points_per_cell: PPC)],
        gravity: (acceleration: GRAVITY),
        solver: (time_step: Courant(0.5), max_steps: 1),
    )"#;

    fn scene(dim3: bool) -> LoadedScene {
        let t = if dim3 {
            SCENE
                .replace("DIM", "3")
                .replace("ORIGIN", "[0.0, 0.0, 0.0]")
                .replace("CELLS", "[6, 5, 4]")
                .replace("MIN", "[0.2, 0.0, 0.3]")
                .replace("MAX", "[2.9, 1.7, 2.0]")
                .replace("PPC", "[2, 3, 2]")
                .replace("GRAVITY", "[0.0, -9.81, 0.0]")
        } else {
            SCENE
                .replace("DIM", "2")
                .replace("ORIGIN", "[-1.0, 0.0]")
                .replace("CELLS", "[8, 6]")
                .replace("MIN", "[-1.0, 0.0]")
                .replace("MAX", "[2.7, 2.3]")
                .replace("PPC", "[3, 2]")
                .replace("GRAVITY", "[0.0, -9.81]")
        };
        LoadedScene::from_text(std::path::Path::new("test.ron"), &t, &[]).unwrap()
    }

    /// Gives every point a different velocity, maps, and compares grid and point totals.
    fn check<D: Dim, S: Shape>(sim: &mut Simulation<D>) {
        let mut k = 0.0f64;
        for arch in points_with::<Velocity<D::Vec>>(&sim.ctx.world) {
            for v in col_mut::<Velocity<D::Vec>>(arch).iter_mut() {
                k += 1.0;
                v.0 = D::vec_from([(k * 0.37).sin(), (k * 0.11).cos(), (k * 0.53).sin() - 0.2]);
            }
        }
        let (mut mass, mut mom) = (0.0, D::Vec::ZERO);
        for arch in points_with::<Velocity<D::Vec>>(&sim.ctx.world) {
            let (m, v) = (col::<Mass>(arch), col::<Velocity<D::Vec>>(arch));
            for p in 0..m.len() {
                mass += m[p].0;
                mom += v[p].0 * m[p].0;
            }
        }
        GridReset::default().run(&mut sim.ctx).unwrap();
        P2g::<D, S>::new(P2gPart::All).run(&mut sim.ctx).unwrap();
        let n = nodes(&sim.ctx.world);
        let grid_mass: f64 = col::<NodeMass>(n).iter().map(|m| m.0).sum();
        let grid_mom = col::<NodeMomentum<D::Vec>>(n)
            .iter()
            .fold(D::Vec::ZERO, |a, p| a + p.0);
        let grid_force = col::<NodeForce<D::Vec>>(n)
            .iter()
            .fold(D::Vec::ZERO, |a, p| a + p.0);
        assert!((grid_mass / mass - 1.0).abs() < 1e-14, "{grid_mass} vs {mass}");
        let scale = mom.dot(mom).sqrt();
        let d = grid_mom - mom;
        assert!(d.dot(d).sqrt() < 1e-13 * scale, "{grid_mom:?} vs {mom:?}");
        // Zero stress: no internal force anywhere.
        assert_eq!(grid_force, D::Vec::ZERO);
    }

    #[test]
    fn p2g_conserves_mass_and_momentum() {
        for dim3 in [false, true] {
            for bspline in [false, true] {
                let (sim, _) = build(&scene(dim3)).unwrap();
                match sim {
                    AnySimulation::Two(mut s) if bspline => check::<_, QuadraticBSpline>(&mut s),
                    AnySimulation::Two(mut s) => check::<_, Linear>(&mut s),
                    AnySimulation::Three(mut s) if bspline => check::<_, QuadraticBSpline>(&mut s),
                    AnySimulation::Three(mut s) => check::<_, Linear>(&mut s),
                    AnySimulation::Axi(_) => unreachable!("the scenes here are 2D or 3D"),
                }
            }
        }
    }
}
