//! Model scripts for isoforge: a Rhai script builds a field graph once; the graph, not the
//! script, is evaluated per point.

use std::path::Path;

use isoforge_field::{Bounds, Shape};

/// A declared parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Its name.
    pub name: String,
    /// The script's default.
    pub default: f64,
    /// The value used (the default or the command line's).
    pub value: f64,
    /// The declared range, if any.
    pub range: Option<(f64, f64)>,
}

/// A loaded model.
#[derive(Clone, Debug)]
pub struct Model {
    /// The field.
    pub shape: Shape,
    /// The region the script declared with `bounds(..)`, if any.
    pub bounds: Option<Bounds>,
    /// Parameters the script declared with `param(..)`.
    pub params: Vec<Param>,
}

/// A script failed; the message names the file, line and column.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ScriptError(pub String);

/// Loads a model file (`.rhai` script, or a `.vm` expression file) with parameter overrides.
pub fn load_file(path: &Path, params: &[(String, f64)]) -> Result<Model, ScriptError> {
    let _ = (path, params);
    todo!("script helper")
}

/// Finds a region enclosing the model by interval pruning of a large box.
pub fn find_bounds(shape: &Shape) -> Result<Bounds, ScriptError> {
    let _ = shape;
    todo!("script helper")
}
