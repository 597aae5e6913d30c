//! Custom nodes: fields that are not closed-form expressions (an imported mesh, a tube along
//! a sampled curve), given by callbacks so they compose with every other operation.

use inari::Interval;

/// A field given by callbacks. Every callback sees the point (or box) after any transforms
/// that were applied to the shape holding it.
///
/// Contract: `interval` must enclose every value `value` can return for points in the box
/// (NaN aside), or the mesher may drop surface.
pub trait CustomField: Send + Sync {
    /// A short name for messages and debugging.
    fn name(&self) -> &str;
    /// The field's value at a point.
    fn value(&self, p: [f64; 3]) -> f64;
    /// An interval enclosing the field's values over a box.
    fn interval(&self, b: [Interval; 3]) -> Interval;
    /// The value and the partial derivatives `[f, df/dx, df/dy, df/dz]` at a point.
    fn gradient(&self, p: [f64; 3]) -> [f64; 4];
}
