//! The pore water as a cell field: for the points of an undrained material, one rate of
//! volume change and one excess pore pressure a background cell.
//!
//! An undrained point's water takes each step's volume change as pressure,
//! δu_p = −K_f tr(δε_p) (`materials/modified_cam_clay.rs`), K_f = K_w/n being far stiffer
//! than the skeleton. Left to each point, that is one nearly incompressible constraint a
//! point: four a cell in 2D on two velocity degrees of freedom a node, and the grid answers
//! with pore pressures that alternate from point to point (a layered mode the nodal forces
//! do not see) while their mean holds the load. Two systems make it the Q1/P0 count of one
//! constraint a cell (Hughes 1980, selective reduced integration of the penalty term; the
//! mean dilatation of Nagtegaal, Parks & Rice 1974, CMAME 4):
//!
//! * [`UndrainedStrain`], before the stress update: the undrained points of a cell take the
//!   cell's volume-weighted mean rate of volume change, their deviatoric rate and spin their
//!   own,
//!
//!   θ_c = Σ_{p∈c} V_p tr L_p / Σ_{p∈c} V_p,   L_p ← L_p + (θ_c − tr L_p) I / n
//!
//!   (n = `Dim::STRAIN_AXES`, the hoop rate included when axisymmetric), so that the water
//!   and the skeleton of a cell change their volume alike;
//! * [`PorePressureField`], after it: the undrained points of a cell take the cell's
//!   volume-weighted mean pressure,
//!
//!   ū_c = Σ_{p∈c} V_p u_p / Σ_{p∈c} V_p,   σ_p ← σ_p + (u_p − ū_c) I,   u_p ← ū_c,
//!
//!   their effective stress σ′_p = σ_p + u_p I untouched (σ total, tension positive; u
//!   compression positive).
//!
//! With u one value a cell before the step, the step adds to it K_f times the cell's mean
//! volume change. The pressure's power in the nodal forces, Σ_p V_p ū_c tr D_p =
//! ū_c V_c θ_c, is the power the update stores: the mean makes or loses no energy. A point
//! that flows into another cell brings its pressure into that cell's mean, which smooths the
//! field by as much as the soil moves past the cells.
//!
//! Both are needed. With the pressure's mean alone, each point's skeleton straining at its
//! own rate, a point's volume drifted from its neighbours' in a cell, where neither the mean
//! pressure nor the nodal forces resist it: beside a piezocone's apex the clay lost a
//! quarter of its volume under a suction, and a heavily overconsolidated clay was squeezed
//! to no voids left. With the shared rate alone, each point keeping its own pressure
//! (K_f times its own volume change), the points that cross different cells at different
//! times gather different volume changes: round a cylindrical cavity the points a cell or
//! two off the wall held −174 to +356 kPa where the closed form gives 139–141 kPa
//! (docs/tried-and-dropped.md). Keeping each point's own accumulated
//! pressure apart and giving the stress its cell's mean of those was dropped too (the own
//! pressures drift apart in the modes the mean does not see), and so was a nodal
//! projection of the pressure.
//!
//! The points that carry a traction (a `PointLoad` column) keep their own rate and
//! pressure: they pass their load to the grid as point forces, not through their stress,
//! and in a cell with them the mean would let the loaded points expand to zero effective
//! stress while the ones under them compress (an undrained oedometer loaded at its top
//! settled 7 times the element test's; docs/verification.md).
//!
//! The points are grouped by the cell that holds them when each system runs (after the
//! points moved in USL and MUSL, before in USF), as the cell means against locking do.
//! Points of other materials take no part. Over MPI ranks the cells of the shared node
//! layers are summed across the ranks first, so every rank holds the whole mean.

use crate::components::*;
use crate::context::Context;
use crate::dim::Dim;
use crate::error::StepError;
use crate::grid::Grid;
use crate::infra::columns::{col, col_mut};
use crate::materials::{visit_states, MaterialState, StateVisitor};
use crate::parallel::{SlabCache, CHUNK};
use crate::schedule::System;
use crate::shape::Shape;
use crate::systems::node_pairs::{set_volumetric_rates_where, NodePairs};
use crate::systems::shared::averaged_points;
use crate::tensor::{StoredSym, Sym3};
use hecs::Archetype;
use rayon::prelude::*;
use std::marker::PhantomData;

/// The undrained points' excess pore pressure as a cell field (see the module's text).
#[derive(Debug)]
pub struct PorePressureField<D: Dim, S> {
    /// Per cell, at its lowest node: Σ V u, Σ V; then ū_c in the first entry.
    sums: NodePairs,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for PorePressureField<D, S> {
    fn default() -> Self {
        PorePressureField {
            sums: NodePairs::default(),
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for PorePressureField<D, S> {
    fn name(&self) -> &str {
        "pore_pressure_field"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // A reset step neither strains nor moves the points: the means stand.
        if ctx.motion_dt().is_none() {
            return Ok(());
        }
        let water: Vec<bool> = ctx.materials.iter().map(|m| m.holds_water()).collect();
        for arch in averaged_points::<D>(&ctx.world) {
            let mut gather = Gather::<D, S> {
                arch,
                grid: &ctx.grid,
                slabs: &mut ctx.slabs,
                sums: &mut self.sums,
                water: &water,
                _marker: PhantomData,
            };
            visit_states(&mut gather);
        }
        let grid = &ctx.grid;
        self.sums.means_over_ranks(grid, &ctx.comm, &ctx.decomposition);
        for arch in averaged_points::<D>(&ctx.world) {
            let mut spread = Spread::<D> {
                arch,
                grid,
                sums: &self.sums,
                water: &water,
            };
            visit_states(&mut spread);
        }
        self.sums.clear(grid);
        Ok(())
    }
}

/// Adds one archetype's undrained points to their cells' sums, if its state column holds
/// water.
struct Gather<'a, D: Dim, S> {
    arch: &'a Archetype,
    grid: &'a Grid<D>,
    slabs: &'a mut SlabCache,
    sums: &'a mut NodePairs,
    /// Per material id: whether it holds undrained water.
    water: &'a [bool],
    _marker: PhantomData<fn() -> S>,
}

impl<D: Dim, S: Shape> StateVisitor for Gather<'_, D, S> {
    fn visit<T: MaterialState>(&mut self) {
        if std::mem::size_of::<T>() == 0 {
            return;
        }
        let Some(states) = self.arch.get::<&T>() else {
            return;
        };
        let (xg, vg, mg) = (
            col::<Position<D::Vec>>(self.arch),
            col::<Volume>(self.arch),
            col::<MaterialId>(self.arch),
        );
        let (vol, mat, water): (&[Volume], &[MaterialId], &[bool]) = (&vg, &mg, self.water);
        let states: &[T] = &states;
        self.sums
            .scatter_cells_where::<D, S>(self.slabs, self.grid, &xg, |p| {
                water[mat[p].0 as usize].then(|| [vol[p].0 * states[p].excess_pore_pressure(), vol[p].0])
            });
    }
}

/// Gives one archetype's undrained points their cell's mean, if its state column holds
/// water.
struct Spread<'a, D: Dim> {
    arch: &'a Archetype,
    grid: &'a Grid<D>,
    sums: &'a NodePairs,
    water: &'a [bool],
}

impl<D: Dim> StateVisitor for Spread<'_, D> {
    fn visit<T: MaterialState>(&mut self) {
        if std::mem::size_of::<T>() == 0 {
            return;
        }
        let Some(mut states) = self.arch.get::<&mut T>() else {
            return;
        };
        let (grid, cells, water) = (self.grid, self.sums.pairs(), self.water);
        let (xg, mg) = (col::<Position<D::Vec>>(self.arch), col::<MaterialId>(self.arch));
        let (x, mat): (&[Position<D::Vec>], &[MaterialId]) = (&xg, &mg);
        let mut sg = col_mut::<Stress<D::Stress>>(self.arch);
        sg.par_chunks_mut(CHUNK)
            .zip(states.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (s, st))| {
                for (k, (sp, state)) in s.iter_mut().zip(st.iter_mut()).enumerate() {
                    let p = c * CHUNK + k;
                    if !water[mat[p].0 as usize] {
                        continue;
                    }
                    let u = cells[grid.cell_key(x[p].0)][0];
                    let shift = state.excess_pore_pressure() - u;
                    let t = sp.0.to_sym3() + Sym3::IDENTITY * shift;
                    sp.0 = D::Stress::from_sym3(&t);
                    state.set_excess_pore_pressure(u);
                }
            });
    }
}

/// The undrained points' rate of volume change as a cell field (see the module's text).
#[derive(Debug)]
pub struct UndrainedStrain<D: Dim, S> {
    /// Per cell, at its lowest node: Σ V tr L, Σ V; then θ_c in the first entry.
    sums: NodePairs,
    _marker: PhantomData<fn() -> (D, S)>,
}

impl<D: Dim, S> Default for UndrainedStrain<D, S> {
    fn default() -> Self {
        UndrainedStrain {
            sums: NodePairs::default(),
            _marker: PhantomData,
        }
    }
}

impl<D: Dim, S: Shape> System<D> for UndrainedStrain<D, S> {
    fn name(&self) -> &str {
        "undrained_strain"
    }

    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        // A reset step neither strains nor moves the points.
        if ctx.motion_dt().is_none() {
            return Ok(());
        }
        let water: Vec<bool> = ctx.materials.iter().map(|m| m.holds_water()).collect();
        let grid = &ctx.grid;
        for arch in averaged_points::<D>(&ctx.world) {
            let (xg, vg, lg, mg) = (
                col::<Position<D::Vec>>(arch),
                col::<Volume>(arch),
                col::<VelocityGradient<D::Mat>>(arch),
                col::<MaterialId>(arch),
            );
            let (vol, mat): (&[Volume], &[MaterialId]) = (&vg, &mg);
            let l: &[VelocityGradient<D::Mat>] = &lg;
            let water = &water;
            self.sums
                .scatter_cells_where::<D, S>(&mut ctx.slabs, grid, &xg, |p| {
                    water[mat[p].0 as usize].then(|| [vol[p].0 * D::volumetric_rate(&l[p].0), vol[p].0])
                });
        }
        self.sums.means_over_ranks(grid, &ctx.comm, &ctx.decomposition);
        let sums = &self.sums;
        for arch in averaged_points::<D>(&ctx.world) {
            let mg = col::<MaterialId>(arch);
            let mat: &[MaterialId] = &mg;
            set_volumetric_rates_where::<D>(arch, |p, x| {
                water[mat[p].0 as usize].then(|| sums.of_cell(grid, x)[0])
            });
        }
        self.sums.clear(grid);
        Ok(())
    }
}
