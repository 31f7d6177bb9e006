//! Prescribed motions and the analyses over runs (strength reduction). The motions' boxes
//! are checked against the grid nodes the bodies touch once set-up has placed the points
//! ([`check_motion_boxes`]).

use super::rules::*;
use crate::components::NodeFixity;
use crate::dim::Dim;
use crate::error::Refusal;
use crate::error::SceneError;
use crate::grid::Grid;
use crate::scene::loaded::LoadedScene;

/// The finest bisection of `kdmpm fos`, relative to the bracket's high end: about 24
/// halvings of a bracket [0.5, 2].
pub const MIN_FOS_TOLERANCE: f64 = 1e-7;

/// Motions, names, and the strength-reduction analysis.
pub(super) fn check_motions_and_analyses(r: &Rules) -> Result<(), SceneError> {
    let (loaded, s) = (r.loaded, &r.loaded.scene);
    if s.motions.len() > NodeFixity::MAX_DRIVES {
        return r.bad(
            "motions",
            format!(
                "at most {} motions, found {}",
                NodeFixity::MAX_DRIVES,
                s.motions.len()
            ),
        );
    }
    for (i, m) in s.motions.iter().enumerate() {
        m.check(s.dimension.axes())
            .map_err(|Refusal { field, rule }| loaded.invalid(&format!("motions[{i}].{field}"), rule))?;
    }
    unique_names(s).map_err(|Refusal { field, rule }| loaded.invalid(&field, rule))?;
    if let Some(spec) = &s.strength_reduction {
        let ok =
            matches!(spec.bracket[..], [lo, hi] if lo.is_finite() && hi.is_finite() && 0.0 < lo && lo < hi);
        if !ok {
            return r.bad(
                "strength_reduction.bracket",
                format!("needs two factors 0 < low < high, found {:?}", spec.bracket),
            );
        }
        let hi = spec.bracket[1];
        if !(spec.tolerance.is_finite() && spec.tolerance >= MIN_FOS_TOLERANCE * hi) {
            return r.bad(
                "strength_reduction.tolerance",
                format!(
                    "must be at least {MIN_FOS_TOLERANCE:e} of the bracket's high end ({:e}), found {:e}: \
                     each halving of the bracket is a whole run, and a factor finer than that is \
                     below what a trial resolves",
                    MIN_FOS_TOLERANCE * hi,
                    spec.tolerance
                ),
            );
        }
        if !(spec.failure_displacement.is_finite() && spec.failure_displacement > 0.0) {
            return r.bad(
                "strength_reduction.failure_displacement",
                "must be above 0 (m)".into(),
            );
        }
        if spec.check_every == 0 {
            return r.bad(
                "strength_reduction.check_every",
                "must be at least 1 (steps)".into(),
            );
        }
        if !s.output.displacements {
            return r.bad(
                "output.displacements",
                "strength reduction judges trials by displacement: keep them (true)".into(),
            );
        }
    }
    Ok(())
}

/// Every motion's box holds grid nodes that the body touches at the start, and no node is
/// in two boxes: a box of nodes the body never reaches pushes nothing (a curve of zero
/// forces), and a node two motions claim is driven by the later one only.
pub(crate) fn check_motion_boxes<D: Dim>(
    loaded: &LoadedScene,
    grid: &Grid<D>,
    touched: &[bool],
) -> Result<(), SceneError> {
    let motions = &loaded.scene.motions;
    if motions.is_empty() {
        return Ok(());
    }
    let mut owner: Vec<Option<usize>> = vec![None; grid.node_count()];
    for (k, m) in motions.iter().enumerate() {
        let (mut inside, mut loaded_nodes) = (0usize, 0usize);
        for (id, o) in owner.iter_mut().enumerate() {
            let x = D::vec_to3(grid.node_position(grid.node_ijk(id)));
            if !m.holds_node(x, D::N, grid.cell_size) {
                continue;
            }
            if let Some(j) = *o {
                return Err(loaded.invalid(
                    &format!("motions[{k}].min"),
                    format!(
                        "the box shares the node at {:?} with motions[{j}] (\"{}\"): a node has one \
                         motion; give the motions boxes apart",
                        &x[..D::N],
                        motions[j].name
                    ),
                ));
            }
            // On the axis of an axisymmetric scene r stays 0: a radial velocity there would
            // override the axis's roller and tear the soil off the axis.
            if D::AXISYMMETRIC && grid.node_ijk(id)[0] == 0 && m.vector()[0] != 0.0 {
                return Err(loaded.invalid(
                    &format!("motions[{k}].velocity"),
                    format!(
                        "{} m/s along r drives nodes on the axis (r = 0), which stay on it: give \
                         the motion no radial entry, or a box that starts off the axis",
                        m.vector()[0]
                    ),
                ));
            }
            *o = Some(k);
            inside += 1;
            loaded_nodes += usize::from(touched[id]);
        }
        if inside == 0 {
            return Err(loaded.invalid(
                &format!("motions[{k}].min"),
                format!(
                    "the box {:?}..{:?} holds no grid node (nodes lie every {} m from the grid's \
                     origin): the motion would drive nothing",
                    m.min, m.max, grid.cell_size
                ),
            ));
        }
        if loaded_nodes == 0 {
            return Err(loaded.invalid(
                &format!("motions[{k}].min"),
                format!(
                    "none of the box's {inside} nodes touches the body at the start: grid nodes \
                     do not move, so the motion would push nothing and report zero force; put the \
                     box on the body's surface"
                ),
            ));
        }
    }
    Ok(())
}

/// Names that label output (columns of `history.csv`, rows of `curve.csv` and
/// `stages.csv`) are unique within their list: two traced points called "top" would give
/// two columns of one name.
fn unique_names(s: &crate::scene::spec::Scene) -> Result<(), Refusal> {
    let lists: [(&str, Vec<&str>); 5] = [
        ("traced", s.traced.iter().map(|t| t.name.as_str()).collect()),
        (
            "point_loads",
            s.point_loads.iter().map(|t| t.name.as_str()).collect(),
        ),
        ("tractions", s.tractions.iter().map(|t| t.name.as_str()).collect()),
        ("motions", s.motions.iter().map(|t| t.name.as_str()).collect()),
        ("stages", s.stages.iter().map(|t| t.name.as_str()).collect()),
    ];
    for (field, names) in lists {
        for (i, name) in names.iter().enumerate() {
            if let Some(j) = names[..i].iter().position(|m| m == name) {
                return Err(Refusal::new(
                    format!("{field}[{i}].name"),
                    format!("\"{name}\" is also the name of {field}[{j}]: each needs its own name"),
                ));
            }
        }
    }
    Ok(())
}
