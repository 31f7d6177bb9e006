//! Point loads: concentrated forces carried by points. Scheduled only when a scene has them.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use crate::systems::exchange::{exchange, MASS};
use std::marker::PhantomData;

/// Spreads each point load F over the nodes of its support that carry mass, with the shape
/// weights renormalised over those nodes.
///
/// A load point at the free end of a bar sits on the last node; once the bar stretches its
/// support reaches the empty node beyond, where a share of F would be lost (massless nodes
/// have no degrees of freedom). Renormalising keeps the whole load on the body.
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
        for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
            let x = col::<Position<D::Vec>>(arch);
            let load = col::<PointLoad<D::Vec>>(arch);
            let id = col::<PointId>(arch);
            for p in 0..x.len() {
                let load = match pressures.index(id[p].0) {
                    Some(k) => pressures.force::<D>(k, load[p].0, place),
                    None => load[p].0,
                };
                let mut carried = 0.0;
                for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                    if grid.carries(i, nm[i].0, min_mass) {
                        carried += w;
                    }
                });
                if carried <= 0.0 {
                    return Err(StepError::LoadLost {
                        step: ctx.state.clock.step,
                        point: id[p].0,
                        position: D::vec_to3(x[p].0),
                    });
                }
                let f = load * (1.0 / carried);
                for_each_node::<D, S>(grid, x[p].0, |i, w, _| {
                    if grid.carries(i, nm[i].0, min_mass) {
                        nf[i].0 += f * w;
                        ne[i].0 += f * w;
                    }
                });
            }
        }
        Ok(())
    }
}
