//! Cell means of the volumetric strain rate and of the mean stress: a volumetric treatment
//! against locking that holds for dilatant plastic flow.
//!
//! A point of a low-order grid that must flow at a set rate of volume change (ψ = 0: none;
//! ψ > 0: sin ψ times its shear rate) is one constraint on the nodal velocities; four
//! points a cell in 2D (eight in 3D) are twice (2.7 times) the velocity degrees of freedom
//! a cell has, and the grid locks: a limit load grows with the stiffness. Here each
//! background cell holds one volumetric strain rate and one mean stress, the constraint
//! count of the Q1/P0 element (Hughes 1980, B-bar; Mast et al. 2012, "Mitigating kinematic
//! locking in the material point method", J. Comput. Phys. 231, the cell-based
//! Hu–Washizu averaging):
//!
//! θ_c = Σ_{p∈c} V_p tr(L_p) / Σ_{p∈c} V_p,   L_p ← L_p + (θ_c − tr L_p) I / n   (before the stress update),
//!
//! m̄_c = Σ_{p∈c} V_p m_p / Σ_{p∈c} V_p,      σ_p ← σ_p + (m̄_c − m_p) I_n        (after it),
//!
//! with n = `Dim::STRAIN_AXES` (2 in plane strain, where m_p = (σ_xx + σ_yy)/2 and the
//! out-of-plane σ_zz keeps its own; 3 in 3D and axisymmetry, the hoop components
//! included). Both are needed, and in this pairing:
//!
//! - *Power.* With the mean stress constant over a cell, the nodal forces' power
//!   Σ_p V_p σ_p : ∇v equals the points' stress power Σ_p V_p σ_p : D̄_p exactly, since
//!   Σ_{p∈c} V_p m̄_c tr D_p = m̄_c V_c θ_c. Smoothing the strain alone (the nodal
//!   smoothing) leaves Σ_p V_p m_p (θ − tr D_p), which dilatant flow feeds into the kinetic
//!   energy until the run fails (docs/verification.md).
//! - *Strength.* Projecting the mean stress only in the nodal forces (the classical B-bar)
//!   leaves each point's own m_p free to drift in modes no force resists; a frictional
//!   point whose strength follows its m_p then weakens, and a point by a footing's edge
//!   heaves out of the grid. Projecting the points' stress itself keeps the strength on the
//!   stress the forces carry.
//!
//! Where the shift of its mean takes a point outside its yield surface ([`Material::admits`]),
//! the point's own material returns it and its cell is projected again, for a few rounds
//! (`RETURNS`), the last of which scales the deviator at the cell's mean instead. Both
//! systems group the points by the cell that holds them when they run: in USL and MUSL
//! after the points moved, in USF before,
//! the same cells in both, and those of the next particle-to-grid. The points that carry a
//! traction take no part and keep their own rate and stress ([`averaged_points`]).
//!
//! A quadratic B-spline's velocity gradient varies within a cell, so with one volumetric
//! strain rate a cell the in-cell variation of the normal strains goes into the points'
//! deviators. Where the mean stress is small (a cohesionless soil under gravity, near its
//! free surface) that deviator lies on the friction limit, the points yield, and on a coarse
//! grid the soil creeps (docs/verification.md, "Why the cell means move the sand at rest").
//!
//! [`Material::admits`]: crate::materials::Material::admits
//! [`averaged_points`]: crate::systems::shared::averaged_points

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, col_mut};
use crate::infra::decomposition::{ACROSS, SLAB};
use crate::materials::{visit_states, MaterialModel, MaterialState, StateVisitor};
use crate::parallel::CHUNK;
use crate::schedule::System;
use crate::shape::Shape;
use crate::systems::exchange::band_boxes;
use crate::systems::node_pairs::{set_volumetric_rates, NodePairs};
use crate::systems::shared::averaged_points;
use crate::tensor::{StoredSym, Sym3};
use hecs::Archetype;
use rayon::prelude::*;
use std::marker::PhantomData;

/// Which of the two cell means a [`CellMean`] system takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellMeanPart {
    /// The volumetric strain rate, before the stress update.
    Strain,
    /// The mean stress, after it.
    Stress,
}

/// One of the two cell means (see the module's text).
#[derive(Debug)]
pub struct CellMean<D: Dim, S> {
    part: CellMeanPart,
    /// Per cell, at its lowest node: Σ V q, Σ V; then the mean in the first entry.
    sums: NodePairs,
    /// Per cell, at its lowest node: whether a point in it was returned this round (all
    /// false between rounds).
    dirty: Vec<bool>,
    /// The points of each cell, found in a step that returns a point.
    index: CellPoints,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> CellMean<D, S> {
    /// The system that takes `part`'s cell mean.
    pub fn new(part: CellMeanPart) -> Self {
        CellMean {
            part,
            sums: NodePairs::default(),
            dirty: Vec::new(),
            index: CellPoints::default(),
            _marker: PhantomData,
        }
    }
}

/// The mean of a stress over the strain axes (Pa): in plane strain the in-plane mean,
/// whose power the in-plane strain rate's trace takes.
#[inline(always)]
fn mean_stress<D: Dim>(s: &D::Stress) -> f64 {
    let t = s.to_sym3();
    if D::STRAIN_AXES == 2 {
        0.5 * (t.xx + t.yy)
    } else {
        (t.xx + t.yy + t.zz) / 3.0
    }
}

/// `s` with `k` (Pa) added to its normal components on the strain axes.
#[inline(always)]
fn shift_mean<D: Dim>(s: &D::Stress, k: f64) -> D::Stress {
    let mut t = s.to_sym3();
    t.xx += k;
    t.yy += k;
    if D::STRAIN_AXES == 3 {
        t.zz += k;
    }
    D::Stress::from_sym3(&t)
}

impl<D: Dim, S: Shape> System<D> for CellMean<D, S> {
    fn name(&self) -> &str {
        match self.part {
            CellMeanPart::Strain => "cell_mean_strain",
            CellMeanPart::Stress => "cell_mean_stress",
        }
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // A reset step neither strains nor moves the points: the means stand.
        if ctx.motion_dt().is_none() {
            return Ok(());
        }
        match self.part {
            CellMeanPart::Strain => self.strain(ctx),
            CellMeanPart::Stress => self.stress(ctx),
        }
        self.sums.clear(&ctx.grid);
        Ok(())
    }
}

impl<D: Dim, S: Shape> CellMean<D, S> {
    /// Σ_{p∈c} V_p q_p and Σ_{p∈c} V_p over every stressed point, then their ratio.
    fn means<Q: Send + Sync + 'static>(&mut self, ctx: &mut Context<D>, q: impl Fn(&Q) -> f64 + Sync) {
        let grid = &ctx.grid;
        for arch in averaged_points::<D>(&ctx.world) {
            let (xg, vg, qg) = (col::<Position<D::Vec>>(arch), col::<Volume>(arch), col::<Q>(arch));
            let (vol, qs): (&[Volume], &[Q]) = (&vg, &qg);
            self.sums
                .scatter_cells::<D, S>(&mut ctx.slabs, grid, &xg, |p| [vol[p].0 * q(&qs[p]), vol[p].0]);
        }
        self.sums.means_over_ranks(grid, &ctx.comm, &ctx.decomposition);
    }

    /// L_p ← L_p + (θ_c − tr L_p) I / n.
    fn strain(&mut self, ctx: &mut Context<D>) {
        self.means::<VelocityGradient<D::Mat>>(ctx, |l| D::volumetric_rate(&l.0));
        let (grid, sums) = (&ctx.grid, &self.sums);
        set_volumetric_rates::<D>(averaged_points::<D>(&ctx.world), |x| sums.of_cell(grid, x)[0]);
    }

    /// σ_p ← σ_p + (m̄_c − m_p) I_n, and where the point's strength does not admit that,
    /// the return that makes it so: see [`RETURNS`]. The first round visits every point;
    /// the later ones only the cells where a point was returned, whose means alone moved.
    fn stress(&mut self, ctx: &mut Context<D>) {
        self.means::<Stress<D::Stress>>(ctx, |s| mean_stress::<D>(&s.0));
        let mut returned = self.project(ctx, None, RETURNS == 0);
        for round in 1..=RETURNS {
            if !ctx.comm.any(returned.iter().any(|r| !r.is_empty())) {
                break;
            }
            // The cells a returned point is in.
            let grid = &ctx.grid;
            let (dirty, sums) = (&mut self.dirty, &mut self.sums);
            dirty.resize(grid.node_count(), false);
            let mut cells = Vec::new();
            for (arch, points) in averaged_points::<D>(&ctx.world).zip(&returned) {
                let x = col::<Position<D::Vec>>(arch);
                for &p in points {
                    let key = grid.cell_key(x[p as usize].0);
                    if !std::mem::replace(&mut dirty[key], true) {
                        cells.push(key);
                    }
                }
            }
            // Over several ranks the cells of the shared layers may hold points of both:
            // every rank takes them all afresh, whichever rank returned a point in them.
            for key in shared_cells(ctx) {
                if !std::mem::replace(&mut dirty[key], true) {
                    cells.push(key);
                }
            }
            // Every point in them (the points of each cell found once a step), and their
            // means afresh, each cell's summed in archetype and point order as in the
            // first round (cell by cell in parallel: 3D flow returns most points).
            if round == 1 {
                self.index.build(&ctx.world, grid);
            }
            let index = &self.index;
            let guards: Vec<_> = averaged_points::<D>(&ctx.world)
                .map(|arch| (col::<Volume>(arch), col::<Stress<D::Stress>>(arch)))
                .collect();
            let columns: Vec<_> = guards.iter().map(|(v, s)| (&v[..], &s[..])).collect();
            let fresh: Vec<[f64; 2]> = (cells.par_iter().with_min_len(64))
                .map(|&key| {
                    let mut pair = [0.0; 2];
                    for &(a, p) in index.of(key) {
                        let (vol, s) = columns[a as usize];
                        let v = vol[p as usize].0;
                        pair[0] += v * mean_stress::<D>(&s[p as usize].0);
                        pair[1] += v;
                    }
                    pair
                })
                .collect();
            for (&key, pair) in cells.iter().zip(fresh) {
                *sums.at_mut(key) = pair;
            }
            drop(columns);
            drop(guards);
            let active = index.in_cells(&cells, dirty);
            sums.sum_over_ranks(grid, &ctx.comm, &ctx.decomposition);
            let dirty = &mut self.dirty;
            for key in cells {
                let pair = sums.at_mut(key);
                // A shared cell may hold no point.
                if pair[1] > 0.0 {
                    pair[0] /= pair[1];
                }
                dirty[key] = false;
            }
            returned = self.project(ctx, Some(&active), round == RETURNS);
        }
    }

    /// One round of the projection over every archetype: all their points, or `only` those
    /// listed; the points returned, by archetype.
    fn project(&self, ctx: &Context<D>, only: Option<&[Vec<u32>]>, last: bool) -> Vec<Vec<u32>> {
        averaged_points::<D>(&ctx.world)
            .enumerate()
            .map(|(a, arch)| {
                let mut project = Project::<D> {
                    arch,
                    grid: &ctx.grid,
                    sums: &self.sums,
                    materials: &ctx.materials,
                    only: only.map(|o| &o[a][..]),
                    last,
                    returned: None,
                };
                visit_states(&mut project);
                match project.returned {
                    Some(r) => r,
                    None => project.run::<()>(None),
                }
            })
            .collect()
    }
}

/// Every point grouped by the cell that holds it (by the cell's lowest node), a cell's
/// points in archetype then point order: the order a cell's sums take them in.
#[derive(Debug, Default)]
struct CellPoints {
    /// Where each cell's run starts in `points`: one entry a node, and one more.
    start: Vec<u32>,
    /// (archetype among those with a volume, point) by cell.
    points: Vec<(u32, u32)>,
    /// Each point's cell, archetype after archetype (kept between steps for its room).
    keys: Vec<u32>,
    /// Each cell's next free entry while the points are placed (as `keys`).
    next: Vec<u32>,
    /// Where each archetype's points end in `keys`.
    ends: Vec<usize>,
}

impl CellPoints {
    /// Groups the points of `world` as they stand (a counting sort by cell).
    fn build<D: Dim>(&mut self, world: &hecs::World, grid: &Grid<D>) {
        let n = grid.node_count();
        self.keys.clear();
        self.ends.clear();
        for arch in averaged_points::<D>(world) {
            let x = col::<Position<D::Vec>>(arch);
            let from = self.keys.len();
            self.keys.resize(from + x.len(), 0);
            (self.keys[from..].par_chunks_mut(CHUNK))
                .zip(x.par_chunks(CHUNK))
                .for_each(|(k, x)| {
                    k.iter_mut()
                        .zip(x)
                        .for_each(|(k, x)| *k = grid.cell_key(x.0) as u32)
                });
            self.ends.push(self.keys.len());
        }
        self.start.clear();
        self.start.resize(n + 1, 0);
        for &k in &self.keys {
            self.start[k as usize + 1] += 1;
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        self.next.clear();
        self.next.extend_from_slice(&self.start[..n]);
        self.points.resize(self.keys.len(), (0, 0));
        let mut from = 0;
        for (a, &end) in self.ends.iter().enumerate() {
            for (p, &k) in self.keys[from..end].iter().enumerate() {
                let at = &mut self.next[k as usize];
                self.points[*at as usize] = (a as u32, p as u32);
                *at += 1;
            }
            from = end;
        }
    }

    /// The points of the cell whose lowest node is `key`.
    fn of(&self, key: usize) -> &[(u32, u32)] {
        &self.points[self.start[key] as usize..self.start[key + 1] as usize]
    }

    /// The points in `cells` (the cells `dirty` marks), by archetype in point order: from
    /// the cells' lists when they hold few points, else from a scan of every point's cell
    /// (the same lists either way).
    fn in_cells(&self, cells: &[usize], dirty: &[bool]) -> Vec<Vec<u32>> {
        let count: usize = cells.iter().map(|&k| self.of(k).len()).sum();
        let mut active = vec![Vec::new(); self.ends.len()];
        if count * 16 < self.keys.len() {
            for &key in cells {
                for &(a, p) in self.of(key) {
                    active[a as usize].push(p);
                }
            }
            active.iter_mut().for_each(|points| points.sort_unstable());
            return active;
        }
        let mut from = 0;
        for (points, &end) in active.iter_mut().zip(&self.ends) {
            *points = (self.keys[from..end].par_chunks(CHUNK).enumerate())
                .flat_map_iter(|(c, keys)| {
                    (keys.iter().enumerate())
                        .filter(|&(_, &k)| dirty[k as usize])
                        .map(move |(k, _)| (c * CHUNK + k) as u32)
                })
                .collect();
            from = end;
        }
        active
    }
}

/// The cells (by their lowest node) of the node layers this rank shares with its
/// neighbours; none with one rank.
fn shared_cells<D: Dim>(ctx: &Context<D>) -> impl Iterator<Item = usize> + '_ {
    let several = ctx.comm.size() > 1;
    let bands = [SLAB, ACROSS]
        .into_iter()
        .filter(move |_| several)
        .flat_map(|axis| {
            band_boxes(&ctx.grid, &ctx.decomposition, axis)
                .into_iter()
                .flatten()
        });
    bands.flat_map(|(_, b)| b.rows(&ctx.grid)).flatten()
}

/// How many times a step returns the points that the shift of their mean took outside
/// their yield surface, before it scales their deviators instead.
///
/// The points of a cell share one mean stress, so a plastic return at one point (which
/// moves its mean: dilatancy) is shared by the others at the next projection, which may
/// take one of them outside in turn. The cell's stress is the fixed point of the pair
/// "project, return": the mixed formulation's local problem, each point on or inside its
/// surface at the cell's mean (Simo, Taylor & Pister 1985). Left to the next steps, the pair
/// relaxes the stress step after step with no strain, and a footing never comes to rest (K_F
/// held at 1.7e-3); scaling the deviator at once instead holds the mean but dissipates
/// strength (the c–φ footing 4–9 % under Prandtl–Reissner). A few rounds settle a step;
/// what is left after them is scaled.
const RETURNS: usize = 8;

/// The projection of one archetype's stresses, with the state column it carries (the
/// strength of a softening soil is in its state, and a return adds to it).
struct Project<'a, D: Dim> {
    arch: &'a Archetype,
    grid: &'a Grid<D>,
    sums: &'a NodePairs,
    materials: &'a [MaterialModel],
    /// The points to visit, all when `None`.
    only: Option<&'a [u32]>,
    /// The last round: scale the deviators of the points still outside.
    last: bool,
    /// The points returned, once the archetype's state column was found.
    returned: Option<Vec<u32>>,
}

impl<D: Dim> StateVisitor for Project<'_, D> {
    fn visit<S: MaterialState>(&mut self) {
        if self.returned.is_none() && std::mem::size_of::<S>() > 0 {
            if let Some(states) = self.arch.get::<&mut S>() {
                self.returned = Some(self.run(Some(states)));
            }
        }
    }
}

impl<D: Dim> Project<'_, D> {
    /// Projects the points, `states` their state column (`None` for points without
    /// state); gives the points returned to their yield surface, in point order.
    fn run<S: MaterialState>(&self, states: Option<hecs::ArchetypeColumnMut<'_, S>>) -> Vec<u32> {
        let (grid, sums, materials, last) = (self.grid, self.sums, self.materials, self.last);
        let (xg, mg) = (col::<Position<D::Vec>>(self.arch), col::<MaterialId>(self.arch));
        let (x, mat): (&[Position<D::Vec>], &[MaterialId]) = (&xg, &mg);
        let mut sg = col_mut::<Stress<D::Stress>>(self.arch);
        // One point: true when it was returned.
        let point = |p: usize, sp: &mut Stress<D::Stress>, state: &mut S| {
            let mean = sums.of_cell(grid, x[p].0)[0];
            let mut t = shift_mean::<D>(&sp.0, mean - mean_stress::<D>(&sp.0)).to_sym3();
            let model = &materials[mat[p].0 as usize];
            let mut returned = false;
            if !model.admits(&t, state) {
                if last {
                    t = scale_deviator(&t, mean, |t| model.admits(t, state));
                }
                // A mean beyond the strength in tension (a cell at a free surface pulled
                // apart) admits no deviator at all: the material's return takes the point
                // to its tension limit, which no cell mean may pass.
                if !last || !model.admits(&t, state) {
                    model.update(&mut t, &Sym3::ZERO, state);
                    returned = !last;
                }
            }
            sp.0 = D::Stress::from_sym3(&t);
            returned
        };
        // The points of one chunk of CHUNK rows, c its number: all of them, or in a later
        // round those `only` lists (in point order); gives those returned.
        let only = self.only;
        let chunk = |c: usize, s: &mut [Stress<D::Stress>], st: &mut [S]| -> Vec<u32> {
            let (first, len) = (c * CHUNK, s.len());
            let mut visit = |k: usize| point(first + k, &mut s[k], &mut st[k]);
            let id = |k: usize| (first + k) as u32;
            match only {
                None => (0..len).filter(|&k| visit(k)).map(id).collect(),
                Some(only) => {
                    let lo = only.partition_point(|&p| (p as usize) < first);
                    let hi = only.partition_point(|&p| (p as usize) < first + len);
                    only[lo..hi]
                        .iter()
                        .map(|&p| p as usize - first)
                        .filter(|&k| visit(k))
                        .map(id)
                        .collect()
                }
            }
        };
        match states {
            Some(mut states) => sg
                .par_chunks_mut(CHUNK)
                .zip(states.par_chunks_mut(CHUNK))
                .enumerate()
                .flat_map_iter(|(c, (s, st))| chunk(c, s, st))
                .collect(),
            // A state of no size: the slice costs no memory.
            None => sg
                .par_chunks_mut(CHUNK)
                .enumerate()
                .flat_map_iter(|(c, s)| chunk(c, s, &mut vec![S::default(); s.len()]))
                .collect(),
        }
    }
}

/// m I + α (σ − m I) with the largest α in [0, 1] (to 2⁻⁴⁰) that `admits` takes; α = 0
/// where none does (a mean beyond the tension cut-off, which the caller then returns).
/// The mean over the strain axes stays m: in plane strain σ_zz − m scales with the rest,
/// and σ_xx + σ_yy stays 2m.
///
/// The last resort of [`RETURNS`]: it holds the mean, so the projection is done.
fn scale_deviator(sigma: &Sym3, m: f64, admits: impl Fn(&Sym3) -> bool) -> Sym3 {
    let at = |a: f64| Sym3 {
        xx: m + a * (sigma.xx - m),
        yy: m + a * (sigma.yy - m),
        zz: m + a * (sigma.zz - m),
        xy: a * sigma.xy,
        yz: a * sigma.yz,
        zx: a * sigma.zx,
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if admits(&at(mid)) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    at(lo)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The last resort keeps the mean of the strain axes and ends on the surface: here a
    /// Tresca-like cap on the in-plane radius, 10 kPa.
    #[test]
    fn scaling_the_deviator_keeps_the_mean_and_ends_on_the_surface() {
        let sigma = Sym3 {
            xx: -50.0e3,
            yy: -10.0e3,
            zz: -20.0e3,
            xy: 15.0e3,
            yz: 0.0,
            zx: 0.0,
        };
        let m = 0.5 * (sigma.xx + sigma.yy);
        let radius = |t: &Sym3| (0.25 * (t.xx - t.yy).powi(2) + t.xy * t.xy).sqrt();
        let capped = scale_deviator(&sigma, m, |t| radius(t) <= 10.0e3);
        assert_eq!(0.5 * (capped.xx + capped.yy), m);
        assert!(radius(&capped) <= 10.0e3 && radius(&capped) > 10.0e3 * (1.0 - 1e-11));
        // σ_zz scales about the same mean.
        assert!((capped.zz - m) / (sigma.zz - m) > 0.0);
        // Nothing admitted: the mean alone.
        let none = scale_deviator(&sigma, m, |_| false);
        assert_eq!((none.xx, none.yy, none.zz, none.xy), (m, m, m, 0.0));
    }
}
