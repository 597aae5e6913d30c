//! Script errors as `path:line:column: what`, with the call chain for errors raised inside
//! script functions.

use std::path::Path;

use rhai::{EvalAltResult, ParseError, Position};

use crate::ScriptError;
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

fn location(at: Locator, pos: Position) -> String {
    let path = at.path;
    match (pos.line(), pos.position()) {
        (Some(l), Some(c)) => format!("{}:{l}:{}", path.display(), at.map.original_column(l, c)),
        (Some(l), None) => format!("{}:{l}", path.display()),
        _ => path.display().to_string(),
    }
}

/// A syntax error.
pub fn parse_error(at: Locator, err: &ParseError) -> ScriptError {
    ScriptError(format!(
        "{}: syntax error: {}",
        location(at, err.position()),
        err.err_type()
    ))
}

/// A runtime error, located at the innermost position (inside the function that failed),
/// with the calls that led there.
pub fn eval_error(at: Locator, err: &EvalAltResult) -> ScriptError {
    let mut calls = Vec::new();
    let mut inner = err;
    while let EvalAltResult::ErrorInFunctionCall(name, _, next, pos) = inner {
        let who = if name.starts_with("anon$") {
            "a closure".to_string()
        } else {
            format!("function `{name}`")
        };
        calls.push(format!("in {who} called at {}", location(at, *pos)));
        inner = next;
    }
    let pos = inner.position();
    let mut what = describe(inner);
    if let EvalAltResult::ErrorStackOverflow(_) = inner
        && let Some(name) = word_at(&at.map.source, pos)
    {
        what = format!("{what}, starting with the call to `{name}`");
    }
    let mut msg = format!("{}: {what}", location(at, pos));
    for c in calls.iter().rev() {
        msg.push_str("\n  ");
        msg.push_str(c);
    }
    ScriptError(msg)
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

/// Rhai's message, with advice for the limits a model script runs into.
fn describe(err: &EvalAltResult) -> String {
    match err {
        EvalAltResult::ErrorTooManyOperations(_) => format!(
            "the script ran more than {} operations (an endless loop?)",
            crate::engine::MAX_OPERATIONS
        ),
        EvalAltResult::ErrorStackOverflow(_) => format!(
            "function calls nested more than {} deep (endless recursion?)",
            crate::engine::MAX_CALL_LEVELS
        ),
        EvalAltResult::ErrorFunctionNotFound(sig, _) => {
            // The notation pass turned `^` into `**`; name the operator the user wrote.
            let sig = match sig.strip_prefix("** (") {
                Some(rest) => format!("^ ({rest}"),
                None => sig.clone(),
            };
            let name = sig.split(" (").next().unwrap_or(&sig);
            match suggestion(name) {
                Some(known) => format!("no function {sig}: did you mean {known}?"),
                None => format!(
                    "no function {sig}: unknown name, or wrong number or types of arguments"
                ),
            }
        }
        EvalAltResult::ErrorRuntime(msg, _) => match msg.clone().into_immutable_string() {
            Ok(s) => s.to_string(),
            Err(_) => format!("{msg}"),
        },
        EvalAltResult::ErrorMismatchDataType(want, got, _) => {
            format!("wrong type: expected {want}, got {got}")
        }
        other => {
            // rhai's own message ends with " (line L, position C)": we lead with that.
            let text = other.to_string();
            let suffix = format!(" ({})", other.position());
            text.strip_suffix(&suffix).unwrap_or(&text).to_string()
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
