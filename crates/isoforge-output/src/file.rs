//! [`OutputFile`]: one output file, written into a temporary beside it and renamed into place
//! on commit (or straight into a FIFO or device).

use std::fs::{File, OpenOptions, Permissions};
use std::io::{self, BufWriter, Write};
use std::os::unix::fs::{OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

use crate::registry::{Closed, GLOBAL, TempKind};
use crate::target::{self, Existing, Target};
use crate::{Durability, Options, OutputError};

/// Buffer between a writer and the file: big enough that a 400 MB mesh goes out in large
/// writes, small next to the mesh itself.
const BUFFER: usize = 1 << 20;

/// Where the bytes go.
#[derive(Debug)]
enum Sink {
    /// A registered temporary file, renamed over the target on commit. `id` is `None` once
    /// committed (nothing left to remove).
    Temp {
        file: File,
        temp: PathBuf,
        id: Option<u64>,
    },
    /// A FIFO or character device, opened at the first write (opening a FIFO waits for a
    /// reader, which should not hold up the work before it).
    Stream { file: Option<File> },
}

/// An output file being written. Nothing appears at the path until [`commit`](Self::commit);
/// dropping it uncommitted removes the temporary and leaves the path as it was.
#[derive(Debug)]
pub struct OutputFile {
    target: Target,
    durability: Durability,
    sink: Sink,
}

impl OutputFile {
    /// Checks the path (see the crate docs for the rules) and creates the temporary file in
    /// its folder, so every reason the output cannot be written shows now, before the work.
    pub fn prepare(path: &Path, options: Options<'_>) -> Result<OutputFile, OutputError> {
        let target = target::for_file(path, options.inputs, options.streams)?;
        let sink = match target.existing {
            Existing::Stream => Sink::Stream { file: None },
            Existing::File { mode, uid, gid } => {
                let (file, temp, id) = create_temp(&target)?;
                // The new file takes the old one's place: same permissions, and (where the
                // process may) the same owner, as if it had been written in place.
                file.set_permissions(Permissions::from_mode(mode))
                    .map_err(|source| OutputError::Create {
                        folder: target.folder.clone(),
                        source,
                    })?;
                let _ = std::os::unix::fs::fchown(&file, Some(uid), Some(gid));
                Sink::Temp {
                    file,
                    temp,
                    id: Some(id),
                }
            }
            Existing::Nothing | Existing::Folder { .. } => {
                let (file, temp, id) = create_temp(&target)?;
                Sink::Temp {
                    file,
                    temp,
                    id: Some(id),
                }
            }
        };
        Ok(OutputFile {
            target,
            durability: options.durability,
            sink,
        })
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.target.requested
    }

    /// The file that will be written: the path with symlinks followed.
    pub fn target(&self) -> &Path {
        &self.target.resolved
    }

    /// The temporary file being written, if there is one (none for a FIFO or device).
    pub fn temp_path(&self) -> Option<&Path> {
        match &self.sink {
            Sink::Temp { temp, .. } => Some(temp),
            Sink::Stream { .. } => None,
        }
    }

    fn write_error(&self, source: io::Error) -> OutputError {
        OutputError::Write {
            path: self.target.requested.clone(),
            source,
        }
    }

    /// Puts the finished file in place: the temporary is flushed (with
    /// [`Durability::Sync`]) and renamed over the target.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let durability = self.durability;
        match &mut self.sink {
            Sink::Stream { file } => {
                if file.is_none() {
                    // Nothing was written: still open it, so an empty output reaches the
                    // reader as an end of file, and a bad device shows.
                    *file = Some(open_stream(&self.target.resolved).map_err(|source| {
                        OutputError::Write {
                            path: self.target.requested.clone(),
                            source,
                        }
                    })?);
                }
                if let Some(f) = file {
                    let flushed = f.flush();
                    flushed.map_err(|source| OutputError::Write {
                        path: self.target.requested.clone(),
                        source,
                    })?;
                }
                Ok(())
            }
            Sink::Temp { file, temp, id } => {
                if durability == Durability::Sync {
                    file.sync_all().map_err(|source| OutputError::Write {
                        path: self.target.requested.clone(),
                        source,
                    })?;
                }
                let Some(key) = *id else {
                    return Ok(());
                };
                let (temp, dest) = (temp.clone(), self.target.resolved.clone());
                match GLOBAL.commit(key, || std::fs::rename(&temp, &dest)) {
                    Err(Closed) => {
                        return Err(OutputError::Interrupted {
                            path: self.target.requested.clone(),
                        });
                    }
                    Ok(Err(source)) => {
                        return Err(OutputError::Commit {
                            path: self.target.requested.clone(),
                            source,
                        });
                    }
                    Ok(Ok(())) => *id = None,
                }
                if durability == Durability::Sync {
                    sync_folder(&self.target.folder);
                }
                Ok(())
            }
        }
    }

    /// Runs `write` on a buffered writer into this file, then commits it. The work's own
    /// error type passes through; write and commit failures become `E` from [`OutputError`].
    pub fn write_with<E: From<OutputError>>(
        mut self,
        write: impl FnOnce(&mut dyn Write) -> Result<(), E>,
    ) -> Result<(), E> {
        {
            let mut buf = BufWriter::with_capacity(BUFFER, &mut self);
            write(&mut buf)?;
            if let Err(source) = buf.flush() {
                drop(buf);
                return Err(self.write_error(source).into());
            }
        }
        self.commit()?;
        Ok(())
    }
}

impl Write for OutputFile {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        match &mut self.sink {
            Sink::Temp { file, .. } => file.write(bytes),
            Sink::Stream { file } => match file {
                Some(f) => f.write(bytes),
                None => file
                    .insert(open_stream(&self.target.resolved)?)
                    .write(bytes),
            },
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match &mut self.sink {
            Sink::Temp { file, .. } => file.flush(),
            Sink::Stream { file } => file.as_mut().map_or(Ok(()), |f| f.flush()),
        }
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        if let Sink::Temp { id: Some(id), .. } = &self.sink {
            GLOBAL.discard(*id);
        }
    }
}

/// Creates and registers a temporary file in the target's folder, with the mode a new file
/// gets (0666 less the umask, which `open` applies), not the private 0600 of mkstemp.
fn create_temp(target: &Target) -> Result<(File, PathBuf, u64), OutputError> {
    let made = GLOBAL.create(&target.folder, TempKind::File, |p| {
        OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o666)
            .open(p)
    });
    match made {
        Err(Closed) => Err(OutputError::Interrupted {
            path: target.requested.clone(),
        }),
        Ok(Err(source)) => Err(OutputError::Create {
            folder: target.folder.clone(),
            source,
        }),
        Ok(Ok((id, temp, file))) => Ok((file, temp, id)),
    }
}

fn open_stream(path: &Path) -> io::Result<File> {
    OpenOptions::new().write(true).open(path)
}

/// Makes a rename in `folder` durable. Some file systems refuse to sync a folder; the file
/// itself is on disk by then, so that is not worth failing the write for.
pub(crate) fn sync_folder(folder: &Path) {
    if let Ok(d) = File::open(folder) {
        let _ = d.sync_all();
    }
}

/// Writes `bytes` to `path` whole, by the rules of [`OutputFile`].
pub fn write_file(path: &Path, bytes: &[u8], options: Options<'_>) -> Result<(), OutputError> {
    let mut out = OutputFile::prepare(path, options)?;
    if let Err(source) = out.write_all(bytes) {
        return Err(out.write_error(source));
    }
    out.commit()
}

/// Checks that `path` could be written by the rules of [`OutputFile`] (for an output written
/// later, or many times, like the print journal), leaving nothing behind.
pub fn check_file(path: &Path, options: Options<'_>) -> Result<(), OutputError> {
    OutputFile::prepare(path, options).map(drop)
}
