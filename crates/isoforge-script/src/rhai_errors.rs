//! Turning rhai's errors into [`ScriptError`]s located at `path:line:column` of the text the
//! user wrote, with the call chain for errors raised inside script functions.

use std::path::Path;

use rhai::{EvalAltResult, ParseError, Position};

use crate::error::{CallSite, Location, RuntimeCause, ScriptError};
use crate::notation::Rewritten;

/// Where errors point: the file, and the map from the compiled text's columns back to
/// the text the user wrote.
#[derive(Clone, Copy)]
pub struct Locator<'a> {
    /// The script's path, as given.
    pub path: &'a Path,
    /// The notation pass's column map.
    pub map: &'a Rewritten,
}

fn location(at: Locator, pos: Position) -> Location {
    let line = pos.line();
    Location {
        path: at.path.to_path_buf(),
        line,
        column: line
            .zip(pos.position())
            .map(|(l, c)| at.map.original_column(l, c)),
    }
}

/// A syntax error.
pub fn parse_error(at: Locator, err: &ParseError) -> ScriptError {
    ScriptError::Syntax {
        at: location(at, err.position()),
        message: err.err_type().to_string(),
    }
}

/// A runtime error, located at the innermost position (inside the function that failed),
/// with the calls that led there.
pub fn eval_error(at: Locator, err: &EvalAltResult) -> ScriptError {
    let mut calls = Vec::new();
    let mut inner = err;
    while let EvalAltResult::ErrorInFunctionCall(name, _, next, pos) = inner {
        calls.push(CallSite {
            function: (!name.starts_with("anon$")).then(|| name.to_string()),
            at: location(at, *pos),
        });
        inner = next;
    }
    calls.reverse();
    let pos = inner.position();
    let mut cause = describe(inner);
    if let RuntimeCause::TooDeep { function, .. } = &mut cause {
        *function = word_at(&at.map.source, pos);
    }
    ScriptError::Runtime {
        at: location(at, pos),
        cause: Box::new(cause),
        calls,
    }
}

/// The identifier at a 1-based line and column of `source`, if one starts there.
fn word_at(source: &str, pos: Position) -> Option<String> {
    let line = source.lines().nth(pos.line()?.checked_sub(1)?)?;
    let word: String = line
        .chars()
        .skip(pos.position()?.checked_sub(1)?)
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (!word.is_empty()).then_some(word)
}

/// What stopped the script, with advice for the limits a model script runs into.
fn describe(err: &EvalAltResult) -> RuntimeCause {
    match err {
        EvalAltResult::ErrorTooManyOperations(_) => RuntimeCause::TooManyOperations {
            limit: crate::engine::MAX_OPERATIONS,
        },
        EvalAltResult::ErrorStackOverflow(_) => RuntimeCause::TooDeep {
            limit: crate::engine::MAX_CALL_LEVELS,
            function: None,
        },
        EvalAltResult::ErrorFunctionNotFound(sig, _) => {
            // The notation pass turned `^` into `**`; name the operator the user wrote.
            let signature = match sig.strip_prefix("** (") {
                Some(rest) => format!("^ ({rest}"),
                None => sig.clone(),
            };
            let name = signature.split(" (").next().unwrap_or(&signature);
            RuntimeCause::UnknownFunction {
                suggestion: suggestion(name),
                signature,
            }
        }
        EvalAltResult::ErrorRuntime(value, _) => {
            // The library raises typed causes (see `args::fail_with`); `throw` raises text.
            if let Some(cause) = value.clone().try_cast::<RuntimeCause>() {
                return cause;
            }
            match value.clone().into_immutable_string() {
                Ok(s) => RuntimeCause::Failed(s.to_string()),
                Err(_) => RuntimeCause::Failed(format!("{value}")),
            }
        }
        EvalAltResult::ErrorTerminated(token, _) => token
            .clone()
            .try_cast::<RuntimeCause>()
            .unwrap_or_else(|| RuntimeCause::Failed("the script was stopped".into())),
        EvalAltResult::ErrorDataTooLarge(what, _) => {
            let (what, limit) = if what.starts_with("Length of string") {
                ("a string", format!("{} bytes", crate::engine::MAX_STRING))
            } else if what.starts_with("Size of object map") {
                (
                    "an object map",
                    format!("{} entries", crate::engine::MAX_MAP),
                )
            } else {
                ("an array", format!("{} elements", crate::engine::MAX_ARRAY))
            };
            RuntimeCause::DataTooLarge {
                what: what.into(),
                limit,
            }
        }
        EvalAltResult::ErrorMismatchDataType(want, got, _) => RuntimeCause::WrongType {
            expected: want.clone(),
            found: got.clone(),
        },
        other => {
            // rhai's own message ends with " (line L, position C)": we lead with that.
            let text = other.to_string();
            let suffix = format!(" ({})", other.position());
            RuntimeCause::Failed(text.strip_suffix(&suffix).unwrap_or(&text).to_string())
        }
    }
}

/// The library's names, for "did you mean" hints.
const KNOWN: [&str; 61] = [
    "Sphere",
    "Cube",
    "Prism",
    "Torus",
    "Cyl",
    "Cyyl",
    "Cone",
    "Ellip",
    "Para",
    "Close",
    "HSpace",
    "Tetrahedral",
    "Sinus",
    "Bug",
    "Drope",
    "Heart",
    "TransX",
    "TransY",
    "TransZ",
    "ScaleX",
    "ScaleY",
    "ScaleZ",
    "ScaleXYZ",
    "ReflectXY",
    "ReflectZX",
    "ReflectYZ",
    "RotateRX",
    "RotateRY",
    "RotateRZ",
    "RotateX",
    "RotateY",
    "RotateZ",
    "Union",
    "Intersect",
    "Subtract",
    "Morph",
    "Blend",
    "Combine",
    "Max",
    "Min",
    "curve_fol_sphere",
    "curve_fol_cyl",
    "curve_fol_cyyl",
    "curve_fol_box",
    "sin",
    "cos",
    "tan",
    "asin",
    "acos",
    "atan",
    "atan2",
    "exp",
    "ln",
    "sqrt",
    "abs",
    "min",
    "max",
    "square",
    "floor",
    "pow",
    "DegToRad",
];

/// A library name close to `name` (a typo or wrong case), unless `name` is itself one.
fn suggestion(name: &str) -> Option<&'static str> {
    if KNOWN.contains(&name) {
        return None;
    }
    let lower = name.to_lowercase();
    KNOWN
        .iter()
        .map(|k| (edit_distance(&lower, &k.to_lowercase()), *k))
        .filter(|(d, k)| *d <= 2.min(k.len() / 3).max(usize::from(lower.len() > 2)))
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// Levenshtein distance.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_near_names() {
        assert_eq!(suggestion("Sphre"), Some("Sphere"));
        assert_eq!(suggestion("sphere"), Some("Sphere"));
        assert_eq!(suggestion("rotatey"), Some("RotateY"));
        assert_eq!(suggestion("Sphere"), None);
        assert_eq!(suggestion("frobnicate"), None);
        assert_eq!(suggestion("q"), None);
    }
}
