//! Convergence monitor: force ratio K_F (eq. 3), external work (eq. 6), energy ratio K_E
//! (eq. 4), and the stopping rule (paper step 7).

use crate::components::*;
use crate::context::Context;
use crate::dim::{Dim, Vector};
use crate::error::StepError;
use crate::infra::columns::{col, col_mut, nodes, points_with};
use crate::infra::traffic::Traffic;
use crate::parallel::grid_pass;
use crate::schedule::System;
use crate::state::{StaticCheck, StopReason};
use crate::systems::shared::{hold, Hold};

/// K_E above which a run is declared unstable (a sound run stays at or below 1).
pub const UNSTABLE_ENERGY_RATIO: f64 = 10.0;

/// The value of a ratio whose denominator is zero (no external force on a free degree of
/// freedom, no external work yet). It is not 0: it compares false with every tolerance,
/// so it never counts as met; the terminal and summary.json show it as `undefined`, the CSV
/// files as an empty cell (see [`is_defined`]).
pub const UNDEFINED: f64 = f64::NAN;

/// True when a ratio K_F or K_E has a value (its denominator was not zero).
pub fn is_defined(ratio: f64) -> bool {
    !ratio.is_nan()
}

/// A ratio as a CSV cell: in scientific notation with `digits` decimals, or empty where it
/// is undefined (pandas, R and spreadsheets read an empty cell as missing, where a word
/// would turn the whole column into text).
pub fn ratio_cell(ratio: f64, digits: usize) -> String {
    ratio_or(ratio, digits, "")
}

/// A ratio as text for people: in scientific notation with `digits` decimals, or
/// `undefined`.
pub fn ratio_text(ratio: f64, digits: usize) -> String {
    ratio_or(ratio, digits, "undefined")
}

/// A ratio in scientific notation with `digits` decimals, or `undefined` where it has none.
fn ratio_or(ratio: f64, digits: usize, undefined: &str) -> String {
    if is_defined(ratio) {
        format!("{ratio:.digits$e}")
    } else {
        undefined.into()
    }
}

/// Force-ratio norms over the free degrees of freedom of nodes that carry mass
/// ([`Grid::counts_in_balance`](crate::grid::Grid::counts_in_balance)).
///
/// Fixed components are left out (their reaction keeps K_F near 1 for ever), and so are
/// massless nodes (they carry no degree of freedom). A component driven by a prescribed
/// motion counts its load (the reaction) as external force and has no unbalanced force.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForceNorms {
    /// max|F_ext + F_int| and Σ|F_ext + F_int| (N).
    pub unbalanced: [f64; 2],
    /// max|F_ext| and Σ|F_ext| (N).
    pub external: [f64; 2],
}

impl ForceNorms {
    /// K_F = max|F_ext + F_int| / max|F_ext| and Σ|F_ext + F_int| / Σ|F_ext|, measured
    /// against `reference` (the last applied load's norms) when no external force acts:
    /// [`UNDEFINED`] when there is neither.
    pub fn ratios(&self, reference: Option<[f64; 2]>) -> [f64; 2] {
        let e = if self.external[0] > 0.0 {
            self.external
        } else {
            reference.unwrap_or([0.0; 2])
        };
        std::array::from_fn(|k| {
            if e[k] > 0.0 {
                self.unbalanced[k] / e[k]
            } else {
                UNDEFINED
            }
        })
    }
}

/// Computes the force norms from the node columns.
pub fn force_norms<D: Dim>(ctx: &Context<D>) -> ForceNorms {
    let min_mass = ctx.numerics.min_node_mass;
    let n = nodes(&ctx.world);
    let nm = col::<NodeMass>(n);
    let nf = col::<NodeForce<D::Vec>>(n);
    let ne = col::<NodeExternalForce<D::Vec>>(n);
    let fix = col::<NodeFixity>(n);
    // Plain slices: the column guards cannot be shared with the pool.
    let (nm, nf, ne, fix) = (&*nm, &*nf, &*ne, &*fix);
    let drives = &ctx.state.control.drives[..];
    let grid = &ctx.grid;
    // Over MPI each rank sums the nodes it owns; the ranks' parts are combined below.
    let owned = ctx.owned_node_ids();
    let owned = owned.as_ref();
    // Per group of node layers: max|F_unb|, max|F_ext|, Σ|F_unb|, Σ|F_ext|, combined in node
    // order below.
    let parts = grid_pass(grid, ctx.state.active_nodes, &(), |b, (), _| {
        let (mut max_u, mut max_e, mut sum_u, mut sum_e) = (0.0f64, 0.0f64, 0.0, 0.0);
        for i in b.rows(grid).flatten() {
            if !grid.counts_in_balance(i, nm[i].0, min_mass) || owned.is_some_and(|o| !o.contains(&i)) {
                continue;
            }
            for a in 0..D::N {
                // A driven component's external force is the motion's load (applied, and
                // balanced by construction); a fixed one's would be a support reaction.
                let driven = match hold(fix[i], a, drives) {
                    Hold::Free => false,
                    Hold::Fixed => continue,
                    Hold::Driven(_) => true,
                };
                let u = if driven { 0.0 } else { nf[i].0.get(a).abs() };
                let e = ne[i].0.get(a).abs();
                max_u = max_u.max(u);
                max_e = max_e.max(e);
                sum_u += u;
                sum_e += e;
            }
        }
        [max_u, max_e, sum_u, sum_e]
    });
    let [mut max_u, mut max_e, mut sum_u, mut sum_e] = parts.iter().fold([0.0f64; 4], |t, p| {
        [t[0].max(p[0]), t[1].max(p[1]), t[2] + p[2], t[3] + p[3]]
    });
    if ctx.comm.size() > 1 {
        let (mut largest, mut sums) = ([max_u, max_e], [sum_u, sum_e]);
        ctx.comm.max(&mut largest);
        ctx.comm.sum(&mut sums);
        [max_u, max_e, sum_u, sum_e] = [largest[0], largest[1], sums[0], sums[1]];
    }
    ForceNorms {
        unbalanced: [max_u, sum_u],
        external: [max_e, sum_e],
    }
}

/// Updates K_F, W_ext and K_E and sets `state.stop` when the run should end.
///
/// The external-work increment is Σ_p f_p^ext·Δu_p. Both gravity (f_p = m_p g) and point
/// loads reach the grid through the shape weights, and every point moves by
/// Δt Σ_i w_ip v_i, so the sum equals Δt Σ_i F_i^ext·v_i over the nodes, which costs a
/// grid pass instead of a point pass. A reset step moves nothing and does no work.
///
/// With a [`StaticCheck`] the first step that meets both ratios opens a window; the run
/// stops at the end of the window only if the ratios are met again and no point moved
/// more than the allowed distance, otherwise a new window opens at the next step that
/// meets them.
///
/// It keeps nothing itself: the window lives in [`crate::state::SolverState`] and each
/// point's place at its opening in the point's [`WindowStart`], so that a checkpoint holds
/// them and over MPI ranks each rank keeps its own points' only.
#[derive(Debug, Default)]
pub struct Convergence;

impl Convergence {
    fn confirm_static<D: Dim>(&mut self, ctx: &mut Context<D>, met: bool, check: StaticCheck) -> bool {
        let now = ctx.state.clock.time;
        match ctx.state.static_window.start {
            Some(start) if now >= start + check.window * (1.0 - 1e-12) => {
                // Each rank's points against where they were (their own column, which went
                // with a point that changed rank), the largest over the ranks.
                let mut moved = [window_movement::<D>(&ctx.world)];
                ctx.comm.max(&mut moved);
                let moved = moved[0];
                ctx.state.static_window.movement = Some(moved);
                ctx.state.static_window.start = None;
                if met && moved <= check.max_displacement {
                    return true;
                }
                if met {
                    // Still balanced but moving: a creeping state. Watch a new window.
                    ctx.state.static_window.start = Some(now);
                    open_window::<D>(&ctx.world);
                }
                false
            }
            Some(_) => false,
            None => {
                if met {
                    ctx.state.static_window.start = Some(now);
                    open_window::<D>(&ctx.world);
                }
                false
            }
        }
    }
}

/// Marks where every point is as the static check's window opens ([`WindowStart`]).
fn open_window<D: Dim>(world: &hecs::World) {
    for arch in points_with::<WindowStart<D::Vec>>(world) {
        let x = col::<Position<D::Vec>>(arch);
        let mut start = col_mut::<WindowStart<D::Vec>>(arch);
        start.iter_mut().zip(x.iter()).for_each(|(s, x)| s.0 = x.0);
    }
}

/// The largest distance of this rank's points from where they were when the window opened
/// (m).
fn window_movement<D: Dim>(world: &hecs::World) -> f64 {
    let mut moved = 0.0f64;
    for arch in points_with::<WindowStart<D::Vec>>(world) {
        let (x, start) = (col::<Position<D::Vec>>(arch), col::<WindowStart<D::Vec>>(arch));
        for (x, s) in x.iter().zip(start.iter()) {
            let (a, b) = (D::vec_to3(s.0), D::vec_to3(x.0));
            moved = moved.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt());
        }
    }
    moved
}

impl<D: Dim> System<D> for Convergence {
    fn name(&self) -> &str {
        "convergence"
    }
    fn traffic(&self, ctx: &Context<D>) -> Option<Traffic> {
        // The force norms' pass (a static check's occasional look at the positions is not
        // counted).
        let n = ctx.state.active_nodes.len();
        Some(
            Traffic::NONE
                .read_nodes::<NodeMass>(n)
                .read_nodes::<NodeForce<D::Vec>>(n)
                .read_nodes::<NodeExternalForce<D::Vec>>(n)
                .read_nodes::<NodeFixity>(n),
        )
    }
    fn run(&mut self, ctx: &mut Context<D>) -> Result<(), StepError> {
        let norms = force_norms(ctx);
        // A load still ramping up, or a prescribed motion still moving, is not a static
        // state, however balanced this step is; nor is a body whose load the soil does not
        // yet balance.
        let time = ctx.state.clock.time;
        let loading = ctx
            .model
            .gravity
            .is_some_and(|g| g.step_factor(time, ctx.numerics.dt) < 1.0)
            || ctx.state.control.driving();
        // Nothing acts and nothing moves once the loading is done (soil that nothing has
        // touched, a body that moved away from it): K_F and K_E are 0, not 0/0.
        let quiet = !loading && norms.unbalanced[0] == 0.0 && ctx.state.energy.current() == 0.0;
        let mut ratios = norms.ratios(ctx.state.convergence.force_reference);
        if quiet {
            ratios = ratios.map(|r| if is_defined(r) { r } else { 0.0 });
        }
        let dw = if let Some(dt) = ctx.motion_dt() {
            let n = nodes(&ctx.world);
            let ne = col::<NodeExternalForce<D::Vec>>(n);
            let nv = col::<NodeVelocity<D::Vec>>(n);
            let (ne, nv) = (&*ne, &*nv);
            let grid = &ctx.grid;
            // Over MPI each node's power counts on the rank that owns it.
            let owned = ctx.owned_node_ids();
            let owned = owned.as_ref();
            let power: f64 = grid_pass(grid, ctx.state.active_nodes, &(), |b, (), _| {
                b.rows(grid)
                    .map(|r| match owned {
                        None => r.map(|i| ne[i].0.dot(nv[i].0)).sum::<f64>(),
                        Some(o) => r.filter(|i| o.contains(i)).map(|i| ne[i].0.dot(nv[i].0)).sum(),
                    })
                    .sum::<f64>()
            })
            .iter()
            .sum();
            let mut power = [power];
            ctx.comm.sum(&mut power);
            power[0] * dt
        } else {
            0.0
        };
        let s = &mut ctx.state;
        s.convergence.external_work += dw;
        [s.convergence.force_ratio_max, s.convergence.force_ratio_mean] = ratios;
        if norms.external[0] > 0.0 {
            s.convergence.force_reference = Some(norms.external);
        }
        // K_E = E_k / W_ext. Where the loads have done no work yet (a start in balance, such
        // as a geostatic state, whose W_ext is round-off about 0) the energy the start's
        // stress holds, E_0, is the scale the kinetic energy is judged against.
        s.convergence.energy_ratio = if s.convergence.external_work > 0.0 {
            s.energy.current() / s.convergence.external_work
        } else if quiet {
            0.0
        } else if ctx.numerics.initial_energy > 0.0 {
            s.energy.current() / ctx.numerics.initial_energy
        } else {
            UNDEFINED
        };
        // Energy balance: W_ext + E_0 = E_k + stored + dissipated (E_0 the strain energy of
        // an initial stress), so E_k ≤ W_ext + E_0 in a sound run. Well above that the
        // scheme is creating energy; stop before it turns into NaN.
        let available = s.convergence.external_work + ctx.numerics.initial_energy;
        if s.convergence.external_work > 0.0 && s.energy.current() > UNSTABLE_ENERGY_RATIO * available {
            return Err(StepError::Unstable {
                step: s.clock.step,
                kinetic_energy: s.energy.current(),
                external_work: s.convergence.external_work,
                ratio: s.convergence.energy_ratio,
            });
        }
        let tol = ctx.numerics.tolerance;
        // An undefined ratio (NaN) compares false: it never meets the tolerance.
        let met = !loading
            && s.convergence.force_ratio(ctx.numerics.force_norm) <= tol
            && s.control.unbalanced() <= tol
            && s.convergence.energy_ratio <= tol;
        let converged = match ctx.numerics.static_check {
            None => met,
            Some(check) => self.confirm_static(ctx, met, check),
        };
        if converged {
            state_faults(ctx)?;
            ctx.state.stop = Some(StopReason::Converged);
        } else if let Some(limit) = ctx.state.clock.limit(&ctx.numerics) {
            ctx.state.stop = Some(limit);
        }
        Ok(())
    }
}

/// A static state is an answer: one that holds a point whose material state has no
/// physical meaning (a clay with no voids left) stops the run with the point of the
/// smallest id over the ranks (every rank makes the same call, with the same figures).
fn state_faults<D: Dim>(ctx: &Context<D>) -> Result<(), StepError> {
    let mut first: Option<(u32, [f64; 3], String)> = None;
    for arch in points_with::<Position<D::Vec>>(&ctx.world) {
        for (r, why) in crate::materials::state_faults(arch) {
            let id = col::<PointId>(arch)[r].0;
            if first.as_ref().is_none_or(|f| id < f.0) {
                first = Some((id, D::vec_to3(col::<Position<D::Vec>>(arch)[r].0), why));
            }
        }
    }
    // The ranks' smallest faulty id (none: +∞); its rank says why and where.
    let mut least = [-first.as_ref().map_or(f64::INFINITY, |f| f64::from(f.0))];
    ctx.comm.max(&mut least);
    let id = -least[0];
    if id.is_infinite() {
        return Ok(());
    }
    let owned = first.filter(|f| f64::from(f.0) == id);
    let (rank, why) = (ctx.comm)
        .first_message(owned.as_ref().map(|f| f.2.as_str()))
        .expect("the rank that holds the point says why");
    let places = ctx.comm.gather_all(&owned.map_or([0.0; 3], |f| f.1));
    let position = [places[3 * rank], places[3 * rank + 1], places[3 * rank + 2]];
    Err(StepError::StateFault {
        step: ctx.state.clock.step,
        point: id as u32,
        position,
        why,
    })
}
