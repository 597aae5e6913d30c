//! What can be wrong with a printer profile: where the value came from ([`Origin`]) and what
//! is wrong with it ([`ProfileErrorKind`]). Messages name no command-line flag: a program
//! that takes overrides from its own flags names them by matching [`Origin::Override`].

use std::fmt;

use super::keys::{KeySpec, Range};
use super::settings::Technology;

/// Where a profile value came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// A profile file, and the 1-based line of the key when known.
    File {
        /// The file, as given.
        path: String,
        /// The line.
        line: Option<usize>,
    },
    /// A profile built into isoforge.
    Builtin {
        /// Its name.
        name: &'static str,
    },
    /// An override `KEY=VALUE`, as given.
    Override {
        /// The `KEY=VALUE` text.
        assignment: String,
    },
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Origin::File { path, line: None } => write!(f, "{path}"),
            Origin::File {
                path,
                line: Some(l),
            } => write!(f, "{path}:{l}"),
            Origin::Builtin { name } => write!(f, "built-in profile {name}"),
            Origin::Override { assignment } => write!(f, "override {assignment}"),
        }
    }
}

/// What is wrong with a profile value.
#[derive(Debug, thiserror::Error)]
pub enum ProfileErrorKind {
    /// The profile file cannot be read.
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    /// The file is not TOML.
    #[error("not a valid TOML profile: {0}")]
    Toml(String),
    /// An override that is not `KEY=VALUE`.
    #[error("expected KEY=VALUE")]
    OverrideSyntax,
    /// A key no profile has.
    #[error(
        "unknown key `{key}`{}",
        match suggestion {
            Some(s) => format!("; did you mean `{s}`?"),
            None => format!(" (known keys: {})", super::keys::names().join(", ")),
        }
    )]
    UnknownKey {
        /// The key as written.
        key: String,
        /// A known key close to it.
        suggestion: Option<&'static str>,
    },
    /// A key of the other technology (`pixel_size` in a filament profile).
    #[error("`{key}` is a setting for {key_technology} printer, and this is {technology} profile")]
    OtherTechnology {
        /// The key.
        key: String,
        /// The technology the key belongs to.
        key_technology: Technology,
        /// The profile's technology.
        technology: Technology,
    },
    /// A key the output needs is not in the profile.
    #[error("missing key `{}` ({}); add it to the profile", spec.key, spec.meaning)]
    Missing {
        /// The key.
        spec: &'static KeySpec,
    },
    /// A value of the wrong type or form (text for a number, an unknown pattern name).
    #[error("`{key}`: {message}")]
    Invalid {
        /// The key.
        key: String,
        /// What serde says is wrong.
        message: String,
    },
    /// A number outside the key's physical range.
    #[error(
        "`{}` = {}{} is out of range: it must be {}",
        spec.key, value, unit(spec.unit), spec_range_text(spec)
    )]
    OutOfRange {
        /// The key, its unit and its range.
        spec: &'static KeySpec,
        /// The value given.
        value: f64,
    },
    /// A value that does not fit another key's (a layer thicker than the nozzle).
    #[error("`{key}` = {value}{} {rule}", unit(unit_of(key)))]
    Conflict {
        /// The key.
        key: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks, naming the other key.
        rule: String,
    },
    /// A `{placeholder}` in a G-code template that isoforge does not fill.
    #[error(
        "`{key}`: unknown placeholder {{{placeholder}}} (known: {})",
        super::template::PLACEHOLDERS.map(|p| format!("{{{p}}}")).join(", ")
    )]
    UnknownPlaceholder {
        /// The template's key.
        key: &'static str,
        /// The name between the braces.
        placeholder: String,
    },
    /// A `{` in a G-code template that is never closed.
    #[error("`{key}`: a {{ at byte {byte} is never closed by }}")]
    UnclosedPlaceholder {
        /// The template's key.
        key: &'static str,
        /// The byte offset of the `{` in the template.
        byte: usize,
    },
    /// The profile is for the other kind of printer.
    #[error("this is {found} profile, and this output needs {wanted} printer profile")]
    WrongTechnology {
        /// What the output needs.
        wanted: Technology,
        /// What the profile is.
        found: Technology,
    },
}

impl ProfileErrorKind {
    /// The key the problem is about, if one.
    pub fn key(&self) -> Option<&str> {
        match self {
            ProfileErrorKind::UnknownKey { key, .. }
            | ProfileErrorKind::OtherTechnology { key, .. }
            | ProfileErrorKind::Invalid { key, .. } => Some(key),
            ProfileErrorKind::Missing { spec } | ProfileErrorKind::OutOfRange { spec, .. } => {
                Some(spec.key)
            }
            ProfileErrorKind::Conflict { key, .. }
            | ProfileErrorKind::UnknownPlaceholder { key, .. }
            | ProfileErrorKind::UnclosedPlaceholder { key, .. } => Some(key),
            _ => None,
        }
    }
}

/// A printer profile problem: where the value came from, and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[error("{}{kind}", origin.as_ref().map(|o| format!("{o}: ")).unwrap_or_default())]
pub struct ProfileError {
    /// Where the value came from; `None` for settings built in code.
    pub origin: Option<Origin>,
    /// What is wrong.
    pub kind: ProfileErrorKind,
}

impl ProfileError {
    /// An error with no origin (settings built in code).
    pub fn new(kind: ProfileErrorKind) -> ProfileError {
        ProfileError { origin: None, kind }
    }

    /// The same error, from `origin`.
    pub fn at(self, origin: Origin) -> ProfileError {
        ProfileError {
            origin: Some(origin),
            ..self
        }
    }
}

impl From<ProfileErrorKind> for ProfileError {
    fn from(kind: ProfileErrorKind) -> ProfileError {
        ProfileError::new(kind)
    }
}

/// " mm" after a value, or nothing for unitless keys.
fn unit(u: &str) -> String {
    match u {
        "" => String::new(),
        "°C" => " °C".into(),
        u => format!(" {u}"),
    }
}

fn unit_of(key: &str) -> &'static str {
    super::keys::spec(key).map_or("", |s| s.unit)
}

fn spec_range_text(spec: &KeySpec) -> String {
    spec.range
        .map_or_else(String::new, |r| range_text(&r, spec.unit))
}

/// "from 0 to 400 °C", "a whole number from 0 to 20".
pub(crate) fn range_text(r: &Range, u: &str) -> String {
    let whole = if r.whole { "a whole number " } else { "" };
    format!("{whole}from {} to {}{}", r.min, r.max, unit(u))
}
