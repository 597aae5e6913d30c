//! What stands at an output path, and whether writing there is allowed: symlinks followed to
//! the file they name, inputs recognised by device and inode, read-only files, folders and
//! devices told apart, the folder checked.

use std::fs::{self, Metadata};
use std::io;
use std::os::unix::fs::{FileTypeExt, MetadataExt, PermissionsExt};
use std::path::{Path, PathBuf};

use crate::{OutputError, Streams};

/// Links followed before giving up, as Linux's own limit (ELOOP after 40).
const MAX_SYMLINKS: usize = 40;

/// What already stands at the resolved path.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Existing {
    /// Nothing: the output is new.
    Nothing,
    /// A regular file, replaced keeping its mode and owner.
    File { mode: u32, uid: u32, gid: u32 },
    /// A FIFO or character device, written into.
    Stream,
    /// A folder (for a folder output: replaced if empty, keeping its mode).
    Folder { mode: u32 },
}

/// A checked output path.
#[derive(Clone, Debug)]
pub(crate) struct Target {
    /// The path as the caller gave it, for messages.
    pub requested: PathBuf,
    /// The path with symlinks followed: what is written or replaced.
    pub resolved: PathBuf,
    /// The folder of `path`, where temporaries go.
    pub folder: PathBuf,
    /// What is there now.
    pub existing: Existing,
}

/// The folder a path is in (`.` for a bare file name).
pub(crate) fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Follows symlinks at the last component of `path` (each link relative to its own folder)
/// to what they name, which may not exist yet. Returns that path and its metadata.
pub(crate) fn resolve(path: &Path) -> Result<(PathBuf, Option<Metadata>), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(OutputError::EmptyPath);
    }
    let inspect = |p: &Path, source: io::Error| OutputError::Inspect {
        path: p.to_path_buf(),
        source,
    };
    let mut p = path.to_path_buf();
    for _ in 0..=MAX_SYMLINKS {
        match fs::symlink_metadata(&p) {
            // Nothing there (or a file where a folder should be: the folder check says so).
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::NotFound | io::ErrorKind::NotADirectory
                ) =>
            {
                return Ok((p, None));
            }
            Err(e) => return Err(inspect(&p, e)),
            Ok(m) if m.file_type().is_symlink() => {
                let link = fs::read_link(&p).map_err(|e| inspect(&p, e))?;
                p = if link.is_absolute() {
                    link
                } else {
                    folder_of(&p).join(link)
                };
            }
            Ok(m) => return Ok((p, Some(m))),
        }
    }
    Err(OutputError::SymlinkLoop {
        path: path.to_path_buf(),
    })
}

/// Refuses `meta` (what stands at the output) if it is one of `inputs`: the same device and
/// inode, so another spelling of the path, a symlink or a hard link is caught too.
fn refuse_inputs(requested: &Path, meta: &Metadata, inputs: &[&Path]) -> Result<(), OutputError> {
    for input in inputs {
        // An input that cannot be read is the command's problem to report, not this one.
        if let Ok(im) = fs::metadata(input)
            && im.dev() == meta.dev()
            && im.ino() == meta.ino()
        {
            return Err(OutputError::IsInput {
                output: requested.to_path_buf(),
                input: input.to_path_buf(),
            });
        }
    }
    Ok(())
}

/// The folder must exist and be a folder.
fn check_folder(requested: &Path, folder: &Path) -> Result<(), OutputError> {
    match fs::metadata(folder) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(_) => Err(OutputError::NotAFolder {
            path: folder.to_path_buf(),
        }),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Err(OutputError::NoFolder {
            path: requested.to_path_buf(),
            folder: folder.to_path_buf(),
        }),
        Err(e) => Err(OutputError::Inspect {
            path: folder.to_path_buf(),
            source: e,
        }),
    }
}

fn unsupported(path: &Path, kind: &'static str, hint: &'static str) -> OutputError {
    OutputError::Unsupported {
        path: path.to_path_buf(),
        kind,
        hint,
    }
}

/// Checks a path for a file output.
pub(crate) fn for_file(
    requested: &Path,
    inputs: &[&Path],
    streams: Streams,
) -> Result<Target, OutputError> {
    // A pipe or terminal reached through a magic link (`/dev/stdout`, `/proc/self/fd/1`)
    // has no path of its own to follow to: let the kernel open it by the name given.
    if let Ok(m) = fs::metadata(requested)
        && (m.file_type().is_fifo() || m.file_type().is_char_device())
        && streams == Streams::WriteThrough
    {
        refuse_inputs(requested, &m, inputs)?;
        return Ok(Target {
            requested: requested.to_path_buf(),
            resolved: requested.to_path_buf(),
            folder: folder_of(requested),
            existing: Existing::Stream,
        });
    }
    let (path, meta) = resolve(requested)?;
    let folder = folder_of(&path);
    let existing = match &meta {
        None => Existing::Nothing,
        Some(m) => {
            let ft = m.file_type();
            refuse_inputs(requested, m, inputs)?;
            if ft.is_dir() {
                return Err(OutputError::IsFolder { path });
            } else if ft.is_file() {
                if m.permissions().mode() & 0o222 == 0 {
                    return Err(OutputError::ReadOnly { path });
                }
                Existing::File {
                    mode: m.permissions().mode() & 0o7777,
                    uid: m.uid(),
                    gid: m.gid(),
                }
            } else if ft.is_fifo() || ft.is_char_device() {
                if streams == Streams::Refuse {
                    let kind = if ft.is_fifo() {
                        "FIFO"
                    } else {
                        "character device"
                    };
                    return Err(unsupported(
                        &path,
                        kind,
                        " that can be read back here; give a file path",
                    ));
                }
                Existing::Stream
            } else if ft.is_block_device() {
                return Err(unsupported(&path, "block device", ""));
            } else if ft.is_socket() {
                return Err(unsupported(&path, "socket", ""));
            } else {
                return Err(unsupported(&path, "special file", ""));
            }
        }
    };
    if existing != Existing::Stream {
        check_folder(requested, &folder)?;
    }
    Ok(Target {
        requested: requested.to_path_buf(),
        resolved: path,
        folder,
        existing,
    })
}

/// Checks a path for a folder output: new, or an existing empty folder.
pub(crate) fn for_folder(requested: &Path, inputs: &[&Path]) -> Result<Target, OutputError> {
    let (path, meta) = resolve(requested)?;
    let folder = folder_of(&path);
    let existing = match &meta {
        None => Existing::Nothing,
        Some(m) => {
            refuse_inputs(requested, m, inputs)?;
            if !m.is_dir() {
                return Err(OutputError::NotAFolder { path });
            }
            let mut entries = fs::read_dir(&path).map_err(|source| OutputError::Inspect {
                path: path.clone(),
                source,
            })?;
            if entries.next().is_some() {
                return Err(OutputError::FolderNotEmpty { path });
            }
            Existing::Folder {
                mode: m.permissions().mode() & 0o7777,
            }
        }
    };
    check_folder(requested, &folder)?;
    Ok(Target {
        requested: requested.to_path_buf(),
        resolved: path,
        folder,
        existing,
    })
}
