//! Which side of a thin rigid body the soil at a node lies against, so that a body driven
//! away from soil beyond its far face leaves it.
//!
//! The grid holds one soil velocity a node, whichever side of a body its points lie on. A
//! body thinner than the shape functions' reach from both its faces (SUPPORT cells: 3 for
//! B-splines, 2 for linear shapes) has nodes that the soil beyond one face reaches and the
//! constraints of the opposite face hold. Driven into that soil, the far face's hold only
//! keeps the soil's lightest nodes moving with the body, as the soil next to a pushing face
//! does. Driven away from it, the hold is a tension the interface cannot carry: a strip
//! 0.25 m thick pulled up off clay dragged it with 3–5 kN/m through its top face's samples
//! and the nodes inside it nearer its top (docs/verification.md, "Bodies, meshes, water
//! and the axis at their extremes").
//!
//! For a thin body with a motion or a load, every step, each point near it adds
//! w_ip m_p n_p to the nodes it reaches, n_p the outward normal of the body's surface
//! nearest the point:
//!
//! N_i = Σ_p w_ip m_p n_p,
//!
//! the faces the node's soil lies against. Where the body is driven away from them
//! (d·N_i < 0, d its velocity or its load), a constraint whose normal n is turned more than
//! about 105° from N_i (N_i·n < −¼|N_i|, [`OPPOSED`]) does not hold the node: a surface
//! sample leaves it out (of the nodes it holds and of the soil its support must meet), a
//! node inside the body takes no constraint. Soil on both sides of a body within the reach
//! of one node is one field there.
//!
//! A body is thin when some sample's inward ray leaves the body, into the grid its
//! surface can reach over its travel, within SUPPORT cells (looked at every quarter cell,
//! once, at the first step; a sample on a face of the grid, as a cone's edge on the axis,
//! is not looked through). A body that is not thin, or holds its place, is not summed and
//! its contacts are those it had without this test, bit for bit; so are those of a thin
//! body driven into the soil it holds. Over several ranks each rank sums its own points
//! over a box of nodes that every rank draws alike, and the sums are made whole on every
//! rank.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::grid::{Grid, NodeBox};
use crate::infra::columns::{col, points_with};
use crate::rigid::RigidBody;
use crate::shape::{for_each_node, Shape};

/// N̂·n below this: the soil at the node lies behind the face whose constraint has normal
/// n (turned from it by more than cos⁻¹(−¼) ≈ 104.5°).
pub const OPPOSED: f64 = -0.25;

/// Per thin driven body, N_i over a box of nodes round it (see the module's notes).
#[derive(Debug, Default)]
pub struct SoilSide {
    /// Per body, the direction it is driven along (its motion's velocity or its load) when
    /// it is thin and driven; found at the first step.
    drives: Option<Vec<Option<[f64; 3]>>>,
    /// Per body, this step's sums (empty for a body that is not thin and driven).
    tables: Vec<Table>,
}

/// The sums N_i over a box of nodes (ids of the grid that names the contacts' nodes).
#[derive(Debug, Default)]
struct Table {
    /// Per node id, its index in `sums` (`u32::MAX`: outside the box).
    index: Vec<u32>,
    /// The box's node ids, in the order of `sums` (ascending).
    nodes: Vec<usize>,
    /// N_i (kg, x y z).
    sums: Vec<[f64; 3]>,
    /// The direction the body is driven along (x y z, not unit).
    drive: [f64; 3],
}

impl Table {
    /// N_i at node `i` (id), `None` outside the box.
    fn at(&self, i: usize) -> Option<[f64; 3]> {
        let k = *self.index.get(i)?;
        (k != u32::MAX).then(|| self.sums[k as usize])
    }
}

impl SoilSide {
    /// Sums N_i round every thin driven body at its current place, over the nodes of
    /// `grid` (the grid that names the contacts' nodes: over several ranks, the whole grid).
    pub fn gather<D: Dim, S: Shape>(&mut self, ctx: &Context<D>, grid: &Grid<D>) {
        let bodies = &ctx.model.bodies;
        let bounds = (D::vec_to3(grid.origin), D::vec_to3(grid.max_corner()));
        let drives = self.drives.get_or_insert_with(|| {
            (bodies.iter())
                .map(|b| {
                    let drive = (b.spec.motion.as_ref().map(|m| m.vector()))
                        .or_else(|| b.spec.load.as_ref().map(|l| l.vector()))?;
                    is_thin(b, D::N, grid.cell_size, S::SUPPORT, bounds).then_some(drive)
                })
                .collect()
        });
        self.tables.resize_with(bodies.len(), Table::default);
        let h = grid.cell_size;
        // A sample holds the nodes within half the support of it; a point adds to the
        // nodes within half the support of it.
        let reach = 0.5 * S::SUPPORT as f64 * h;
        for (b, body) in bodies.iter().enumerate() {
            let table = &mut self.tables[b];
            for &i in &table.nodes {
                table.index[i] = u32::MAX;
            }
            table.nodes.clear();
            table.sums.clear();
            let Some(drive) = drives[b] else { continue };
            table.drive = drive;
            let offset = ctx.state.control.bodies[b].offset;
            let (lo, hi) = body.spec.bounds(D::N);
            let o = D::vec_to3(grid.origin);
            // The nodes within half the support of the body's bounds.
            let mut nodes = NodeBox {
                lo: [0; 3],
                hi: [1; 3],
            };
            for a in 0..D::N {
                let first = ((lo[a] + offset[a] - reach - o[a]) / h).floor().max(0.0) as usize;
                let last = (((hi[a] + offset[a] + reach - o[a]) / h).ceil().max(0.0) as usize)
                    .min(grid.nodes[a] - 1);
                (nodes.lo[a], nodes.hi[a]) = (first.min(last), last + 1);
            }
            table.index.resize(grid.node_count(), u32::MAX);
            for id in nodes.rows(grid).flatten() {
                table.index[id] = table.nodes.len() as u32;
                table.nodes.push(id);
            }
            table.sums.resize(table.nodes.len(), [0.0; 3]);
            let near = |x: [f64; 3]| {
                (0..D::N).all(|a| {
                    x[a] >= lo[a] + offset[a] - 2.0 * reach && x[a] <= hi[a] + offset[a] + 2.0 * reach
                })
            };
            for arch in points_with::<Volume>(&ctx.world) {
                let (xg, mg) = (col::<Position<D::Vec>>(arch), col::<Mass>(arch));
                for (x, m) in xg.iter().zip(mg.iter()) {
                    let x3 = D::vec_to3(x.0);
                    if !near(x3) {
                        continue;
                    }
                    let at: [f64; 3] = std::array::from_fn(|a| x3[a] - offset[a]);
                    let (_, n, _) = body.spec.distance(at, D::N);
                    for_each_node::<D, S>(grid, x.0, |i, w, _| {
                        let k = table.index[i];
                        if k != u32::MAX {
                            let s = &mut table.sums[k as usize];
                            (0..3).for_each(|a| s[a] += w * m.0 * n[a]);
                        }
                    });
                }
            }
            ctx.comm.sum(table.sums.as_flattened_mut());
        }
    }

    /// Whether body `body`'s constraint of outward normal `normal` at node `node` (an id of
    /// the grid [`SoilSide::gather`] was given) lets the node go: the body is thin and
    /// driven away from the faces the node's soil lies against, which are turned from
    /// `normal` by more than about 105°. False wherever nothing was summed.
    pub fn lets_go(&self, body: usize, node: usize, normal: [f64; 3]) -> bool {
        let Some(table) = self.tables.get(body) else {
            return false;
        };
        let Some(s) = table.at(node) else {
            return false;
        };
        let dot = |a: [f64; 3]| s[0] * a[0] + s[1] * a[1] + s[2] * a[2];
        let size = dot(s).sqrt();
        dot(table.drive) < 0.0 && dot(normal) < OPPOSED * size
    }
}

/// Whether some sample of `body` looks through it, within `support` cells of size `cell`
/// (m), at a place strictly inside the grid `bounds` (lower, upper corner, m) as its
/// surface can reach it over its travel: soil there would reach the nodes the sample
/// holds. A sample on a face of the grid (a cone's edge along the axis) meets no soil and
/// is not looked through.
fn is_thin(body: &RigidBody, n: usize, cell: f64, support: usize, bounds: ([f64; 3], [f64; 3])) -> bool {
    let reach = body.spec.reach(n, bounds.0, bounds.1, 0.0);
    let margin = 1e-9 * cell;
    let within = |x: [f64; 3]| (0..n).all(|a| x[a] > reach.lo[a] + margin && x[a] < reach.hi[a] - margin);
    let probes = 4 * support;
    body.samples.iter().any(|(s, _)| {
        within(s.x)
            && (1..=probes).find_map(|k| {
                let t = 0.25 * cell * k as f64;
                let x: [f64; 3] = std::array::from_fn(|a| s.x[a] - t * s.normal[a]);
                (body.spec.distance(x, n).0 > margin).then(|| within(x))
            }) == Some(true)
    })
}
