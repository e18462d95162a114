//! One error type for every scene file, and the context that turns a byte span into file:line:col.

use crate::toml_scene::schema::{ColorDef, S, V3};
use glam::DVec3;
use lt_core::math::{Color, Vec3};
use std::ops::Range;
use std::path::PathBuf;

/// One clear message naming the file, the place (line and column when known) and the problem.
#[derive(Debug, Clone)]
pub struct SceneError {
    pub file: String,
    pub line: Option<usize>,
    pub column: Option<usize>,
    pub message: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.line, self.column) {
            (Some(l), Some(c)) => write!(f, "{}:{}:{}: {}", self.file, l, c, self.message),
            (Some(l), None) => write!(f, "{}:{}: {}", self.file, l, self.message),
            _ => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// What error messages need: the file's name and text (for line numbers) and its directory.
pub(crate) struct Ctx<'a> {
    pub file: String,
    pub text: &'a str,
    pub base_dir: PathBuf,
}

impl Ctx<'_> {
    /// An error at a byte span of the file (reported as 1-based line and column of its start).
    pub fn at(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        let start = span.start.min(self.text.len());
        let before = self.text.get(..start).unwrap_or(self.text);
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
        SceneError {
            file: self.file.clone(),
            line: Some(line),
            column: Some(column),
            message: message.into(),
        }
    }

    /// The bytes of the mesh file `file` names (relative to the scene file), with its path; a
    /// missing or unreadable file is an error at the scene's `file` key.
    pub fn read_mesh(&self, file: &S<String>) -> Result<(PathBuf, Vec<u8>), SceneError> {
        let path = self.base_dir.join(file.get_ref());
        match std::fs::read(&path) {
            Ok(b) => Ok((path, b)),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(self.at(
                file.span(),
                format!(
                    "mesh file `{}` not found (looked for {})",
                    file.get_ref(),
                    path.display()
                ),
            )),
            Err(e) => Err(self.at(
                file.span(),
                format!("cannot read mesh file {}: {e}", path.display()),
            )),
        }
    }

    /// An error about the scene as a whole.
    pub fn whole(&self, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.clone(),
            line: None,
            column: None,
            message: message.into(),
        }
    }

    /// A finite number (also after rounding to f32).
    pub fn num(&self, v: &S<f64>, key: &str) -> Result<f32, SceneError> {
        let x = *v.get_ref();
        if !(x as f32).is_finite() {
            return Err(self.at(
                v.span(),
                format!("`{key}` must be a finite number, got {x}"),
            ));
        }
        Ok(x as f32)
    }

    /// A finite number > 0.
    pub fn positive(&self, v: &S<f64>, key: &str) -> Result<f32, SceneError> {
        let x = self.num(v, key)?;
        if !(x > 0.0) {
            return Err(self.at(
                v.span(),
                format!("`{key}` must be positive, got {}", v.get_ref()),
            ));
        }
        Ok(x)
    }

    /// A point or direction with finite coordinates.
    pub fn vec3(&self, v: &S<V3>, key: &str) -> Result<Vec3, SceneError> {
        let a = v.get_ref().map(|x| x as f32);
        if a.iter().any(|x| !x.is_finite()) {
            return Err(self.at(
                v.span(),
                format!(
                    "`{key}` must have finite coordinates, got {:?}",
                    v.get_ref()
                ),
            ));
        }
        Ok(Vec3::from_array(a))
    }

    /// A world position, kept in f64 until `world.rs` rounds it once; finite and within range.
    pub fn dvec3(&self, v: &S<V3>, key: &str) -> Result<DVec3, SceneError> {
        let p = DVec3::from_array(*v.get_ref());
        if !crate::world::in_range(p) {
            return Err(self.at(
                v.span(),
                crate::world::out_of_range_message(&format!("`{key}`"), p),
            ));
        }
        Ok(p)
    }

    /// A finite, non-negative colour; with `at_most_one`, a reflectance that conserves energy.
    pub fn color(
        &self,
        v: &S<ColorDef>,
        key: &str,
        at_most_one: bool,
    ) -> Result<Color, SceneError> {
        let c = v.get_ref().0;
        let f = c.map(|x| x as f32);
        if f.iter().any(|x| !x.is_finite()) {
            return Err(self.at(v.span(), format!("`{key}` must be finite, got {c:?}")));
        }
        if f.iter().any(|&x| x < 0.0) {
            return Err(self.at(v.span(), format!("`{key}` must not be negative, got {c:?}")));
        }
        if at_most_one && f.iter().any(|&x| x > 1.0) {
            return Err(self.at(v.span(), format!("`{key}` must be at most 1 (a surface cannot reflect more than it receives), got {c:?}")));
        }
        Ok(Vec3::from_array(f))
    }

    /// A key the element must have; the error points at the element (`owner`).
    pub fn need<'v, T>(
        &self,
        v: &'v Option<S<T>>,
        key: &str,
        owner: &Range<usize>,
        what: &str,
    ) -> Result<&'v S<T>, SceneError> {
        v.as_ref().ok_or_else(|| {
            self.at(
                owner.clone(),
                format!("missing required key `{key}` for {what}"),
            )
        })
    }

    /// Rejects keys given to an element type they do not apply to (serde only knows the union).
    pub fn only(
        &self,
        given: &[(&str, Option<Range<usize>>)],
        allowed: &[&str],
        what: &str,
    ) -> Result<(), SceneError> {
        for (key, span) in given {
            if let (Some(span), false) = (span, allowed.contains(key)) {
                let takes = if allowed.is_empty() {
                    "no further keys".to_string()
                } else {
                    allowed
                        .iter()
                        .map(|k| format!("`{k}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                return Err(self.at(
                    span.clone(),
                    format!("key `{key}` does not apply to {what} (it takes {takes})"),
                ));
            }
        }
        Ok(())
    }
}
