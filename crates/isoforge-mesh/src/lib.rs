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

pub mod check;
pub mod dc;
pub mod io;
pub mod mesh;
pub mod samples;

pub use check::{MeshReport, check};
pub use dc::{MeshError, MeshSettings, mesh_shape, try_mesh_shape};
pub use io::{MeshFormat, MeshIoError, read_mesh, write_mesh};
pub use mesh::Mesh;
