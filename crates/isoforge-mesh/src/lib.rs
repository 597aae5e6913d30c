//! Meshing for isoforge: an interval-pruned octree over a field, dual contouring into a
//! closed, manifold, consistently oriented triangle mesh, a mesh checker, mesh readers and
//! writers (STL, OBJ, PLY, 3MF). (Preview pictures are `isoforge-render`'s, which needs
//! no mesh.)
//!
//! The main call, field to checked mesh:
//! ```no_run
//! use isoforge_field::{Bounds, Shape};
//! use isoforge_mesh::{mesh_shape, check, MeshSettings};
//! let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
//! let sphere = x.square() + y.square() + z.square() - 1.0;
//! let bounds = Bounds::new([-1.5; 3], [1.5; 3]).unwrap();
//! let mesh = mesh_shape(&sphere, &MeshSettings::new(bounds, 6));
//! assert!(check(&mesh).is_closed_manifold());
//! ```
//!
//! The data flow: shape → `isoforge_field::ClippedField` (the model clipped to
//! `MeshSettings::bounds`) → the dual-contouring stages in `dc/` (octree, hermite data,
//! cells and QEF vertices, contour; see `dc/mod.rs`) → [`Mesh`] → [`check`](fn@check) and [`io`].
//! Only the mesh type, the settings, `mesh_shape`/`try_mesh_shape`, the checker, the
//! readers and writers, and sample meshes ([`samples`]) are public: the mesher's stages
//! are internal, tested in the crate.

mod check;
mod dc;
mod deviation;
mod int_hash;
pub mod io;
mod mesh;
pub mod samples;
pub mod sink;

pub use check::{MeshReport, StreamCheck, StreamReport, check};
pub use dc::{
    DEFAULT_TOLERANCE_CELLS, Estimate, MAX_DEPTH, MAX_REFINE_LEVELS, MeshError, MeshNotes,
    MeshSettings, Progress, Refinement, estimate, estimate_bound, mesh_shape, mesh_shape_into,
    try_mesh_shape,
};
pub use deviation::{
    Deviation, DeviationSink, beyond, deviation, deviation_beyond, deviation_where_wide, farthest,
};
pub use io::{MeshFormat, MeshIoError, read_mesh, write_mesh};
pub use mesh::Mesh;
pub use sink::{MeshSink, Tally};
