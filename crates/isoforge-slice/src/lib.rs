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
//!
//! The public surface: a [`Source`] (field or mesh), a [`Profile`] read into
//! [`FdmSettings`] or [`ResinSettings`], [`slice_gcode`] and [`render_layers`], the archive
//! writers in [`sl1`] and [`svx`], and the G-code checker in [`check`]. Outlines, perimeters,
//! skins, infill and path ordering are internal stages.

mod adhesion;
mod bridges;
pub mod check;
mod clip;
pub mod display;
mod fdm;
mod gcode;
mod geom;
mod infill;
mod medial;
mod outline;
mod overhangs;
mod paths;
pub mod preview;
mod profile;
mod raster;
pub mod sl1;
mod source;
mod supports;
mod surfaces;
pub mod svx;
mod walls;

#[cfg(test)]
mod region_agreement_tests;

pub use display::DisplayFrame;
pub use fdm::{Control, GcodeJob, Progress, SliceWarning, slice_gcode, slice_plate};
pub use gcode::GcodeStats;
pub use paths::Role;
pub use profile::keys;
pub use profile::{
    DisplayOrientation, FdmSettings, InfillPattern, Origin, PLACEHOLDERS, Profile, ProfileError,
    ProfileErrorKind, ResinSettings, SupportStyle, Technology, TopFillPattern,
};
pub use raster::{GridSpec, LayerImages, PixelGrid, render_layers, render_layers_from};
pub use source::{Layer, Source};

use std::path::PathBuf;

/// Why a mesh cannot be sliced.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshProblem {
    /// No triangles at all.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// A vertex with a coordinate that is not a number.
    #[error("vertex {index} has a coordinate that is not a number: {position:?}")]
    NotFinite {
        /// The vertex's index.
        index: usize,
        /// Its coordinates.
        position: [f32; 3],
    },
    /// A triangle naming a vertex that does not exist.
    #[error("triangle {triangle} refers to a vertex beyond the {vertices} vertices")]
    BadIndex {
        /// The triangle's index.
        triangle: usize,
        /// How many vertices there are.
        vertices: usize,
    },
    /// An edge two triangles run the same way: inconsistent winding, or not manifold.
    #[error(
        "the edge at ({:.3}, {:.3}, {:.3}) is used twice in the same direction: triangles are \
         wound inconsistently or the mesh is not manifold; repair it before slicing",
        at[0], at[1], at[2]
    )]
    NotManifold {
        /// One end of the edge.
        at: [f64; 3],
    },
    /// Edges with a triangle on one side only.
    #[error(
        "the mesh is open: {edges} edges have only one triangle (one near ({:.3}, {:.3}, \
         {:.3})); close the holes before slicing",
        near[0], near[1], near[2]
    )]
    Open {
        /// How many such edges.
        edges: usize,
        /// One end of one of them.
        near: [f64; 3],
    },
    /// Triangles wound clockwise seen from outside.
    #[error(
        "the mesh is inside out (its volume is {volume:.3} mm³: triangles wind clockwise seen \
         from outside); flip its normals before slicing"
    )]
    InsideOut {
        /// The (negative) volume.
        volume: f64,
    },
    /// A closed mesh around nothing.
    #[error("the mesh encloses no volume")]
    NoVolume,
}

/// Slicing failed; each variant carries the facts, and its message says what to fix.
#[derive(Debug, thiserror::Error)]
pub enum SliceError {
    /// A profile value is missing, unknown or out of range.
    #[error(transparent)]
    Profile(#[from] ProfileError),
    /// A mesh that cannot be sliced.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshProblem),
    /// A model with no material inside its region.
    #[error(
        "the model has no material inside its region {min:?} .. {max:?}; check the model \
         (negative is inside) or its region"
    )]
    EmptyRegion {
        /// The region's low corner.
        min: [f64; 3],
        /// The region's high corner.
        max: [f64; 3],
    },
    /// A mesh without vertices.
    #[error("the mesh has no vertices")]
    EmptyMesh,
    /// Every layer came out empty.
    #[error("no layer has any material: the model is empty or too thin to print")]
    NoLayers,
    /// The model (with its skirt) is wider than the bed.
    #[error(
        "the model is {:.1} x {:.1} mm ({:.1} x {:.1} mm with its skirt), larger than the \
         {:.0} x {:.0} mm bed: scale the model down, or set a larger bed_size",
        size[0], size[1], with_skirt[0], with_skirt[1], bed[0], bed[1]
    )]
    LargerThanBed {
        /// The model's footprint, mm.
        size: [f64; 2],
        /// The footprint with the skirt, mm.
        with_skirt: [f64; 2],
        /// The bed, mm.
        bed: [f64; 2],
    },
    /// The model is taller than the printer can print.
    #[error(
        "the model is {height:.1} mm tall, more than the printer's {max_height:.0} mm \
         max_height: scale it down or set max_height"
    )]
    TallerThanPrinter {
        /// The model's height, mm.
        height: f64,
        /// The printable height, mm.
        max_height: f64,
    },
    /// The model reaches the edge of the resin display.
    #[error(
        "the model is larger than the {:.1} x {:.1} mm display (layer {layer} reaches its \
         edge): scale the model down",
        display[0], display[1]
    )]
    LargerThanDisplay {
        /// The display, mm.
        display: [f64; 2],
        /// The first layer that reaches its edge.
        layer: usize,
    },
    /// The layer height would make more layers than one job may have.
    #[error(
        "the model is {height:.1} mm tall: {layers} layers of {layer_height} mm, more than \
         the {max} one job may have; use a larger layer_height"
    )]
    TooManyLayers {
        /// The model's height, mm.
        height: f64,
        /// The layer height, mm.
        layer_height: f64,
        /// The layers it would take.
        layers: usize,
        /// The most allowed.
        max: usize,
    },
    /// The work was cancelled through the cancel flag.
    #[error("cancelled")]
    Cancelled,
    /// Layer images of this size cannot be made.
    #[error(
        "layer images of {width} x {height} pixels of {pixel} mm, {layer_height} mm apart, \
         cannot be made"
    )]
    BadGrid {
        /// Pixels across.
        width: u64,
        /// Pixels down.
        height: u64,
        /// Pixel size, mm.
        pixel: f64,
        /// Layer height, mm.
        layer_height: f64,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Writing an archive or image failed.
    #[error("{what}: {message}")]
    Encode {
        /// What was being written ("SL1 archive", "PNG").
        what: &'static str,
        /// The encoder's message.
        message: String,
    },
}
