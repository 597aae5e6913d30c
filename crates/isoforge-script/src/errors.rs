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
    let what = describe(inner);
    let mut msg = format!("{}: {what}", location(at, pos));
    for c in calls.iter().rev() {
        msg.push_str("\n  ");
        msg.push_str(c);
    }
    ScriptError(msg)
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
            format!("no function {sig}: unknown name, or wrong number or types of arguments")
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
