//! Mesh readers and writers: STL (binary and ASCII), OBJ, PLY and 3MF.
//!
//! Readers take the whole file as bytes, pick the format by content (falling back on the
//! extension), and never panic: every malformed input is a [`MeshIoError::Parse`] naming the
//! file and the line (text formats) or byte offset (binary formats). [`encode`] writes a
//! format onto any writer; [`write_mesh`] puts it in a file through `isoforge-output`.

mod error;
pub mod obj;
pub mod ply;
pub mod stl;
pub mod stream;
pub mod threemf;
mod weld;

use std::io::Write;
use std::path::Path;

use isoforge_output::{Options, OutputFile};

use crate::mesh::Mesh;
use crate::sink::MeshSink;

pub use stream::MeshWriter;

pub use error::{ParseError, ParseErrorKind, Place};
pub(crate) use error::{at_line, too_many_vertices};
pub(crate) use weld::Welder;

/// A mesh file format.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary STL.
    Stl,
    /// ASCII STL.
    StlAscii,
    /// 3MF package.
    ThreeMf,
    /// Wavefront OBJ.
    Obj,
    /// PLY (binary little-endian when written).
    Ply,
}

impl MeshFormat {
    /// The format a file name's extension names (`.stl` is binary STL), if any.
    pub fn from_extension(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "stl" => Some(MeshFormat::Stl),
            "3mf" => Some(MeshFormat::ThreeMf),
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }

    /// The format for a command-line name: `stl`, `stl-ascii`, `3mf`, `obj`, `ply`.
    pub fn from_name(name: &str) -> Option<MeshFormat> {
        match name.to_ascii_lowercase().as_str() {
            "stl" => Some(MeshFormat::Stl),
            "stl-ascii" => Some(MeshFormat::StlAscii),
            "3mf" => Some(MeshFormat::ThreeMf),
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }

    /// The command-line name of the format.
    pub fn name(self) -> &'static str {
        match self {
            MeshFormat::Stl => "stl",
            MeshFormat::StlAscii => "stl-ascii",
            MeshFormat::ThreeMf => "3mf",
            MeshFormat::Obj => "obj",
            MeshFormat::Ply => "ply",
        }
    }

    /// Recognises a format by a file's first bytes and size, where that is unambiguous.
    pub fn sniff(bytes: &[u8]) -> Option<MeshFormat> {
        if bytes.starts_with(b"PK\x03\x04") {
            return Some(MeshFormat::ThreeMf);
        }
        if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
            return Some(MeshFormat::Ply);
        }
        if stl::is_binary_size(bytes) {
            return Some(MeshFormat::Stl);
        }
        if stl::looks_ascii(bytes) {
            return Some(MeshFormat::StlAscii);
        }
        None
    }
}

impl std::fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A mesh file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    /// An I/O failure.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The output was refused or could not be put in place (the message names the path).
    #[error(transparent)]
    Output(#[from] isoforge_output::OutputError),
    /// The file's content is not valid.
    #[error("{path}: {error}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong, and where (line, byte offset or package entry).
        error: ParseError,
    },
}

impl MeshIoError {
    /// The parse error, when the content was at fault.
    pub fn parse_error(&self) -> Option<&ParseError> {
        match self {
            MeshIoError::Parse { error, .. } => Some(error),
            MeshIoError::Io { .. } | MeshIoError::Output(_) => None,
        }
    }
}

/// Reads a mesh, choosing the format by content and extension.
pub fn read_mesh(path: &Path) -> Result<Mesh, MeshIoError> {
    let bytes = isoforge_output::read_input(path).map_err(|source| MeshIoError::Io {
        path: path.display().to_string(),
        source,
    })?;
    read_mesh_bytes(&bytes, &path.display().to_string())
}

/// Parses a mesh held in memory. `name` is the file name: its extension is the fallback
/// when the content does not name its format, and errors start with it.
pub fn read_mesh_bytes(bytes: &[u8], name: &str) -> Result<Mesh, MeshIoError> {
    let format = MeshFormat::sniff(bytes)
        .or_else(|| MeshFormat::from_extension(Path::new(name)))
        .or_else(|| obj::looks_like_obj(bytes).then_some(MeshFormat::Obj));
    let parse_error = |error: ParseError| MeshIoError::Parse {
        path: name.to_string(),
        error,
    };
    let Some(format) = format else {
        return Err(parse_error(ParseError::file(ParseErrorKind::UnknownFormat)));
    };
    decode(bytes, format).map_err(parse_error)
}

/// Parses bytes as the given format (binary and ASCII STL are told apart by content).
pub fn decode(bytes: &[u8], format: MeshFormat) -> Result<Mesh, ParseError> {
    match format {
        MeshFormat::Stl | MeshFormat::StlAscii => stl::read(bytes),
        MeshFormat::ThreeMf => threemf::read(bytes),
        MeshFormat::Obj => obj::read(bytes),
        MeshFormat::Ply => ply::read(bytes),
    }
}

/// Encodes a mesh in a format onto a writer. The mesh's indices must be in range.
pub fn encode(mesh: &Mesh, format: MeshFormat, w: &mut dyn Write) -> std::io::Result<()> {
    if !mesh.has_valid_indices() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the mesh has a triangle index past its last vertex",
        ));
    }
    let mut writer = MeshWriter::ordered(format, w, mesh.vertices.len(), mesh.triangles.len())?;
    for &v in &mesh.vertices {
        writer.vertex(v)?;
    }
    for &t in &mesh.triangles {
        writer.triangle(t, t.map(|i| mesh.vertices[i as usize]))?;
    }
    writer.finish().map(drop)
}

/// Writes a mesh file by the rules of [`isoforge_output`]: whole or not at all, into a
/// symlink's target, keeping the mode of a file it replaces. No fsync: a mesh can be
/// written again, and waiting for the disk would double the time of a large one.
pub fn write_mesh(mesh: &Mesh, path: &Path, format: MeshFormat) -> Result<(), MeshIoError> {
    let out = OutputFile::prepare(path, Options::default())?;
    out.write_with(|w| {
        encode(mesh, format, w).map_err(|source| MeshIoError::Io {
            path: path.display().to_string(),
            source,
        })
    })
}

/// A coordinate for text formats: shortest text that reads back to the same f32, with
/// `-0.0` written as `0` so readers that weld by bit pattern see one vertex. A `Display`
/// value, not a `String`, so writers format straight into their buffer.
pub(crate) fn fmt_coord(v: f32) -> impl std::fmt::Display {
    struct Coord(f32);
    impl std::fmt::Display for Coord {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            std::fmt::Display::fmt(&(self.0 + 0.0), f)
        }
    }
    Coord(v)
}

/// Parses one coordinate token of a text format: finite f32 or an error.
pub(crate) fn parse_coord(token: &str, line: usize) -> Result<f32, ParseError> {
    token
        .parse::<f32>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            ParseError::new(
                Place::Line(line),
                ParseErrorKind::BadNumber {
                    field: "coordinate".into(),
                    token: token.to_string(),
                },
            )
        })
}

/// The lines of a text file, numbered from 1, each as text (an error names a line that is
/// not UTF-8).
pub(crate) fn text_lines(bytes: &[u8]) -> impl Iterator<Item = Result<(usize, &str), ParseError>> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, raw)| {
        let line = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        std::str::from_utf8(raw)
            .map(|s| (line, s))
            .map_err(|_| ParseError::new(Place::Line(line), ParseErrorKind::NotText))
    })
}

#[cfg(test)]
mod hostile_tests;
#[cfg(test)]
mod tests;
