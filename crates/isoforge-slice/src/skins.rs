//! Solid top and bottom skins: the part of a layer's inner region that is not covered by
//! material within `top_layers` above and `bottom_layers` below. Found with polygon
//! booleans on the neighbouring layers' outlines.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;

use crate::geom::Region;

/// `a ∩ b`.
pub fn intersect(a: &Region, b: &Region) -> Region {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    a.overlay(b, OverlayRule::Intersect, FillRule::NonZero)
}

/// `a − b`.
pub fn difference(a: &Region, b: &Region) -> Region {
    if a.is_empty() || b.is_empty() {
        return a.clone();
    }
    a.overlay(b, OverlayRule::Difference, FillRule::NonZero)
}

/// A layer's inner region split into solid skin and sparse interior.
#[derive(Clone, Debug, Default)]
pub struct SkinSplit {
    /// Printed solid (lines one width apart).
    pub solid: Region,
    /// Printed with sparse infill.
    pub sparse: Region,
}

/// Splits `inner` (layer `i`'s region inside its perimeters) by what `outlines` (every
/// layer's full region) hold within `top` layers above and `bottom` below. Beyond the
/// first or last layer there is nothing, so those layers come out solid.
pub fn split_skins(
    i: usize,
    inner: &Region,
    outlines: &[Region],
    top: usize,
    bottom: usize,
) -> SkinSplit {
    if inner.is_empty() {
        return SkinSplit::default();
    }
    // Material over and under this layer everywhere in `covered`.
    let mut covered = inner.clone();
    let mut neighbours = (1..=top)
        .map(|k| i.checked_add(k))
        .chain((1..=bottom).map(|k| i.checked_sub(k)));
    for n in neighbours.by_ref() {
        let Some(r) = n.and_then(|n| outlines.get(n)) else {
            covered.clear();
            break;
        };
        covered = intersect(&covered, r);
        if covered.is_empty() {
            break;
        }
    }
    SkinSplit {
        solid: difference(inner, &covered),
        sparse: covered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::region_area;
    use crate::perimeters::region_from_contours;

    fn square(s: f64) -> Region {
        let h = s / 2.0;
        region_from_contours(&[vec![[-h, -h], [h, -h], [h, h], [-h, h]]])
    }

    #[test]
    fn a_pyramid_has_skin_where_the_layer_above_is_smaller() {
        // Layers shrinking upward: 10, 8, 6, 4, 2 mm squares.
        let outlines: Vec<Region> = [10.0, 8.0, 6.0, 4.0, 2.0].into_iter().map(square).collect();
        let s = split_skins(1, &outlines[1], &outlines, 1, 1);
        // Covered above by the 6 mm square, below by the 10 mm one.
        assert!((region_area(&s.sparse) - 36.0).abs() < 1e-6);
        assert!((region_area(&s.solid) - (64.0 - 36.0)).abs() < 1e-6);
        // The first and last layers are all skin.
        let s = split_skins(0, &outlines[0], &outlines, 1, 1);
        assert!(s.sparse.is_empty());
        let s = split_skins(4, &outlines[4], &outlines, 1, 1);
        assert!((region_area(&s.solid) - 4.0).abs() < 1e-6);
    }
}
