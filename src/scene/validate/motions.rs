//! Prescribed motions and the analyses over runs (strength reduction).

use super::*;
use crate::components::NodeFixity;
use crate::error::SceneError;

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
        m.check(s.dimension as usize)
            .map_err(|(field, rule)| loaded.invalid(&format!("motions[{i}].{field}"), rule))?;
    }
    unique_names(s).map_err(|(field, rule)| loaded.invalid(&field, rule))?;
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
