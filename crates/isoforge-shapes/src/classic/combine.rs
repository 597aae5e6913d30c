//! The classic combinations of two fields.
//!
//! These are the 2010 modeler's operators, kept exactly: `Blend` and `Combine` are not
//! distance-preserving, and that is part of how the classic models look.

use isoforge_field::Shape;

/// `Union(a, b)` = min(a, b).
pub fn union(a: &Shape, b: &Shape) -> Shape {
    a.min(b)
}

/// `Intersect(a, b)` = max(a, b).
pub fn intersect(a: &Shape, b: &Shape) -> Shape {
    a.max(b)
}

/// `Subtract(a, b)` = max(a, −b): `a` with `b` cut away.
pub fn subtract(a: &Shape, b: &Shape) -> Shape {
    a.max(&-b)
}

/// `Morph(a, b, t)` = (b − a)·t + a: `a` at t = 0, `b` at t = 1.
pub fn morph(a: &Shape, b: &Shape, t: impl Into<Shape>) -> Shape {
    (b - a) * t.into() + a
}

/// `Blend(a, b, l)` = a·b − 1. The 2010 modeler took `l` and did not use it in the formula;
/// it is accepted here for the same reason (scripts pass it).
pub fn blend(a: &Shape, b: &Shape, l: impl Into<Shape>) -> Shape {
    let _unused_as_in_2010 = l.into();
    a * b - 1.0
}

/// `Combine(a, b, k)` = k·(a + b).
pub fn combine(a: &Shape, b: &Shape, k: impl Into<Shape>) -> Shape {
    k.into() * (a + b)
}

/// `Max(a, b)`: the larger field.
pub fn max(a: &Shape, b: &Shape) -> Shape {
    a.max(b)
}

/// `Min(a, b)`: the smaller field.
pub fn min(a: &Shape, b: &Shape) -> Shape {
    a.min(b)
}

/// The union of many shapes as a balanced tree of mins, so that the graph (and every
/// recursive pass over it) is log₂(n) deep rather than n deep. `None` for no shapes.
pub fn union_all(shapes: &[Shape]) -> Option<Shape> {
    match shapes {
        [] => None,
        [one] => Some(one.clone()),
        _ => {
            let (left, right) = shapes.split_at(shapes.len() / 2);
            Some(union(&union_all(left)?, &union_all(right)?))
        }
    }
}
