//! Custom nodes: fields that are not closed-form expressions (an imported mesh, a tube along
//! a sampled curve), given by callbacks so they compose with every other operation.

use inari::Interval;

/// A field given by callbacks. Every callback sees the point (or box) after any transforms
/// that were applied to the shape holding it.
///
/// Contract: `interval` must enclose every value `value` can return for points in the box
/// (NaN aside), or the mesher may drop surface; `interval_gradient` must likewise enclose
/// every gradient `gradient` returns there. `values` must give what `value` gives, point
/// by point.
pub trait CustomField: Send + Sync {
    /// A short name for messages and debugging.
    fn name(&self) -> &str;
    /// The field's value at a point.
    fn value(&self, p: [f64; 3]) -> f64;
    /// An interval enclosing the field's values over a box.
    fn interval(&self, b: [Interval; 3]) -> Interval;
    /// The value and the partial derivatives `[f, df/dx, df/dy, df/dz]` at a point.
    fn gradient(&self, p: [f64; 3]) -> [f64; 4];

    /// Values at many points: `out[i]` is the value at `(xs[i], ys[i], zs[i])`. The batch
    /// evaluator hands a custom node its whole block at once, so a node that searches a
    /// hierarchy can start each search from the last one's answer (neighbouring points
    /// have neighbouring answers). All four slices have the same length.
    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.value([xs[i], ys[i], zs[i]]);
        }
    }

    /// Enclosures of the partial derivatives `[df/dx, df/dy, df/dz]` over a box: what
    /// [`crate::IntervalGradEval`] uses for this node. The default knows nothing
    /// (`ENTIRE`), which is always safe; a distance field can answer `[-1, 1]` each.
    fn interval_gradient(&self, b: [Interval; 3]) -> [Interval; 3] {
        let _ = b;
        [Interval::ENTIRE; 3]
    }

    /// A field equal to this one everywhere in the box `b` and cheaper to evaluate there,
    /// or `None` when there is nothing to gain (the default). The meshers, the slicer and
    /// the renderer narrow a tape to each box they split ([`crate::Tape::narrow`]); a node
    /// that runs a tape of its own (the first-order distance of `offset`) answers with
    /// that tape narrowed to the box, so its points stop paying for far-off parts.
    fn narrow(&self, b: [Interval; 3]) -> Option<std::sync::Arc<dyn CustomField>> {
        let _ = b;
        None
    }
}
