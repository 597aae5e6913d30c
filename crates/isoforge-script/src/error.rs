//! What can go wrong loading a model, as types: each variant carries the facts (file, line,
//! column, parameter, limit), and its message says what and where. Messages name no
//! command-line flag; a program that takes parameters from its own flags adds that hint by
//! matching the variant.

use std::fmt;
use std::path::PathBuf;

/// A place in a script: `path:line:column`, as far as it is known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The script's path, as given.
    pub path: PathBuf,
    /// The 1-based line, when known.
    pub line: Option<usize>,
    /// The 1-based column in the text the user wrote, when known.
    pub column: Option<usize>,
}

impl Location {
    /// The whole file, no line.
    pub fn file(path: impl Into<PathBuf>) -> Location {
        Location {
            path: path.into(),
            line: None,
            column: None,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        Ok(())
    }
}

/// One call on the way to a runtime error: which function, called from where.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CallSite {
    /// The function's name; `None` for a closure.
    pub function: Option<String>,
    /// Where it was called.
    pub at: Location,
}

/// Why a running script stopped.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RuntimeCause {
    /// More operations than the sandbox allows (an endless loop?).
    #[error("the script ran more than {limit} operations (an endless loop?)")]
    TooManyOperations {
        /// The limit.
        limit: u64,
    },
    /// Calls nested deeper than the sandbox allows.
    #[error(
        "function calls nested more than {limit} deep (endless recursion?){}",
        function.as_ref().map(|f| format!(", starting with the call to `{f}`")).unwrap_or_default()
    )]
    TooDeep {
        /// The limit.
        limit: usize,
        /// The function whose call started the recursion, when it can be named.
        function: Option<String>,
    },
    /// A call to a function that does not exist with these argument types.
    #[error(
        "no function {signature}: {}",
        suggestion.map(|s| format!("did you mean {s}?"))
            .unwrap_or_else(|| "unknown name, or wrong number or types of arguments".into())
    )]
    UnknownFunction {
        /// The call as written, `name (types)`.
        signature: String,
        /// A library name close to it (a typo or wrong case).
        suggestion: Option<&'static str>,
    },
    /// A value of the wrong type.
    #[error("wrong type: expected {expected}, got {found}")]
    WrongType {
        /// What was expected.
        expected: String,
        /// What was given.
        found: String,
    },
    /// A parameter was given a value outside the range the script declares for it.
    #[error("parameter \"{name}\" = {value} is outside its declared range [{min}, {max}]")]
    ParamOutOfRange {
        /// The parameter.
        name: String,
        /// The value given.
        value: f64,
        /// The declared minimum.
        min: f64,
        /// The declared maximum.
        max: f64,
    },
    /// A modern-library call was given an option (`#{key: ..}`) it does not take.
    #[error(
        "{function}: unknown option `{key}`{} ({function} takes: {})",
        suggestion.as_ref().map(|s| format!(", did you mean `{s}`?")).unwrap_or_default(),
        if known.is_empty() { "no options".to_string() } else { known.join(", ") }
    )]
    UnknownOption {
        /// The function called.
        function: String,
        /// The key given.
        key: String,
        /// The keys the function takes.
        known: Vec<String>,
        /// The known key nearest to the one given (a typo).
        suggestion: Option<String>,
    },
    /// A modern-library option has a value of the wrong type or out of its range.
    #[error("{function}: option `{key}` must be {expected}, not {found}")]
    OptionType {
        /// The function called.
        function: String,
        /// The key.
        key: String,
        /// What it must be ("a number", "[x, y, z]", "one of ..").
        expected: String,
        /// What was given.
        found: String,
    },
    /// Anything else: a library function refused its arguments, a `throw`, rhai's own errors.
    #[error("{0}")]
    Failed(String),
}

/// A model could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum ScriptError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not UTF-8 text.
    #[error("{}: not a text file (invalid UTF-8 at byte {byte})", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
        /// The offset of the first invalid byte.
        byte: usize,
    },
    /// The script holds no code.
    #[error("{}: the script is empty: it must end with a shape, such as Sphere(1)", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The script does not parse.
    #[error("{at}: syntax error: {message}")]
    Syntax {
        /// Where.
        at: Location,
        /// What rhai says is wrong.
        message: String,
    },
    /// The script stopped with an error while running.
    #[error("{at}: {cause}{}", calls_text(calls))]
    Runtime {
        /// Where, innermost (inside the function that failed).
        at: Location,
        /// What went wrong (boxed: it is the largest part, and errors travel in `Result`s).
        cause: Box<RuntimeCause>,
        /// The calls that led there, innermost first.
        calls: Vec<CallSite>,
    },
    /// The script's last expression is not a shape.
    #[error(
        "{at}: the model evaluated to {found}, not a shape{}: the script's last expression \
         must be the model, such as Sphere(1)",
        if found.starts_with("nothing") {
            " (does the last statement end with `;` or is it a `let`?)"
        } else {
            ""
        }
    )]
    NotAShape {
        /// The last line with code.
        at: Location,
        /// What it evaluated to ("a number (3)", "nothing", "an array").
        found: String,
    },
    /// Parameters were given that the script never declares (probably typos).
    #[error(
        "{}: the script declares no parameter {} (it declares: {})",
        path.display(),
        names(unknown),
        if declared.is_empty() { "none".to_string() } else { declared.join(", ") }
    )]
    UnknownParams {
        /// The file.
        path: PathBuf,
        /// The names given that the script does not declare.
        unknown: Vec<String>,
        /// The names it declares.
        declared: Vec<String>,
    },
    /// A `.vm` expression file takes no parameters.
    #[error("{}: parameter {name}: a .vm model has no parameters", path.display())]
    VmParams {
        /// The file.
        path: PathBuf,
        /// The first parameter given.
        name: String,
    },
    /// A `.vm` expression file does not parse.
    #[error("{}:{line}: {message}", path.display())]
    Vm {
        /// The file.
        path: PathBuf,
        /// The 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The interpreter could not run (no thread) or crashed: not the script's fault.
    #[error("{}: {what}", path.display())]
    Interpreter {
        /// The file.
        path: PathBuf,
        /// What happened.
        what: String,
    },
}

impl ScriptError {
    /// The runtime cause, if the script stopped while running.
    pub fn runtime_cause(&self) -> Option<&RuntimeCause> {
        match self {
            ScriptError::Runtime { cause, .. } => Some(cause),
            _ => None,
        }
    }
}

fn calls_text(calls: &[CallSite]) -> String {
    let mut out = String::new();
    for c in calls {
        let who = match &c.function {
            Some(name) => format!("function `{name}`"),
            None => "a closure".to_string(),
        };
        out.push_str(&format!("\n  in {who} called at {}", c.at));
    }
    out
}

fn names(list: &[String]) -> String {
    list.iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}
