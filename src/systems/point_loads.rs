//! Point loads: concentrated forces carried by points. Scheduled only when a scene has them.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::schedule::System;
use crate::shape::{for_each_node, Shape};
use std::marker::PhantomData;

/// Spreads each point load F over the nodes of its support that carry mass, with the shape
/// weights renormalised over those nodes.
///
/// A load point at the free end of a bar sits on the last node; once the bar stretches its
/// support reaches the empty node beyond, where a share of F would be lost (massless nodes
/// have no degrees of freedom). Renormalising keeps the whole load on the body.
#[derive(Debug)]
pub struct PointLoads<D, S>(PhantomData<fn() -> (D, S)>);

impl<D, S> Default for PointLoads<D, S> {
    fn default() -> Self {
        PointLoads(PhantomData)
    }
}

impl<D: Dim, S: Shape> System<D> for PointLoads<D, S> {
    fn name(&self) -> &str {
        "point_loads"
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let grid = &ctx.grid;
        let min_mass = ctx.settings.min_node_mass;
        let n = nodes(&ctx.world);
        let nm = col::<NodeMass>(n);
        let mut nf = col_mut::<NodeForce<D::Vec>>(n);
        let mut ne = col_mut::<NodeExternalForce<D::Vec>>(n);
        for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
            let x = col::<Position<D::Vec>>(arch);
            let load = col::<PointLoad<D::Vec>>(arch);
            let id = col::<PointId>(arch);
            for p in 0..x.len() {
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
                let f = load[p].0 * (1.0 / carried);
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

/// Sets the point load of every point named in `loads` (point id, force: N; N/m in 2D,
/// x y z; sorted by id) to `scale` times its force. Loading stages and load control use it.
pub fn set_point_loads<D: Dim>(ctx: &Context<D>, loads: &[(u32, [f64; 3])], scale: f64) {
    for arch in points_with::<PointLoad<D::Vec>>(&ctx.world) {
        let ids = col::<PointId>(arch);
        let mut f = col_mut::<PointLoad<D::Vec>>(arch);
        for (id, f) in ids.iter().zip(f.iter_mut()) {
            if let Ok(k) = loads.binary_search_by_key(&id.0, |l| l.0) {
                f.0 = D::vec_from(loads[k].1.map(|c| c * scale));
            }
        }
    }
}
