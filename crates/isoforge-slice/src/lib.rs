//! Slicing for isoforge: layer outlines straight from the field (or from a mesh), FDM
//! G-code, and resin/voxel layer images.
//!
//! The main call, a model to G-code:
//! ```no_run
//! use isoforge_field::{Bounds, Shape};
//! use isoforge_slice::{Profile, Source, slice_gcode};
//! let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
//! let sphere = (x.square() + y.square() + z.square()).sqrt() - 10.0;
//! let bounds = Bounds::new([-11.0; 3], [11.0; 3]).unwrap();
//! let settings = Profile::default_fdm().fdm().unwrap();
//! let job = slice_gcode(&Source::field(&sphere, bounds), &settings, &|_, _| {}).unwrap();
//! std::fs::write("sphere.gcode", job.gcode).unwrap();
//! ```

pub mod check;
pub mod fdm;
pub mod gcode;
pub mod geom;
pub mod infill;
pub mod outline;
pub mod paths;
pub mod perimeters;
pub mod profile;
pub mod raster;
pub mod skins;
pub mod sl1;
pub mod source;
pub mod svx;

pub use fdm::{GcodeJob, slice_gcode};
pub use geom::{Contour, Point, Region};
pub use profile::{FdmSettings, InfillPattern, Profile, ResinSettings};
pub use raster::{LayerImages, render_layers};
pub use source::Source;

use std::path::PathBuf;

/// Slicing failed; the message says what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SliceError {
    /// A profile or `--set` problem (names the key and the file).
    #[error("{0}")]
    Profile(String),
    /// A mesh that cannot be sliced (open, inside out, ...).
    #[error("mesh: {0}")]
    Mesh(String),
    /// The model does not fit the printer.
    #[error("{0}")]
    TooLarge(String),
    /// The model has no material in its region.
    #[error("{0}")]
    Empty(String),
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Writing an archive or image failed.
    #[error("{0}")]
    Encode(String),
}
