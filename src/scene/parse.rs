//! Scene files (TOML) → `SceneDescription`, with file:line errors.
use super::SceneDescription;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{0}")]
    Other(String),
}

pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Other(format!("{}: {e}", path.display())))?;
    parse_str(&text, path)
}

pub fn parse_str(_text: &str, path: &Path) -> Result<SceneDescription, SceneError> {
    Err(SceneError::Other(format!("{}: scene parsing not written yet", path.display())))
}
