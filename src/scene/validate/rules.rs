//! What every part's check shares: the scene with its dimension ([`Rules`]), through which a
//! check names the field and the rule it breaks, and the tests of a number's sign.

use crate::error::SceneError;
use crate::scene::loaded::LoadedScene;

/// True for a finite number > 0 (NaN fails).
pub(super) fn positive(x: f64) -> bool {
    x > 0.0 && x.is_finite()
}

/// True for a finite number ≥ 0 (NaN fails).
pub(super) fn non_negative(x: f64) -> bool {
    x >= 0.0 && x.is_finite()
}

/// The scene and its dimension, for the checks of each part: each names a field and the
/// rule it breaks through [`Rules::bad`].
pub(super) struct Rules<'a> {
    /// The scene.
    pub(super) loaded: &'a LoadedScene,
    /// 2 or 3.
    pub(super) n: usize,
}

impl Rules<'_> {
    /// The error for `field`, breaking `rule`.
    pub(super) fn bad<T>(&self, field: &str, rule: String) -> Result<T, SceneError> {
        Err(self.loaded.invalid(field, rule))
    }

    /// A vector of one entry per axis.
    pub(super) fn len(&self, field: &str, v: usize) -> Result<(), SceneError> {
        let n = self.n;
        if v != n {
            return Err(self
                .loaded
                .invalid(field, format!("needs {n} entries (dimension {n}), found {v}")));
        }
        Ok(())
    }

    /// Every coordinate, force and acceleration is a finite number: a NaN or infinity in
    /// the input would reach the state and be written out.
    pub(super) fn finite(&self, field: &str, v: &[f64], unit: &str) -> Result<(), SceneError> {
        match v.iter().position(|x| !x.is_finite()) {
            Some(k) => Err(self.loaded.invalid(
                field,
                format!("entry {k} must be a finite number ({unit}), found {}", v[k]),
            )),
            None => Ok(()),
        }
    }
}
