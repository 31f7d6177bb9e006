//! A scene as read from its file: the parsed [`Scene`] with its text, the overrides applied
//! to it, and the places in the text that messages point to (`file:line:col`).

use crate::error::{Refusal, SceneError};
use std::path::{Path, PathBuf};

use super::locate;
use super::spec::{ron_options, Scene};

/// A scene together with its source text, for messages that point into the file.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The parsed scene.
    pub scene: Scene,
    /// Where it came from.
    pub path: PathBuf,
    /// Its text (after overrides).
    pub text: String,
    /// Its text as written (before overrides).
    pub source: String,
    /// The overrides' edits of the file's text, in the order applied: messages map their
    /// positions back through them to the file as written.
    pub edits: Vec<locate::Edit>,
}

impl LoadedScene {
    /// CRC-32 of every STL mesh the scene's bodies read (vertices and triangles, in scene
    /// order); 0 for a scene without one. A checkpoint keeps it, since it keeps the scene's
    /// text but not its files.
    pub fn mesh_crc(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        for b in &self.scene.rigid_bodies {
            for p in &b.parts {
                if let crate::rigid::Geometry::Mesh { .. } = p.geometry {
                    p.geometry.mesh().fingerprint(&mut h);
                }
            }
        }
        h.finalize()
    }

    /// Reads and parses a scene file, applying `overrides` (`path.to.field=value`) first.
    pub fn from_file(path: &Path, overrides: &[String]) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_text(path, &text, overrides)
    }

    /// Parses scene text; `path` is used in messages.
    pub fn from_text(path: &Path, text: &str, overrides: &[String]) -> Result<Self, SceneError> {
        Self::edited(path, text, text.to_string(), Vec::new(), overrides)
    }

    /// This scene with more overrides applied to its text, as if they had followed its own
    /// on the command line: the text (which a checkpoint keeps) says what runs, and messages
    /// still point into the file as written.
    pub fn with_overrides(&self, overrides: &[String]) -> Result<Self, SceneError> {
        Self::edited(
            &self.path,
            &self.source,
            self.text.clone(),
            self.edits.clone(),
            overrides,
        )
    }

    /// Parses `text`, `original` (the file as written) edited by `edits`, after applying
    /// `overrides` to it.
    fn edited(
        path: &Path,
        original: &str,
        mut text: String,
        mut edits: Vec<locate::Edit>,
        overrides: &[String],
    ) -> Result<Self, SceneError> {
        for o in overrides {
            let (t, e) = locate::override_edit(&text, o)?;
            text = t;
            edits.push(e);
        }
        let scene: Scene = ron_options().from_str(&text).map_err(|e| {
            let message = e.code.to_string();
            let (line, column, field) = locate::parse_error_place(&text, &e);
            let at = locate::offset(&text, line, column);
            let (line, column, inside) = Self::place(original, &edits, at);
            // A parser often notices a bad value just before or after it: name the
            // override that set a field of that name.
            let leaf = |e: &&locate::Edit| {
                let last = e.path().rsplit('.').next().unwrap_or_default();
                field
                    .as_deref()
                    .is_some_and(|f| last.split('[').next() == Some(f))
            };
            let set_by = inside.or_else(|| edits.iter().rev().find(leaf));
            let note = set_by.map_or(String::new(), |e| format!("{} ", e.note().trim_start()));
            let field = field.map_or(String::new(), |f| format!("field `{f}`: "));
            SceneError::Syntax {
                path: path.to_path_buf(),
                line,
                column,
                field: format!("{field}{note}"),
                message,
            }
        })?;
        let mut loaded = LoadedScene {
            scene,
            path: path.to_path_buf(),
            text,
            source: original.to_string(),
            edits,
        };
        // The rigid bodies' STL meshes, beside the scene file.
        let dir = path.parent().unwrap_or(Path::new("."));
        for i in 0..loaded.scene.rigid_bodies.len() {
            if let Err(Refusal { field: f, rule }) = loaded.scene.rigid_bodies[i].read_meshes(dir) {
                return Err(loaded.invalid(&format!("rigid_bodies[{i}].{f}"), rule));
            }
        }
        Ok(loaded)
    }

    /// 1-based (line, column) in the file as written of byte offset `at` of the edited
    /// text, and the override whose value holds the offset, if one does.
    fn place<'a>(
        original: &str,
        edits: &'a [locate::Edit],
        at: usize,
    ) -> (usize, usize, Option<&'a locate::Edit>) {
        let (at, edit) = locate::original_offset(edits, at);
        let (line, column) = locate::line_column(original, at);
        (line, column, edit)
    }

    /// An error for the field at dotted `field` path (e.g. `materials.soil.density`).
    pub fn invalid(&self, field: &str, rule: impl Into<String>) -> SceneError {
        let (mut line, mut column, mut inside) = (0, 0, None);
        if let Some((l, c)) = locate::field_position(&self.text, field) {
            let at = locate::offset(&self.text, l, c);
            (line, column, inside) = Self::place(&self.source, &self.edits, at);
        }
        // A value replaced whole by an override: its name stands in the file, its value
        // does not.
        let replaced = |e: &&locate::Edit| {
            let path = e.path();
            field == path || field.starts_with(&format!("{path}.")) || field.starts_with(&format!("{path}["))
        };
        let set_by = inside.or_else(|| self.edits.iter().rev().find(replaced));
        let note = set_by.map_or(String::new(), locate::Edit::note);
        SceneError::Invalid {
            path: self.path.clone(),
            line,
            column,
            field: field.to_string(),
            note,
            rule: rule.into(),
        }
    }
}

/// A place (m) as a message gives it: `[x, y] m`, each to a tenth of a millimetre.
pub(super) fn place_text(x: &[f64]) -> String {
    let c: Vec<String> = x.iter().map(|c| format!("{c:.4}")).collect();
    format!("[{}] m", c.join(", "))
}
