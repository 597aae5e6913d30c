//! Model scripts for isoforge: a Rhai script builds a field graph once; the graph, not the
//! script, is evaluated per point.
//!
//! ```no_run
//! use std::path::Path;
//! // script → field graph (+ declared bounds and parameters) → region
//! let model = isoforge_script::load_file(Path::new("fixtures/classic/heart.rhai"), &[])?;
//! let region = match model.bounds {
//!     Some(b) => b,
//!     None => isoforge_field::find_bounds(&model.shape)?,
//! };
//! # let _ = region;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The scripting language and library are described in `docs/language.md`: `x y z`, mixed
//! number/Shape arithmetic with `^` as power and real division, the classic library,
//! `param(..)` and `bounds(..)`. Scripts run sandboxed: an operation limit, a call-depth
//! limit, no `import` and no `eval`, and output to stderr only.
//!
//! The path: source → `notation` (math precedence for `^`) → rhai compile and run with the
//! bindings of `ops`, `library` and `params` → the resulting `Shape`, or a [`ScriptError`]
//! located at `path:line:column` by `rhai_errors`. A model without `bounds(..)` gets its region
//! from `isoforge_field::find_bounds`: finding a box needs no script, so it lives there.

use std::path::Path;
use std::sync::{Arc, Mutex};

use isoforge_field::{Bounds, Shape};
use rhai::Dynamic;

mod args;
mod engine;
mod error;
mod facts;
mod files;
mod import;
mod library;
mod modern;
mod notation;
mod ops;
pub mod options;
mod params;
mod rhai_errors;
mod surfaces;
mod sweeps;
mod textures;
mod volumes;

pub use engine::{MAX_ARRAY, MAX_CALL_LEVELS, MAX_MAP, MAX_OPERATIONS, MAX_STRING, echo_prints};
pub use error::{CallSite, Location, RuntimeCause, ScriptError};
pub use import::MAX_IMPORT_BYTES;

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

/// The sandbox's budgets beyond rhai's own (operations, call depth, value sizes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScriptLimits {
    /// Wall-clock seconds a script may run.
    pub max_seconds: f64,
    /// Bytes the process may grow by while the script runs (measured where the system
    /// reports it: Linux).
    pub max_memory_bytes: u64,
}

/// 20 s: the slowest fixture script runs in well under a second; a script that needs
/// more is almost surely looping by mistake, and an interactive user should not wait.
pub const DEFAULT_MAX_SECONDS: f64 = 20.0;

/// 1 GiB: importing a million-triangle mesh with its hierarchy takes about 300 MiB.
pub const DEFAULT_MAX_MEMORY_BYTES: u64 = 1 << 30;

impl Default for ScriptLimits {
    fn default() -> Self {
        ScriptLimits {
            max_seconds: DEFAULT_MAX_SECONDS,
            max_memory_bytes: DEFAULT_MAX_MEMORY_BYTES,
        }
    }
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

/// Loads a model file (`.rhai` script, or a `.vm` expression file) with parameter overrides.
pub fn load_file(path: &Path, params: &[(String, f64)]) -> Result<Model, ScriptError> {
    load_file_with(path, params, &ScriptLimits::default())
}

/// [`load_file`] with chosen limits.
pub fn load_file_with(
    path: &Path,
    params: &[(String, f64)],
    limits: &ScriptLimits,
) -> Result<Model, ScriptError> {
    let bytes = read_capped(path)?;
    let text = String::from_utf8(bytes).map_err(|e| ScriptError::NotText {
        path: path.to_path_buf(),
        byte: e.utf8_error().valid_up_to(),
    })?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vm"))
    {
        load_vm(path, &text, params)
    } else {
        load_script_with(path, &text, params, limits)
    }
}

/// The largest model file read, in bytes. Scripts are a few kB and the largest `.vm` model
/// known (prospero, a page of text) about 0.5 MB; the cap only stops `/dev/zero` or a
/// mistaken multi-gigabyte file from filling memory before the parser can say no.
pub const MAX_MODEL_BYTES: u64 = 64 << 20;

/// Reads at most [`MAX_MODEL_BYTES`] (plus one, to tell a file that is too large).
fn read_capped(path: &Path) -> Result<Vec<u8>, ScriptError> {
    use std::io::Read as _;
    let read_error = |source| ScriptError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(read_error)?;
    let mut bytes = Vec::new();
    file.take(MAX_MODEL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_error)?;
    if bytes.len() as u64 > MAX_MODEL_BYTES {
        return Err(ScriptError::TooLarge {
            path: path.to_path_buf(),
            limit: MAX_MODEL_BYTES,
        });
    }
    Ok(bytes)
}

/// Loads a `.vm` expression file (one operation per line; see `isoforge_field::vm`).
pub fn load_vm(path: &Path, text: &str, params: &[(String, f64)]) -> Result<Model, ScriptError> {
    if let Some((name, _)) = params.first() {
        return Err(ScriptError::VmParams {
            path: path.to_path_buf(),
            name: name.clone(),
        });
    }
    let shape = isoforge_field::vm::parse_vm(text).map_err(|e| ScriptError::Vm {
        path: path.to_path_buf(),
        line: e.line,
        message: e.message,
    })?;
    Ok(Model {
        shape,
        bounds: None,
        params: vec![],
    })
}

/// Runs a script's source; `path` names it in messages. The script runs on its own thread
/// with a large stack, so deep (but limited) recursion in scripts cannot overflow ours.
pub fn load_script(
    path: &Path,
    source: &str,
    params: &[(String, f64)],
) -> Result<Model, ScriptError> {
    load_script_with(path, source, params, &ScriptLimits::default())
}

/// [`load_script`] with chosen limits.
pub fn load_script_with(
    path: &Path,
    source: &str,
    params: &[(String, f64)],
    limits: &ScriptLimits,
) -> Result<Model, ScriptError> {
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("isoforge-script".into())
            .stack_size(engine::SCRIPT_STACK)
            .spawn_scoped(scope, || run(path, source, params, limits))
            .map_err(|e| ScriptError::Interpreter {
                path: path.to_path_buf(),
                what: format!("cannot start the script thread: {e}"),
            })?;
        worker.join().unwrap_or_else(|_| {
            Err(ScriptError::Interpreter {
                path: path.to_path_buf(),
                what: "the script interpreter crashed (a bug in isoforge; please report it)".into(),
            })
        })
    })
}

fn run(
    path: &Path,
    source: &str,
    params: &[(String, f64)],
    limits: &ScriptLimits,
) -> Result<Model, ScriptError> {
    let shared = Arc::new(Mutex::new(params::Declared {
        overrides: params.to_vec(),
        ..Default::default()
    }));
    let facts = facts::SharedFacts::default();
    let imports = import::Imports::new(path);
    let engine = engine::build(
        &shared,
        &facts,
        &imports,
        limits,
        &files::ScriptFolder::of_script(path),
    );
    let Some(last_line) = last_code_line(source) else {
        return Err(ScriptError::Empty {
            path: path.to_path_buf(),
        });
    };
    let rewritten = notation::rewrite(source);
    let at = rhai_errors::Locator {
        path,
        map: &rewritten,
    };
    let ast = engine
        .compile(&rewritten.source)
        .map_err(|e| rhai_errors::parse_error(at, &e))?;
    let result: Dynamic = engine
        .eval_ast(&ast)
        .map_err(|e| rhai_errors::eval_error(at, &e))?;
    let declared = std::mem::take(&mut *shared.lock().unwrap_or_else(|e| e.into_inner()));
    let unknown = params::undeclared(&declared);
    if !unknown.is_empty() {
        return Err(ScriptError::UnknownParams {
            path: path.to_path_buf(),
            unknown,
            declared: declared.params.iter().map(|p| p.name.clone()).collect(),
        });
    }
    let shape = model_shape(path, last_line, result)?;
    Ok(Model {
        shape,
        bounds: declared.bounds,
        params: declared.params,
    })
}

/// The script's value as a Shape, or an error that says what it was instead.
fn model_shape(path: &Path, last_line: usize, result: Dynamic) -> Result<Shape, ScriptError> {
    if let Some(s) = result.clone().try_cast::<Shape>() {
        return Ok(s);
    }
    let found = if let Some(v) = args::as_number(&result) {
        format!("a number ({v})")
    } else {
        args::type_name(&result).to_string()
    };
    Err(ScriptError::NotAShape {
        at: Location {
            path: path.to_path_buf(),
            line: Some(last_line),
            column: None,
        },
        found,
    })
}

/// The 1-based number of the last line holding code (not blank, not only a `//` comment);
/// `None` for a script with no code at all.
fn last_code_line(source: &str) -> Option<usize> {
    let mut in_block = false;
    let mut last = None;
    for (i, line) in source.lines().enumerate() {
        let mut rest = line.trim();
        let mut code = false;
        while !rest.is_empty() {
            if in_block {
                match rest.find("*/") {
                    Some(end) => {
                        rest = rest[end + 2..].trim_start();
                        in_block = false;
                    }
                    None => rest = "",
                }
            } else if rest.starts_with("//") {
                rest = "";
            } else if let Some(after) = rest.strip_prefix("/*") {
                rest = after;
                in_block = true;
            } else {
                code = true;
                break;
            }
        }
        if code {
            last = Some(i + 1);
        }
    }
    last
}
