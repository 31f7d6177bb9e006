//! Point loads: concentrated forces carried by points. Scheduled only when a scene has them.

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::exchange::{exchange, MASS};
use crate::systems::shared::{hold, Hold};
use std::marker::PhantomData;

/// Spreads each point load F over the nodes of its support that carry mass, with the shape
/// weights renormalised over those nodes.
///
/// A load point at the free end of a bar sits on the last node; once the bar stretches its
/// support reaches the empty node beyond, where a share of F would be lost (massless nodes
/// have no degrees of freedom). Renormalising keeps the whole load on the body.
///
/// Each component is spread over the nodes a prescribed motion does not drive along it: a
/// driven node's force is the motion's reaction (`boundary`), so a share of a surcharge
/// beside a node-driven footing that fell on its edge nodes would push the footing instead
/// of the soil, and the footing would read too little (docs/verification.md, "A surcharge
/// beside the footing"). A component whose every carrying node is driven (a load on the
/// motion's own nodes) is spread over them all.
///
/// A point under a pressure ([`crate::SurfacePressures`]) carries −p times its share's area
/// vector now, from its neighbours' places, instead of its set-up load.
#[derive(Debug)]
pub struct PointLoads<D, S> {
    /// The current place of each point under a pressure, in the order of its ids (scratch).
    places: Vec<[f64; 3]>,
    /// Their places on the surface they load (scratch; [`crate::SurfacePressures`]).
    on_surface: Vec<[f64; 3]>,
    dims: PhantomData<fn() -> (D, S)>,
}

impl<D, S> Default for PointLoads<D, S> {
    fn default() -> Self {
        PointLoads {
            places: Vec::new(),
            on_surface: Vec::new(),
            dims: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for PointLoads<D, S> {
    fn name(&self) -> &str {
        "point_loads"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // Over MPI: which nodes carry soil is a question of the whole mass.
        exchange(ctx, MASS);
        let grid = &ctx.grid;
        let min_mass = ctx.numerics.min_node_mass;
        let n = nodes(&ctx.world);
        let nm = col::<NodeMass>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        let pressures = &ctx.model.pressures;
        if !pressures.is_empty() {
            self.places.resize(pressures.ids.len(), [0.0; 3]);
            if ctx.comm.size() > 1 {
                self.places.fill([0.0; 3]);
            }
            for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
                let (x, id) = (col::<Position<D::Vec>>(arch), col::<PointId>(arch));
                for (x, id) in x.iter().zip(id.iter()) {
                    if let Some(k) = pressures.index(id.0) {
                        self.places[k] = D::vec_to3(x.0);
                    }
                }
            }
            // Over several ranks a point's neighbours along its surface may be another
            // rank's: each rank holds its own points' places and zeros, the sums all.
            ctx.comm.sum(self.places.as_flattened_mut());
            pressures.surface_places::<D>(&self.places, &mut self.on_surface);
        }
        let places = &self.on_surface;
        let place = |id: u32| {
            places[pressures
                .index(id)
                .expect("a neighbour is under the pressure too")]
        };
        let fix = col::<NodeFixity>(n);
        let drives = &ctx.state.control.drives[..];
        // The axes along which node `i` is driven by a motion, one bit an axis.
        let driven = |i: usize| -> u8 {
            if drives.is_empty() || fix[i].0 == 0 {
                return 0;
            }
            (0..D::N).fold(0, |m, a| match hold(fix[i], a, drives) {
                Hold::Driven(_) => m | 1 << a,
                _ => m,
            })
        };
        for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
            let x = col::<Position<D::Vec>>(arch);
            let load = col::<PointLoad<D::Vec>>(arch);
            let id = col::<PointId>(arch);
            for p in 0..x.len() {
                let load = match pressures.index(id[p].0) {
                    Some(k) => pressures.force::<D>(k, load[p].0, place),
                    None => load[p].0,
                };
                // The weights of the carrying nodes, all and (per axis) those not driven
                // along it.
                let (mut carried, mut free) = (0.0, [0.0; 3]);
                for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                    if grid.carries(i, nm[i].0, min_mass) {
                        carried += w;
                        let d = driven(i);
                        for (a, free) in free.iter_mut().enumerate().take(D::N) {
                            if d & 1 << a == 0 {
                                *free += w;
                            }
                        }
                    }
                });
                if carried <= 0.0 {
                    return Err(StepError::LoadLost {
                        step: ctx.state.clock.step,
                        point: id[p].0,
                        position: D::vec_to3(x[p].0),
                    });
                }
                // Axes along which some carrying node is free: their share skips the
                // driven nodes; the others go to every carrying node. With no motion every
                // axis is spread over `carried`, summed in the same order: the same bits.
                let skip = (0..D::N).fold(0u8, |m, a| if free[a] > 0.0 { m | 1 << a } else { m });
                let mut f = D::Vec::ZERO;
                for a in 0..D::N {
                    let over = if skip & 1 << a != 0 { free[a] } else { carried };
                    f.set(a, load.get(a) * (1.0 / over));
                }
                for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                    if grid.carries(i, nm[i].0, min_mass) {
                        let mut g = f * w;
                        let off = driven(i) & skip;
                        for a in (0..D::N).filter(|a| off & 1 << a != 0) {
                            g.set(a, 0.0);
                        }
                        nf[i].0 += g;
                        ne[i].0 += g;
                    }
                });
            }
        }
        Ok(())
    }
}
