//! The `.vm` text format of the published benchmark models (one operation per line).

use crate::shape::Shape;

/// What went wrong reading a `.vm` file, with the 1-based line.
#[derive(Debug, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct VmError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub message: String,
}

/// Parses a `.vm` model into a shape.
pub fn parse_vm(text: &str) -> Result<Shape, VmError> {
    let _ = text;
    todo!("isoforge-field helper")
}
