//! The isoforge shape library: the classic function-based primitives, transforms and
//! combinations, and curve followers, all built as [`isoforge_field::Shape`] graphs.
//!
//! Plain Rust, usable without scripts; the model scripts of `isoforge-script` are thin
//! bindings over this crate.
//!
//! ```
//! use isoforge_shapes::classic::{intersect, rotate_y, sphere, trans_z, drope};
//! use isoforge_shapes::curve::curve_fol_sphere;
//! // The drope block's first steps, and a ring of seven balls.
//! let top = trans_z(&drope(4.0), 2.5);
//! let block = intersect(&top, &rotate_y(&top, 90.0));
//! let ball = sphere(4.0);
//! let model = intersect(&block, &ball);
//! let ring = curve_fol_sphere(|t| [4.0 * t.sin(), 4.0 * t.cos(), 0.0], 7,
//!                             [0.0, std::f64::consts::TAU], 2.0).unwrap();
//! # let _ = (model, ring);
//! ```

pub mod bound;
pub mod bvh;
pub mod classic;
pub mod curve;
pub mod evals;
pub mod frame;
pub mod functions;
pub mod hull;
pub mod mesh_field;
pub mod metaballs;
pub mod modern;
pub mod probe;
pub mod profile;
pub mod surface;
pub mod sweep;
pub mod texture;
pub mod tube;

#[cfg(test)]
mod reference;
