//! The strength of the soil beside a body's surface: what a `Rough` interface carries.
//!
//! A rough interface is as strong as the soil it touches: the soil moves with the body
//! until the shear on the surface reaches the soil's own strength on that plane,
//! τ = c + σ_n tan φ (σ_n the normal pressure the body takes there), and then slips in a
//! skin along it. On Tresca clay that is a shear of c_u, the fully rough interface of the
//! plasticity solutions (the T-bar and the ball of Randolph & Houlsby 1984 and Martin &
//! Randolph 2006, the cone's α = 1 of Teh & Houlsby 1991); a no-slip face would hold
//! more than the clay beside it can (a no-slip cone face carries 3–6 c_u,
//! docs/verification.md).
//!
//! Each step the points in the cells round the rough samples give their model's (c, tan φ)
//! at their stress and state ([`crate::materials::Material::plane_strength`]), summed per
//! cell with their mass; a node takes the sums of the 2ⁿ cells it is a corner of, and a
//! sample the mean over its nodes weighted by w_i times the nodes' sums of mass:
//!
//! c_s = Σ_i w_i Σ_{p∈cells(i)} m_p c_p / Σ_i w_i Σ_{p∈cells(i)} m_p, and tan φ_s alike.
//!
//! Its friction is then tan φ_s on the normal impulse it leans on and its adhesion c_s·A_s·Δt,
//! the caps of a `Frictional` interface ([`crate::rigid::contact`]). Each mean is held
//! within the least and the largest value of the points it averages, so that a soil of
//! one strength gives exactly that strength, however its points are summed (over several
//! ranks the sums come in another order, and a cap one bit off grows, through the
//! relaxation, into a curve that differs in its fourth figure). A sample whose nodes
//! meet no point with strength (an elastic soil) holds the soil without slip. Over several
//! ranks each rank sums its own points and the sums are made whole on every rank; the
//! pass reads the points once a step, and only in a scene with a rough part. A scene of
//! one material whose strength is the same at every stress and state (Mohr–Coulomb) is
//! not summed: every rough sample takes that strength, the value the sums would give
//! wherever a sample's nodes meet its points.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::grid::Grid;
use crate::infra::columns::{col, points_with};
use crate::materials::{with_state_column, MaterialState, WithStates};
use crate::rigid::InterfaceLaw;
use crate::tensor::StoredSym;

/// How far round a rough sample's cell the points are summed (cells along each axis): a
/// sample's nodes lie within two cells of its own for every shape, and a node's cells
/// within one of it.
const REACH: usize = 2;

/// Per cell round the rough samples: Σ m, Σ m c, Σ m tan φ over its points with strength.
/// Cells are keyed by the id of their lowest node in the whole grid's numbering
/// ([`Grid::whole`], [`Grid::cell_key`]), the same on every rank.
#[derive(Debug, Default)]
pub struct SoilStrength {
    /// Per cell key: its index in `cells` (`u32::MAX`: not summed). All `u32::MAX` for
    /// cells not in `cells`.
    index: Vec<u32>,
    /// The summed cells' keys, ascending.
    cells: Vec<usize>,
    /// Per summed cell: Σ m (kg), Σ m c (kg Pa), Σ m tan φ (kg).
    sums: Vec<[f64; 3]>,
    /// Per summed cell: −min c, max c (Pa), −min tan φ, max tan φ over its points with
    /// strength (−∞ where it has none), so that one reduction (max) takes both bounds.
    bounds: Vec<[f64; 4]>,
    /// The soil's (c, tan φ) when the scene has one material and its strength is the same
    /// at every stress and state ([`crate::materials::Material::constant_strength`]):
    /// every rough sample takes it, and no points are summed.
    uniform: Option<(f64, f64)>,
}

impl SoilStrength {
    /// Sums the points round every rough sample of the scene's bodies at the body's current
    /// place; nothing (and no table) when no part is rough.
    pub fn gather<D: Dim>(&mut self, ctx: &Context<D>) {
        for &c in &self.cells {
            self.index[c] = u32::MAX;
        }
        self.cells.clear();
        self.sums.clear();
        self.bounds.clear();
        let bodies = &ctx.model.bodies;
        if !bodies.iter().any(|b| b.interfaces.contains(&InterfaceLaw::Soil)) {
            return;
        }
        self.uniform = match &ctx.materials[..] {
            [one] => one.constant_strength(),
            _ => None,
        };
        if self.uniform.is_some() {
            return;
        }
        // Cells are keyed by the whole grid's numbering, the same on every rank.
        let grid = &ctx.grid.whole();
        self.index.resize(grid.node_count(), u32::MAX);
        let cells = grid.cells();
        for (body, state) in bodies.iter().zip(&ctx.state.control.bodies) {
            let offset = state.offset;
            for (s, part) in &body.samples {
                if body.interfaces[*part] != InterfaceLaw::Soil {
                    continue;
                }
                let x = D::vec_from(std::array::from_fn(|a| s.x[a] + offset[a]));
                let Some(c) = grid.cell_of(x) else { continue };
                let range = |a: usize| {
                    if a < D::N {
                        c[a].saturating_sub(REACH)..(c[a] + REACH + 1).min(cells[a])
                    } else {
                        0..1
                    }
                };
                for k in range(2) {
                    for j in range(1) {
                        for i in range(0) {
                            let key = grid.node_id([i, j, k]);
                            if self.index[key] == u32::MAX {
                                self.index[key] = 0;
                                self.cells.push(key);
                            }
                        }
                    }
                }
            }
        }
        if self.cells.is_empty() {
            return;
        }
        self.cells.sort_unstable();
        for (n, &c) in self.cells.iter().enumerate() {
            self.index[c] = n as u32;
        }
        self.sums = vec![[0.0; 3]; self.cells.len()];
        self.bounds = vec![[f64::NEG_INFINITY; 4]; self.cells.len()];
        for arch in points_with::<Volume>(&ctx.world) {
            with_state_column(
                arch,
                &mut Summing {
                    ctx,
                    grid,
                    strength: self,
                },
            );
        }
        ctx.comm.sum(self.sums.as_flattened_mut());
        ctx.comm.max(self.bounds.as_flattened_mut());
    }

    /// The sums of mass and of mass times c and tan φ over the cells that have node `i`
    /// (id) as a corner, and the bounds of c and tan φ there (as [`SoilStrength::bounds`]).
    fn at_node<D: Dim>(&self, grid: &Grid<D>, i: usize) -> ([f64; 3], [f64; 4]) {
        let ijk = grid.node_ijk(i);
        let cells = grid.cells();
        let mut sum = [0.0; 3];
        let mut bounds = [f64::NEG_INFINITY; 4];
        for corner in 0..1usize << D::N {
            let mut c = ijk;
            let mut inside = true;
            for (a, ca) in c.iter_mut().enumerate().take(D::N) {
                if corner >> a & 1 == 1 {
                    inside &= *ca > 0;
                    *ca = ca.wrapping_sub(1);
                }
                inside &= *ca < cells[a];
            }
            if !inside {
                continue;
            }
            let k = self.index[grid.node_id(c)];
            if k != u32::MAX {
                let (s, b) = (self.sums[k as usize], self.bounds[k as usize]);
                (0..3).for_each(|q| sum[q] += s[q]);
                (0..4).for_each(|q| bounds[q] = bounds[q].max(b[q]));
            }
        }
        (sum, bounds)
    }

    /// A surface sample's caps under its part's `law` (tan δ, and the adhesion a in Pa):
    /// Coulomb's own, or for a rough part the soil's beside the sample reaching `nodes`
    /// (ids of the whole `grid`, weights), infinite (no slip) where that soil has no strength.
    pub fn caps<D: Dim>(
        &self,
        law: InterfaceLaw,
        grid: &Grid<D>,
        nodes: impl Iterator<Item = (usize, f64)>,
    ) -> (f64, f64) {
        let law = match (law, self.uniform) {
            (InterfaceLaw::Soil, Some((c, tan))) => InterfaceLaw::Coulomb {
                friction: tan,
                adhesion: c,
            },
            (InterfaceLaw::Soil, None) => self.at_sample(grid, nodes).unwrap_or(law),
            (law, _) => law,
        };
        match law {
            InterfaceLaw::Coulomb { friction, adhesion } => (friction, adhesion),
            InterfaceLaw::Soil => (f64::INFINITY, f64::INFINITY),
        }
    }

    /// The soil's Coulomb line (tan φ, and c as the adhesion) at a sample reaching `nodes`
    /// (ids) with weights `w`; `None` when none of them meets a point with strength.
    pub fn at_sample<D: Dim>(
        &self,
        grid: &Grid<D>,
        nodes: impl Iterator<Item = (usize, f64)>,
    ) -> Option<InterfaceLaw> {
        let mut sum = [0.0; 3];
        let mut bounds = [f64::NEG_INFINITY; 4];
        for (i, w) in nodes {
            let (s, b) = self.at_node(grid, i);
            if w > 0.0 && s[0] > 0.0 {
                (0..3).for_each(|q| sum[q] += w * s[q]);
                (0..4).for_each(|q| bounds[q] = bounds[q].max(b[q]));
            }
        }
        (sum[0] > 0.0).then(|| InterfaceLaw::Coulomb {
            friction: (sum[2] / sum[0]).clamp(-bounds[2], bounds[3]),
            adhesion: (sum[1] / sum[0]).clamp(-bounds[0], bounds[1]),
        })
    }
}

/// Adds an archetype's points in summed cells to their cell's sums.
struct Summing<'a, D: Dim> {
    ctx: &'a Context<D>,
    /// The whole grid, whose numbering keys the cells.
    grid: &'a Grid<D>,
    strength: &'a mut SoilStrength,
}

impl<D: Dim> WithStates for Summing<'_, D> {
    fn with<T: MaterialState>(&mut self, arch: &hecs::Archetype, states: Option<&[T]>) {
        let (xg, mg, ig, sg) = (
            col::<Position<D::Vec>>(arch),
            col::<Mass>(arch),
            col::<MaterialId>(arch),
            col::<Stress<D::Stress>>(arch),
        );
        let (grid, materials) = (self.grid, &self.ctx.materials);
        let s = &mut *self.strength;
        for p in 0..xg.len() {
            let k = s.index[grid.cell_key(xg[p].0)];
            if k == u32::MAX {
                continue;
            }
            let sigma = sg[p].0.to_sym3();
            let model = &materials[ig[p].0 as usize];
            let strength = match states {
                Some(st) => model.plane_strength(&sigma, &st[p]),
                None => model.plane_strength(&sigma, &()),
            };
            if let Some((c, tan)) = strength {
                let m = mg[p].0;
                let sum = &mut s.sums[k as usize];
                sum[0] += m;
                sum[1] += m * c;
                sum[2] += m * tan;
                let b = &mut s.bounds[k as usize];
                *b = [b[0].max(-c), b[1].max(c), b[2].max(-tan), b[3].max(tan)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dim::Dim2;
    use glam::DVec2;

    /// A strength table over a 4 × 4 grid (h = 1 m) with the sums of two cells given.
    fn two_cells(grid: &Grid<Dim2>) -> SoilStrength {
        let mut s = SoilStrength {
            index: vec![u32::MAX; grid.node_count()],
            ..SoilStrength::default()
        };
        // Cell (0, 0): 1 kg of clay, c = 10 kPa; cell (1, 0): 3 kg of sand, tan φ = 0.5.
        for (n, (cell, sums)) in [([0, 0, 0], [1.0, 10.0e3, 0.0]), ([1, 0, 0], [3.0, 0.0, 1.5])]
            .into_iter()
            .enumerate()
        {
            let key = grid.node_id(cell);
            s.index[key] = n as u32;
            s.cells.push(key);
            s.sums.push(sums);
            let (c, t) = (sums[1] / sums[0], sums[2] / sums[0]);
            s.bounds.push([-c, c, -t, t]);
        }
        s
    }

    #[test]
    fn a_node_takes_the_mass_weighted_strength_of_the_cells_it_corners() {
        let grid = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [4, 4, 0]);
        let s = two_cells(&grid);
        // Node (1, 0) corners both cells (and none below the grid's edge).
        let law = s.at_sample(&grid, [(grid.node_id([1, 0, 0]), 1.0)].into_iter());
        let expect = InterfaceLaw::Coulomb {
            friction: 1.5 / 4.0,
            adhesion: 10.0e3 / 4.0,
        };
        assert_eq!(law, Some(expect));
        // Node (0, 0) corners the clay's cell alone: c = 10 kPa, no friction.
        let law = s.at_sample(&grid, [(grid.node_id([0, 0, 0]), 1.0)].into_iter());
        assert_eq!(
            law,
            Some(InterfaceLaw::Coulomb {
                friction: 0.0,
                adhesion: 10.0e3
            })
        );
    }

    #[test]
    fn a_sample_weighs_its_nodes_by_shape_weight_times_mass() {
        let grid = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [4, 4, 0]);
        let s = two_cells(&grid);
        // Nodes (0, 0) (1 kg) and (2, 0) (the sand's 3 kg) at weights 0.75 and 0.25: mass
        // times weight 0.75 and 0.75, so the mean of the two.
        let nodes = [(grid.node_id([0, 0, 0]), 0.75), (grid.node_id([2, 0, 0]), 0.25)];
        let law = s.at_sample(&grid, nodes.into_iter());
        assert_eq!(
            law,
            Some(InterfaceLaw::Coulomb {
                friction: 0.25,
                adhesion: 5.0e3
            })
        );
        // Nodes that corner no summed cell (no point with strength): no law, no slip.
        assert_eq!(
            s.at_sample(&grid, [(grid.node_id([3, 3, 0]), 1.0)].into_iter()),
            None
        );
    }

    #[test]
    fn a_soil_of_one_constant_strength_gives_it_to_every_rough_sample() {
        let grid = Grid::<Dim2>::new(DVec2::ZERO, 1.0, [4, 4, 0]);
        // No table: the scene's one material is Tresca clay of c_u = 10 kPa.
        let s = SoilStrength {
            uniform: Some((10.0e3, 0.0)),
            ..SoilStrength::default()
        };
        let nodes = || [(grid.node_id([3, 3, 0]), 1.0)].into_iter();
        assert_eq!(s.caps(InterfaceLaw::Soil, &grid, nodes()), (0.0, 10.0e3));
        // A Coulomb part keeps its own caps.
        let own = InterfaceLaw::Coulomb {
            friction: 0.5,
            adhesion: 2.0e3,
        };
        assert_eq!(s.caps(own, &grid, nodes()), (0.5, 2.0e3));
    }
}
