//! What a mesh reader reports: where in the file ([`Place`]) and what is wrong
//! ([`ParseErrorKind`]), so callers can match on the cause and messages say both.

use std::fmt;

/// Where in a mesh file a problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// The file as a whole (its size, its kind).
    File,
    /// A 1-based line of a text format.
    Line(usize),
    /// A byte offset in a binary format.
    Byte(u64),
    /// An entry of a package (3MF is a zip archive), and a 1-based line in it when known.
    Entry {
        /// The entry's name in the archive.
        name: String,
        /// The line in the entry.
        line: Option<usize>,
    },
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::File => Ok(()),
            Place::Line(l) => write!(f, "line {l}: "),
            Place::Byte(b) => write!(f, "byte {b}: "),
            Place::Entry { name, line: None } => write!(f, "{name}: "),
            Place::Entry {
                name,
                line: Some(l),
            } => write!(f, "{name} line {l}: "),
        }
    }
}

/// What is wrong with a mesh file.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParseErrorKind {
    /// The content is no mesh format isoforge reads.
    #[error("not a mesh file: expected STL (binary or ASCII), 3MF, OBJ or PLY")]
    UnknownFormat,
    /// Bytes that are not UTF-8 where text must be.
    #[error("not text (invalid UTF-8)")]
    NotText,
    /// A number that does not parse, or is not finite.
    #[error("{field} {token:?} is not a finite number")]
    BadNumber {
        /// What the number is ("coordinate", "vertex x", "triangle 2 coordinate").
        field: String,
        /// The text found (or the value, for binary formats).
        token: String,
    },
    /// A vertex index that names no vertex.
    #[error("{token:?} is not a vertex index (there are {vertices} vertices)")]
    BadIndex {
        /// The index as written.
        token: String,
        /// How many vertices there are to refer to.
        vertices: usize,
    },
    /// The file is shorter than its own header says.
    #[error(
        "truncated: the header promises {promised} ({expected} bytes) but the file has {actual} bytes"
    )]
    Truncated {
        /// What the header promises ("12 triangles").
        promised: String,
        /// The size the header implies.
        expected: u64,
        /// The size found.
        actual: u64,
    },
    /// More of something than a reader accepts (a guard against bombs and exhaustion).
    #[error("more than {limit} {what}")]
    TooLarge {
        /// What was counted ("vertices", "bytes of inflated model XML", "elements").
        what: &'static str,
        /// The limit.
        limit: u64,
    },
    /// A document type declaration: 3MF has none, and entity definitions in one are how
    /// entity-expansion bombs work, so it is refused, not expanded.
    #[error("a <!DOCTYPE> declaration (3MF has none; entity definitions are not expanded)")]
    Doctype,
    /// XML that is not well formed, or an entity that is not one of XML's own.
    #[error("XML: {0}")]
    Xml(String),
    /// A zip package that cannot be read.
    #[error("zip package: {0}")]
    Zip(String),
    /// Anything else about the format's structure; the message says what was expected.
    #[error("{0}")]
    Syntax(String),
}

/// A mesh file's content is not valid: where, and what.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{at}{kind}")]
pub struct ParseError {
    /// Where.
    pub at: Place,
    /// What.
    pub kind: ParseErrorKind,
}

impl ParseError {
    /// An error at a place.
    pub fn new(at: Place, kind: ParseErrorKind) -> ParseError {
        ParseError { at, kind }
    }

    /// An error about the whole file.
    pub fn file(kind: ParseErrorKind) -> ParseError {
        ParseError::new(Place::File, kind)
    }
}

/// A structural problem at a text line.
pub(crate) fn at_line(line: usize, what: impl fmt::Display) -> ParseError {
    ParseError::new(Place::Line(line), ParseErrorKind::Syntax(what.to_string()))
}

/// More vertices than a `u32` index can name.
pub(crate) fn too_many_vertices(at: Place) -> ParseError {
    ParseError::new(
        at,
        ParseErrorKind::TooLarge {
            what: "vertices",
            limit: u64::from(u32::MAX),
        },
    )
}
