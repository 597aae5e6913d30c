//! Booleans and smooth blends. The arithmetic operators stay arithmetic; these are the
//! named set operations.
//!
//! `union`, `intersection` and `difference` are min, max and max(a, −b): of exact
//! distances they give the exact distance outside (union) or a bound of it. The smooth
//! versions are the quadratic polynomial blend (Quilez): within `k` of the crease the
//! minimum is lowered by `max(k − |a − b|, 0)² / (4k)`, which is continuous with a
//! continuous slope, reaches `k/4` at the crease and nothing beyond `k` from it.

use isoforge_field::Shape;

use super::{ModernError, positive};

/// `union(a, b)`: inside either.
pub fn union(a: &Shape, b: &Shape) -> Shape {
    a.min(b)
}

/// `intersection(a, b)`: inside both.
pub fn intersection(a: &Shape, b: &Shape) -> Shape {
    a.max(b)
}

/// `difference(a, b)`: inside `a` and outside `b`.
pub fn difference(a: &Shape, b: &Shape) -> Shape {
    a.max(&-b)
}

/// Combines many shapes as a balanced tree, so the graph is log₂(n) deep.
fn balanced(shapes: &[Shape], op: fn(&Shape, &Shape) -> Shape) -> Option<Shape> {
    match shapes {
        [] => None,
        [one] => Some(one.clone()),
        _ => {
            let (l, r) = shapes.split_at(shapes.len() / 2);
            Some(op(&balanced(l, op)?, &balanced(r, op)?))
        }
    }
}

/// `union([..])`; `None` for no shapes.
pub fn union_all(shapes: &[Shape]) -> Option<Shape> {
    balanced(shapes, union)
}

/// `intersection([..])`; `None` for no shapes.
pub fn intersection_all(shapes: &[Shape]) -> Option<Shape> {
    balanced(shapes, intersection)
}

/// `difference([a, b, c, ..])`: `a` with all the others cut away; `None` for no shapes.
pub fn difference_all(shapes: &[Shape]) -> Option<Shape> {
    let (first, rest) = shapes.split_first()?;
    Some(match union_all(rest) {
        Some(cut) => difference(first, &cut),
        None => first.clone(),
    })
}

/// The blend term `max(k − |a − b|, 0)² / (4k)`.
fn blend(a: &Shape, b: &Shape, k: f64) -> Shape {
    let h = Shape::constant(0.0).max(&(k - (a - b).abs()));
    h.square() / (4.0 * k)
}

/// `smooth_union(a, b, k)`: the union with the crease rounded over a width of about `k`.
pub fn smooth_union(a: &Shape, b: &Shape, k: f64) -> Result<Shape, ModernError> {
    let k = positive("the blend width k", k)?;
    Ok(a.min(b) - blend(a, b, k))
}

/// `smooth_intersection(a, b, k)`: the intersection with its edge rounded.
pub fn smooth_intersection(a: &Shape, b: &Shape, k: f64) -> Result<Shape, ModernError> {
    let k = positive("the blend width k", k)?;
    Ok(a.max(b) + blend(a, b, k))
}

/// `smooth_difference(a, b, k)`: `a` minus `b` with the cut's edge rounded.
pub fn smooth_difference(a: &Shape, b: &Shape, k: f64) -> Result<Shape, ModernError> {
    smooth_intersection(a, &-b, k)
}
