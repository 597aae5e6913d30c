//! Mesh readers and writers.

use std::path::Path;

use crate::mesh::Mesh;

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
    /// The file's content is not valid.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong, and where (line or byte offset).
        message: String,
    },
}

/// Reads a mesh, choosing the format by content and extension.
pub fn read_mesh(path: &Path) -> Result<Mesh, MeshIoError> {
    let _ = path;
    todo!("mesh io helper")
}

/// Writes a mesh whole or not at all (temporary file, then rename).
pub fn write_mesh(mesh: &Mesh, path: &Path, format: MeshFormat) -> Result<(), MeshIoError> {
    let _ = (mesh, path, format);
    todo!("mesh io helper")
}
