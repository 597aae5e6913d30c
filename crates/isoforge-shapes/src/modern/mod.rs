//! The modern library: exact signed-distance primitives, transforms that keep distances,
//! booleans and smooth blends, and `offset`/`shell` that work on any field.
//!
//! Names follow `docs/library-modern.md`. Lengths are millimetres, angles degrees.
//! "Exact" means the field's value is the signed Euclidean distance to the surface
//! (negative inside); such fields have a gradient of length 1 wherever it is defined,
//! and offsets and shells of them are exact.

mod booleans;
mod distance;
mod primitives;
mod transforms;

pub use booleans::{
    difference, difference_all, intersection, intersection_all, smooth_difference,
    smooth_intersection, smooth_union, union, union_all,
};
pub use distance::{
    FirstOrderDistance, first_order_distance, offset, offset_exact, shell, shell_exact,
};
pub use primitives::{
    box3, capsule, cone, cylinder, ellipsoid, gyroid, half_space, length2, length3, sphere, torus,
};
pub use transforms::{
    mirror_x, mirror_y, mirror_z, move_by, rotate, rotate_x, rotate_y, rotate_z, scale,
    scale_uniform, twist,
};

/// A parameter a modern-library function cannot build with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModernError {
    /// A size that must be positive is not.
    #[error("{what} must be a positive number, not {value}")]
    NotPositive {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A number that must be finite is not.
    #[error("{what} must be a finite number, not {value}")]
    NotFinite {
        /// Which parameter.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A direction of length zero.
    #[error("{what} must not be the zero vector")]
    ZeroVector {
        /// Which parameter.
        what: &'static str,
    },
}

pub(crate) fn positive(what: &'static str, value: f64) -> Result<f64, ModernError> {
    if !value.is_finite() {
        Err(ModernError::NotFinite { what, value })
    } else if value <= 0.0 {
        Err(ModernError::NotPositive { what, value })
    } else {
        Ok(value)
    }
}

pub(crate) fn finite(what: &'static str, value: f64) -> Result<f64, ModernError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ModernError::NotFinite { what, value })
    }
}

pub(crate) fn finite3(what: &'static str, v: [f64; 3]) -> Result<[f64; 3], ModernError> {
    for c in v {
        finite(what, c)?;
    }
    Ok(v)
}

#[cfg(test)]
mod tests;
