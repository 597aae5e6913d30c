//! [`OutputFolder`]: a folder of files (layer PNGs) that appears whole or not at all: the
//! files go into a temporary folder beside it, renamed into place on commit.

use std::fs::{self, DirBuilder, OpenOptions, Permissions};
use std::io::{self, Write};
use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

use crate::file::sync_folder;
use crate::registry::{Closed, GLOBAL, TempKind};
use crate::target::{self, Existing, Target};
use crate::{Durability, Options, OutputError};

/// A folder of output files being written. The folder at the path must be new or empty;
/// nothing appears there until [`commit`](Self::commit), and dropping it uncommitted removes
/// the temporary folder with everything in it.
#[derive(Debug)]
pub struct OutputFolder {
    target: Target,
    durability: Durability,
    staging: PathBuf,
    id: Option<u64>,
}

impl OutputFolder {
    /// Checks the path (a new or empty folder, not an input, in a folder that exists) and
    /// creates the temporary folder beside it, before the work.
    pub fn prepare(path: &Path, options: Options<'_>) -> Result<OutputFolder, OutputError> {
        let target = target::for_folder(path, options.inputs)?;
        let made = GLOBAL.create(&target.folder, TempKind::Folder, |p| {
            DirBuilder::new().mode(0o777).create(p)
        });
        let (id, staging) = match made {
            Err(Closed) => {
                return Err(OutputError::Interrupted {
                    path: target.requested.clone(),
                });
            }
            Ok(Err(source)) => {
                return Err(OutputError::Create {
                    folder: target.folder.clone(),
                    source,
                });
            }
            Ok(Ok((id, staging, ()))) => (id, staging),
        };
        let out = OutputFolder {
            target,
            durability: options.durability,
            staging,
            id: Some(id),
        };
        if let Existing::Folder { mode } = out.target.existing {
            // The folder that is replaced keeps its permissions.
            fs::set_permissions(&out.staging, Permissions::from_mode(mode)).map_err(|source| {
                OutputError::Create {
                    folder: out.target.folder.clone(),
                    source,
                }
            })?;
        }
        Ok(out)
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.target.requested
    }

    /// Writes one file into the folder. `name` must be a plain file name.
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let write_error = |source| OutputError::Write {
            path: self.target.requested.join(name),
            source,
        };
        let plain = Path::new(name).file_name().is_some_and(|n| n == name);
        if !plain {
            return Err(write_error(io::Error::new(
                io::ErrorKind::InvalidInput,
                "not a plain file name",
            )));
        }
        let mut file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o666)
            .open(self.staging.join(name))
            .map_err(write_error)?;
        file.write_all(bytes).map_err(write_error)?;
        if self.durability == Durability::Sync {
            file.sync_all().map_err(write_error)?;
        }
        Ok(())
    }

    /// Puts the folder in place (replacing the empty folder that stood there, if any).
    pub fn commit(mut self) -> Result<(), OutputError> {
        let Some(id) = self.id else {
            return Ok(());
        };
        if self.durability == Durability::Sync {
            sync_folder(&self.staging);
        }
        let (staging, dest) = (self.staging.clone(), self.target.resolved.clone());
        let replace_empty = matches!(self.target.existing, Existing::Folder { .. });
        let moved = GLOBAL.commit(id, || {
            if replace_empty {
                // Still empty? remove_dir refuses a folder that is not, so nothing the user
                // put there since the check is lost.
                fs::remove_dir(&dest)?;
            }
            fs::rename(&staging, &dest)
        });
        match moved {
            Err(Closed) => Err(OutputError::Interrupted {
                path: self.target.requested.clone(),
            }),
            Ok(Err(source)) => Err(OutputError::Commit {
                path: self.target.requested.clone(),
                source,
            }),
            Ok(Ok(())) => {
                self.id = None;
                if self.durability == Durability::Sync {
                    sync_folder(&self.target.folder);
                }
                Ok(())
            }
        }
    }
}

impl Drop for OutputFolder {
    fn drop(&mut self) {
        if let Some(id) = self.id {
            GLOBAL.discard(id);
        }
    }
}
