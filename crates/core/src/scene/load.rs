//! Reading scenes from TOML. (Being written: see docs/scene-format.md.)

use super::Scene;
use std::path::Path;

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

pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError { file: path.display().to_string(), line: None, column: None, message: e.to_string() })?;
    load_scene_str(&text, path)
}

/// Parses scene text; `path` names the file in errors and anchors relative mesh paths.
pub fn load_scene_str(_text: &str, path: &Path) -> Result<Scene, SceneError> {
    Err(SceneError { file: path.display().to_string(), line: None, column: None, message: "scene loading is not written yet".into() })
}
