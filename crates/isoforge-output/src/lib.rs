//! Output files written safely: the one way isoforge writes a file.
//!
//! Every file a command writes (meshes, G-code, SL1 and SVX archives, layer PNGs, pictures,
//! the print journal, the fake printer's log) goes through [`OutputFile`] (or, for a folder
//! of files, [`OutputFolder`]), so every output keeps the same promises:
//!
//! - **Whole or not at all.** The bytes go to a temporary file in the same folder, renamed over
//!   the target only by [`OutputFile::commit`]. A failure, a panic or a signal leaves what stood
//!   at the path before.
//! - **Durability on request.** [`Durability::Sync`] flushes the file and the folder to disk
//!   (the print journal must survive a power cut); [`Durability::Replace`] does not (a 400 MB
//!   mesh need not wait for the disk).
//! - **Never over an input.** An output that is one of the command's inputs (the same file,
//!   by device and inode, whatever path names it) is refused before any work.
//! - **Into what the user named.** A symlink is followed and its target replaced (the link
//!   stays a link); a FIFO or character device is written straight into; a folder, block
//!   device or socket is refused. A replaced file keeps its permissions; a read-only file is
//!   refused.
//! - **Checked before the work.** [`OutputFile::prepare`] resolves the path, checks the folder
//!   and creates the temporary file at once, so a missing or read-only folder is an error
//!   before a long job, not after it.
//! - **No litter.** Temporary files are removed when dropped, and [`remove_temp_files`] removes
//!   every live one: a program's signal handler calls it before exiting.
//!
//! Inputs have their one way too: [`read_input`] reads a regular file whole and takes at
//! most [`MAX_STREAM_BYTES`] from anything else (`/dev/zero`, a FIFO), so no reader can be
//! made to fill memory by an endless stream.
//!
//! ```no_run
//! use std::io::Write;
//! use std::path::Path;
//! use isoforge_output::{Options, OutputFile};
//!
//! let model = Path::new("heart.rhai");
//! // Before the work: refuses `-o heart.rhai`, a missing folder, a read-only file.
//! let mut out = OutputFile::prepare(Path::new("heart.stl"), Options::with_inputs(&[model]))?;
//! // ... the long work ...
//! out.write_all(b"solid heart\nendsolid heart\n")?;
//! out.commit()?; // now, and only now, heart.stl is replaced
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;
mod file;
mod folder;
mod input;
mod registry;
mod target;

pub use error::OutputError;
pub use file::{OutputFile, check_file, write_file};
pub use folder::OutputFolder;
pub use input::{
    MAX_STREAM_BYTES, StreamTooLarge, read_input, read_input_capped, read_input_to_string,
};
pub use registry::{live_temp_files, remove_temp_files};

use std::path::Path;

/// How hard a committed file is pushed to the disk.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Durability {
    /// Rename into place; the operating system writes it back when it likes. A crash soon
    /// after may lose the new file, never leave half of one under the name.
    #[default]
    Replace,
    /// Flush the file before the rename and the folder after it, so the new content is on
    /// the disk when `commit` returns (the print journal).
    Sync,
}

/// What to do when the path names a FIFO or a character device (`/dev/stdout`, a pipe).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Streams {
    /// Write straight into it (there is nothing to replace atomically).
    #[default]
    WriteThrough,
    /// Refuse it: the output must be a file that can be read back (a journal).
    Refuse,
}

/// What an output must respect.
#[derive(Clone, Copy, Debug, Default)]
pub struct Options<'a> {
    /// The command's input files: the output may be none of them.
    pub inputs: &'a [&'a Path],
    /// How hard a commit pushes the file to disk.
    pub durability: Durability,
    /// Whether a FIFO or character device at the path is written into or refused.
    pub streams: Streams,
}

impl<'a> Options<'a> {
    /// Default options with the command's inputs.
    pub fn with_inputs(inputs: &'a [&'a Path]) -> Options<'a> {
        Options {
            inputs,
            ..Options::default()
        }
    }
}

#[cfg(test)]
mod tests;
