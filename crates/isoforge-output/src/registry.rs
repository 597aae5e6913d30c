//! The process-wide list of temporary files and folders not yet committed, so that a signal
//! handler can remove them before the process exits.
//!
//! Creating, committing and removing a temporary all happen under one lock: the handler's
//! [`remove_temp_files`] therefore never misses a temporary that is being created, and never
//! deletes one that a commit has just renamed into place. Once it has run, the registry is
//! closed: new temporaries and commits fail with [`OutputError::Interrupted`](crate::OutputError),
//! because the process is on its way out.

use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// What a registered temporary is, so it is removed the right way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TempKind {
    File,
    Folder,
}

#[derive(Debug)]
struct Entry {
    id: u64,
    path: PathBuf,
    kind: TempKind,
}

#[derive(Debug, Default)]
struct State {
    live: Vec<Entry>,
    next: u64,
    closed: bool,
}

/// The process is exiting: no temporary may be created or committed.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct Closed;

/// A list of live temporaries. One global instance serves the program; tests make their own.
#[derive(Debug)]
pub(crate) struct Registry {
    state: Mutex<State>,
}

impl Registry {
    pub(crate) const fn new() -> Registry {
        Registry {
            state: Mutex::new(State {
                live: Vec::new(),
                next: 0,
                closed: false,
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock leaves the list consistent (every change is one
        // push or one remove), so a poisoned lock is still usable.
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Creates a temporary in `folder` with `make` (given a fresh name; it must fail with
    /// `AlreadyExists` if the name is taken) and registers it. Returns its id and path.
    pub(crate) fn create<T>(
        &self,
        folder: &Path,
        kind: TempKind,
        mut make: impl FnMut(&Path) -> io::Result<T>,
    ) -> Result<io::Result<(u64, PathBuf, T)>, Closed> {
        let mut state = self.lock();
        if state.closed {
            return Err(Closed);
        }
        loop {
            state.next += 1;
            let id = state.next;
            // Hidden, and named after the process so two programs never collide.
            let path = folder.join(format!(".isoforge-{}-{id}.tmp", std::process::id()));
            match make(&path) {
                Ok(made) => {
                    state.live.push(Entry {
                        id,
                        path: path.clone(),
                        kind,
                    });
                    return Ok(Ok((id, path, made)));
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Ok(Err(e)),
            }
        }
    }

    /// Runs `rename` (which moves the temporary into place) unless the registry is closed;
    /// on success the temporary is no longer tracked.
    pub(crate) fn commit(
        &self,
        id: u64,
        rename: impl FnOnce() -> io::Result<()>,
    ) -> Result<io::Result<()>, Closed> {
        let mut state = self.lock();
        if state.closed {
            return Err(Closed);
        }
        let result = rename();
        if result.is_ok() {
            state.live.retain(|e| e.id != id);
        }
        Ok(result)
    }

    /// Removes one temporary from the disk and the list (a dropped, uncommitted output).
    pub(crate) fn discard(&self, id: u64) {
        let mut state = self.lock();
        if let Some(k) = state.live.iter().position(|e| e.id == id) {
            let entry = state.live.swap_remove(k);
            remove(&entry);
        }
    }

    /// Removes every live temporary and closes the registry. Returns how many were removed.
    pub(crate) fn remove_all(&self) -> usize {
        let mut state = self.lock();
        state.closed = true;
        let live = std::mem::take(&mut state.live);
        for entry in &live {
            remove(entry);
        }
        live.len()
    }

    /// The paths of the live temporaries.
    pub(crate) fn live(&self) -> Vec<PathBuf> {
        self.lock().live.iter().map(|e| e.path.clone()).collect()
    }
}

fn remove(entry: &Entry) {
    // Best effort: the file may already be gone (removed by hand), and there is nobody to
    // tell on the way out.
    let _ = match entry.kind {
        TempKind::File => std::fs::remove_file(&entry.path),
        TempKind::Folder => std::fs::remove_dir_all(&entry.path),
    };
}

/// The program's registry.
pub(crate) static GLOBAL: Registry = Registry::new();

/// Removes every temporary file and folder of an output not yet committed, and makes later
/// outputs fail with [`OutputError::Interrupted`](crate::OutputError::Interrupted). For a
/// signal handler (or any path) that is about to end the process: call it, then exit.
/// Returns how many temporaries were removed.
pub fn remove_temp_files() -> usize {
    GLOBAL.remove_all()
}

/// The paths of the temporaries that exist now (outputs prepared and not yet committed or
/// dropped).
pub fn live_temp_files() -> Vec<PathBuf> {
    GLOBAL.live()
}
