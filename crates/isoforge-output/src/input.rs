//! Input files read with a cap where the size is not known beforehand.
//!
//! A regular file is read whole: its size is on disk for the user to see. Anything else
//! named as an input (`/dev/zero`, a FIFO, a terminal) could give bytes without end, and a
//! reader that slurps it fills memory before any parser can say no, so at most
//! [`MAX_STREAM_BYTES`] are taken from it and more is an error of kind
//! [`io::ErrorKind::FileTooLarge`] carrying a [`StreamTooLarge`].

use std::fs;
use std::io::{self, Read as _};
use std::path::Path;

use thiserror::Error;

/// The most bytes taken from an input that is not a regular file. A mesh, G-code file or
/// profile piped through a FIFO is rarely larger; a larger one can be saved to a file.
pub const MAX_STREAM_BYTES: u64 = 256 << 20;

/// An input that is not a regular file gave more than the cap.
#[derive(Debug, Error)]
#[error(
    "not a regular file, and it gave more than {} MiB (is it a device like /dev/zero?); \
     save it to a file and give that",
    limit >> 20
)]
pub struct StreamTooLarge {
    /// The cap, in bytes.
    pub limit: u64,
}

/// Reads an input file: a regular file whole, anything else up to [`MAX_STREAM_BYTES`].
pub fn read_input(path: &Path) -> io::Result<Vec<u8>> {
    read_input_capped(path, MAX_STREAM_BYTES)
}

/// Reads an input file as UTF-8 text, with [`read_input`]'s cap.
pub fn read_input_to_string(path: &Path) -> io::Result<String> {
    let bytes = read_input(path)?;
    String::from_utf8(bytes).map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e))
}

/// [`read_input`] with a cap of `limit` bytes for non-files.
pub fn read_input_capped(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = fs::File::open(path)?;
    if file.metadata()?.is_file() {
        return fs::read(path);
    }
    let mut bytes = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(io::Error::new(
            io::ErrorKind::FileTooLarge,
            StreamTooLarge { limit },
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_is_read_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        fs::write(&path, vec![b'x'; 5000]).unwrap();
        assert_eq!(read_input_capped(&path, 10).unwrap().len(), 5000);
    }

    #[test]
    fn an_endless_device_is_cut_off_with_a_clear_error() {
        let err = read_input_capped(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::FileTooLarge);
        assert!(err.to_string().contains("not a regular file"), "{err}");
    }

    #[test]
    fn a_short_stream_is_read() {
        assert!(read_input(Path::new("/dev/null")).unwrap().is_empty());
    }
}
