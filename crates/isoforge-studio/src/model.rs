//! Glue to `isoforge-script` and the region search: the editor's text and the sliders'
//! values to a field with its region, or a problem placed at a line and column.

use std::path::Path;

use isoforge_field::{Bounds, Shape};
use isoforge_script::{Param, RuntimeCause, ScriptError};
use serde::Serialize;

/// A model ready to mesh or slice.
pub struct Loaded {
    /// The field.
    pub shape: Shape,
    /// The region it is worked on.
    pub bounds: Bounds,
    /// The parameters it declares, with the values used.
    pub params: Vec<Param>,
}

/// Why the text is not a model, placed for the editor.
#[derive(Debug, Clone, Serialize)]
pub struct Problem {
    /// The message, as the command line would print it.
    pub message: String,
    /// The 1-based line, when known.
    pub line: Option<usize>,
    /// The 1-based column, when known.
    pub column: Option<usize>,
}

impl Problem {
    fn plain(message: String) -> Problem {
        Problem {
            message,
            line: None,
            column: None,
        }
    }
}

impl From<&ScriptError> for Problem {
    fn from(e: &ScriptError) -> Problem {
        let at = match e {
            ScriptError::Syntax { at, .. }
            | ScriptError::Runtime { at, .. }
            | ScriptError::NotAShape { at, .. } => Some((at.line, at.column)),
            ScriptError::Vm { line, .. } => Some((Some(*line), None)),
            _ => None,
        };
        let (line, column) = at.unwrap_or((None, None));
        Problem {
            message: e.to_string(),
            line,
            column,
        }
    }
}

/// Runs the script `text` (named `path` in messages) with the sliders' values.
///
/// Values for names the script no longer declares, or outside a range it now declares,
/// are dropped rather than refused: the page sends what the previous version declared, and
/// an edit to the script must not leave it stuck on an error about a slider.
pub fn load(path: &Path, text: &str, values: &[(String, f64)]) -> Result<Loaded, Problem> {
    let vm = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vm"));
    let run = |values: &[(String, f64)]| {
        if vm {
            isoforge_script::load_vm(path, text, &[])
        } else {
            isoforge_script::load_script(path, text, values)
        }
    };
    let mut values = values.to_vec();
    let model = loop {
        match run(&values) {
            Ok(m) => break m,
            Err(ScriptError::UnknownParams { unknown, .. }) if !values.is_empty() => {
                values.retain(|(n, _)| !unknown.contains(n));
            }
            Err(e) => match e.runtime_cause() {
                Some(RuntimeCause::ParamOutOfRange { name, .. })
                    if values.iter().any(|(n, _)| n == name) =>
                {
                    let name = name.clone();
                    values.retain(|(n, _)| *n != name);
                }
                _ => return Err(Problem::from(&e)),
            },
        }
    };
    let bounds = match model.bounds {
        Some(b) => b,
        None => isoforge_field::find_bounds(&model.shape).map_err(|e| {
            Problem::plain(format!(
                "{e}; give the script a region: bounds([x0, y0, z0], [x1, y1, z1])"
            ))
        })?,
    };
    isoforge_field::ensure_not_empty(&model.shape, &bounds)
        .map_err(|e| Problem::plain(e.to_string()))?;
    Ok(Loaded {
        shape: model.shape,
        bounds,
        params: model.params,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn syntax_error_is_placed() {
        let e = load(Path::new("m.rhai"), "let a = 1;\nlet b = ;\nSphere(1)", &[])
            .err()
            .unwrap();
        assert_eq!(e.line, Some(2), "{e:?}");
        assert!(e.column.is_some(), "{e:?}");
    }

    #[test]
    fn stale_slider_values_are_dropped() {
        let text = "bounds([-2,-2,-2],[2,2,2]);\nSphere(param(\"r\", 1, 0.5, 1.5))";
        let old = vec![("gone".to_string(), 3.0), ("r".to_string(), 9.0)];
        let m = load(Path::new("m.rhai"), text, &old).unwrap();
        assert_eq!(m.params.len(), 1);
        assert_eq!(m.params[0].value, 1.0);
        let m = load(Path::new("m.rhai"), text, &[("r".into(), 1.25)]).unwrap();
        assert_eq!(m.params[0].value, 1.25);
    }
}
