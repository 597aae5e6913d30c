//! The model's folder: the only place the studio reads and writes. Names from the page are
//! single file names inside it; anything else (`..`, an absolute path, a subfolder, a link
//! that leads out) is refused before the file system is touched for it.

use std::path::{Component, Path, PathBuf};

/// A name the page gave is not a file of the model's folder.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// Not a plain file name: a path, `..`, empty, or with odd characters.
    #[error("{name:?} is not a file name in the model's folder (no paths, no ..)")]
    NotAName {
        /// The name as given.
        name: String,
    },
    /// A link (or other trick) that resolves outside the folder.
    #[error("{name:?} leads outside the model's folder")]
    Outside {
        /// The name as given.
        name: String,
    },
    /// The folder itself cannot be used.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// The model's folder, resolved once at start (symlinks and all).
#[derive(Debug, Clone)]
pub struct ModelFolder {
    root: PathBuf,
}

impl ModelFolder {
    /// The folder, resolved to its real path.
    pub fn open(path: &Path) -> Result<ModelFolder, FolderError> {
        let root = path.canonicalize().map_err(|source| FolderError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(ModelFolder { root })
    }

    /// Its real path.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The path of the file `name` in the folder. The file need not exist (a new export),
    /// but if it does, it must really be in the folder (a link to elsewhere is refused).
    pub fn resolve(&self, name: &str) -> Result<PathBuf, FolderError> {
        let not_a_name = || FolderError::NotAName {
            name: name.to_string(),
        };
        let plain = !name.is_empty()
            && name.len() <= 255
            && !name.starts_with('.')
            && !name.contains(['/', '\\', '\0'])
            && !name.chars().any(char::is_control);
        if !plain {
            return Err(not_a_name());
        }
        let mut parts = Path::new(name).components();
        if !matches!(
            (parts.next(), parts.next()),
            (Some(Component::Normal(_)), None)
        ) {
            return Err(not_a_name());
        }
        let path = self.root.join(name);
        match path.canonicalize() {
            Ok(real) if real.parent() == Some(self.root.as_path()) => Ok(path),
            Ok(_) => Err(FolderError::Outside {
                name: name.to_string(),
            }),
            // A dangling link would be created outside by a write: refuse it too.
            Err(_) if path.symlink_metadata().is_ok() => Err(FolderError::Outside {
                name: name.to_string(),
            }),
            Err(_) => Ok(path),
        }
    }

    /// The folder's files with one of these extensions (lower case, no dot), sorted.
    pub fn files_with(&self, extensions: &[&str]) -> Vec<String> {
        let Ok(entries) = std::fs::read_dir(&self.root) else {
            return Vec::new();
        };
        let mut names: Vec<String> = entries
            .filter_map(Result::ok)
            .filter_map(|e| e.file_name().into_string().ok())
            .filter(|n| {
                Path::new(n)
                    .extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| extensions.contains(&e.to_ascii_lowercase().as_str()))
            })
            .filter(|n| self.resolve(n).is_ok_and(|p| p.is_file()))
            .collect();
        names.sort();
        names
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_resolve_inside() {
        let dir = tempfile::tempdir().unwrap();
        let f = ModelFolder::open(dir.path()).unwrap();
        let p = f.resolve("part.stl").unwrap();
        assert_eq!(p.parent(), Some(f.root()));
    }

    #[test]
    fn paths_and_dot_dot_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let f = ModelFolder::open(dir.path()).unwrap();
        for bad in [
            "../x.rhai",
            "..",
            ".",
            "/etc/passwd",
            "a/b.rhai",
            "a\\b",
            "",
            ".hidden",
            "x\0y",
            "new\nline",
        ] {
            assert!(
                matches!(f.resolve(bad), Err(FolderError::NotAName { .. })),
                "{bad:?} was accepted"
            );
        }
    }

    #[test]
    fn links_leading_out_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("secret.txt"), "s").unwrap();
        std::os::unix::fs::symlink(outside.path().join("secret.txt"), dir.path().join("l.rhai"))
            .unwrap();
        std::os::unix::fs::symlink(outside.path().join("none"), dir.path().join("d.stl")).unwrap();
        let f = ModelFolder::open(dir.path()).unwrap();
        assert!(matches!(
            f.resolve("l.rhai"),
            Err(FolderError::Outside { .. })
        ));
        assert!(matches!(
            f.resolve("d.stl"),
            Err(FolderError::Outside { .. })
        ));
        assert!(f.files_with(&["rhai"]).is_empty());
    }
}
