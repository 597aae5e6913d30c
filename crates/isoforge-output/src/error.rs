//! Why an output could not be written.

use std::io;
use std::path::PathBuf;

use thiserror::Error;

/// An output was refused or could not be written. Each variant names the path it is about.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The path is empty.
    #[error("the output path is empty")]
    EmptyPath,
    /// The output is one of the command's inputs (the same file, whatever the path).
    #[error(
        "{output}: this is the input {input}; writing it would destroy the input, so give \
         another output path"
    )]
    IsInput {
        /// The output path as given.
        output: PathBuf,
        /// The input it is.
        input: PathBuf,
    },
    /// A folder stands where a file is to be written.
    #[error("{path}: is a folder; give a file name")]
    IsFolder {
        /// The output path.
        path: PathBuf,
    },
    /// A file stands where a folder of files is to be written.
    #[error("{path}: is not a folder")]
    NotAFolder {
        /// The output path.
        path: PathBuf,
    },
    /// An existing output folder has files in it.
    #[error("{path}: the folder exists and is not empty; give a new or empty folder")]
    FolderNotEmpty {
        /// The output folder.
        path: PathBuf,
    },
    /// The existing file has no write permission.
    #[error("{path}: the file is read-only; make it writable (chmod u+w) or give another path")]
    ReadOnly {
        /// The file (a symlink's target, if the path was a link).
        path: PathBuf,
    },
    /// The folder the output goes into does not exist.
    #[error("{folder}: the output folder does not exist (for {path})")]
    NoFolder {
        /// The output path.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// Something that cannot sensibly be written stands at the path.
    #[error("{path}: is a {kind}; isoforge writes only to files{hint}")]
    Unsupported {
        /// The output path (a symlink's target, if the path was a link).
        path: PathBuf,
        /// What stands there ("block device", "socket", "FIFO", ...).
        kind: &'static str,
        /// What to do instead, or empty.
        hint: &'static str,
    },
    /// The path is a chain of symlinks that does not end.
    #[error("{path}: too many levels of symbolic links")]
    SymlinkLoop {
        /// The output path.
        path: PathBuf,
    },
    /// What stands at the path could not be inspected.
    #[error("{path}: {source}")]
    Inspect {
        /// The path.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// No temporary file could be made in the output folder (permissions, a full disk).
    #[error("{folder}: cannot create a file in this folder: {source}")]
    Create {
        /// The folder.
        folder: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// Writing the content failed.
    #[error("{path}: write failed: {source}")]
    Write {
        /// The output path.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// The finished file could not be moved into place.
    #[error("{path}: cannot put the finished file in place: {source}")]
    Commit {
        /// The output path.
        path: PathBuf,
        /// Why.
        source: io::Error,
    },
    /// The process is exiting on a signal; its temporary files are gone.
    #[error("{path}: not written: the program was interrupted")]
    Interrupted {
        /// The output path.
        path: PathBuf,
    },
}

impl From<OutputError> for io::Error {
    fn from(e: OutputError) -> io::Error {
        let kind = match &e {
            OutputError::Inspect { source, .. }
            | OutputError::Create { source, .. }
            | OutputError::Write { source, .. }
            | OutputError::Commit { source, .. } => source.kind(),
            OutputError::Interrupted { .. } => io::ErrorKind::Interrupted,
            OutputError::ReadOnly { .. } => io::ErrorKind::PermissionDenied,
            OutputError::NoFolder { .. } => io::ErrorKind::NotFound,
            _ => io::ErrorKind::InvalidInput,
        };
        io::Error::new(kind, e)
    }
}
