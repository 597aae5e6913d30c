//! The files a script may read: only those in its own folder (or below), named by a
//! relative path. `image("bark.png")` reads through here; nothing else can open a file.
//!
//! A name is joined to the script's folder and both are resolved (symbolic links
//! followed); the file must then still lie inside the folder. So `../secret.png`, an
//! absolute path, or a link pointing out of the folder is refused with a message that
//! says which rule it broke.

use std::path::{Component, Path, PathBuf};

/// The folder a script's relative file names are read from.
#[derive(Clone, Debug)]
pub struct ScriptFolder {
    folder: PathBuf,
}

/// The most bytes a script may read from one file (a 4096 × 4096 16-bit image is about
/// 32 MB uncompressed; PNG files are smaller).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

impl ScriptFolder {
    /// The folder of the script at `script` (the current folder for a bare file name).
    pub fn of_script(script: &Path) -> ScriptFolder {
        let folder = match script.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        ScriptFolder { folder }
    }

    /// The file `name` (relative to the folder), checked to lie inside it.
    pub fn resolve(&self, name: &str) -> Result<PathBuf, String> {
        let rel = Path::new(name);
        if name.is_empty() {
            return Err("the file name is empty".into());
        }
        if rel.is_absolute() || rel.components().any(|c| matches!(c, Component::Prefix(_))) {
            return Err(format!(
                "\"{name}\" is an absolute path; a script reads only files in its own folder, named relative to it"
            ));
        }
        if rel.components().any(|c| c == Component::ParentDir) {
            return Err(format!(
                "\"{name}\" leaves the script's folder (`..`); a script reads only files in its own folder"
            ));
        }
        let joined = self.folder.join(rel);
        let real = joined.canonicalize().map_err(|e| {
            format!(
                "cannot open \"{name}\" (looked for {}): {e}",
                joined.display()
            )
        })?;
        let root = self.folder.canonicalize().map_err(|e| {
            format!(
                "cannot resolve the script's folder {}: {e}",
                self.folder.display()
            )
        })?;
        if !real.starts_with(&root) {
            return Err(format!(
                "\"{name}\" links to {}, outside the script's folder; a script reads only files in its own folder",
                real.display()
            ));
        }
        if !real.is_file() {
            return Err(format!("\"{name}\" is not a file"));
        }
        Ok(real)
    }

    /// The bytes of the file `name`, with the checks of [`ScriptFolder::resolve`] and a
    /// size limit.
    pub fn read(&self, name: &str) -> Result<Vec<u8>, String> {
        let path = self.resolve(name)?;
        let len = std::fs::metadata(&path)
            .map_err(|e| format!("cannot read \"{name}\": {e}"))?
            .len();
        if len > MAX_FILE_BYTES {
            return Err(format!(
                "\"{name}\" is {len} bytes; a script may read files of at most {MAX_FILE_BYTES} bytes"
            ));
        }
        std::fs::read(&path).map_err(|e| format!("cannot read \"{name}\": {e}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_files_inside_the_folder_are_readable() {
        let dir = tempfile::tempdir().unwrap();
        let inside = dir.path().join("models");
        std::fs::create_dir(&inside).unwrap();
        std::fs::write(inside.join("a.png"), b"x").unwrap();
        std::fs::create_dir(inside.join("sub")).unwrap();
        std::fs::write(inside.join("sub/b.png"), b"y").unwrap();
        std::fs::write(dir.path().join("secret.png"), b"z").unwrap();
        let f = ScriptFolder::of_script(&inside.join("model.rhai"));
        assert_eq!(f.read("a.png").unwrap(), b"x");
        assert_eq!(f.read("sub/b.png").unwrap(), b"y");
        assert!(f.read("../secret.png").unwrap_err().contains(".."));
        let abs = dir.path().join("secret.png");
        assert!(
            f.read(abs.to_str().unwrap())
                .unwrap_err()
                .contains("absolute")
        );
        assert!(f.read("missing.png").unwrap_err().contains("cannot open"));
        assert!(f.read("sub").unwrap_err().contains("not a file"));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(dir.path().join("secret.png"), inside.join("link.png"))
                .unwrap();
            assert!(f.read("link.png").unwrap_err().contains("outside"));
        }
    }
}
