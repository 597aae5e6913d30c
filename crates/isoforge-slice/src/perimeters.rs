//! Perimeters: loops inset from a layer's outline by polygon offsetting (i_overlay), and
//! the region left inside them for skins and infill.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::float::simplify::SimplifyShape;
use i_overlay::mesh::float::outline::offset::OutlineOffset;
use i_overlay::mesh::float::style::{LineJoin, OutlineStyle};

use crate::geom::{Contour, Region, region_area};

/// Mitre corners down to this interior angle; sharper ones are clipped, which keeps a
/// knife-edge corner from shooting a spike out of the part.
const MITER_MIN_ANGLE: f64 = std::f64::consts::PI / 8.0;

/// The region enclosed by oriented contours (outer counter-clockwise, holes clockwise);
/// overlapping or touching pieces are merged.
pub fn region_from_contours(contours: &[Contour]) -> Region {
    if contours.is_empty() {
        return Vec::new();
    }
    contours.to_vec().simplify_shape(FillRule::NonZero)
}

/// The region grown (positive `d`) or shrunk (negative `d`) by `d` mm.
pub fn offset(region: &Region, d: f64) -> Region {
    if region.is_empty() {
        return Vec::new();
    }
    if d == 0.0 {
        return region.clone();
    }
    let style = OutlineStyle::new(d).line_join(LineJoin::Miter(MITER_MIN_ANGLE));
    region.outline(&style)
}

/// One island's perimeters: `loops[0]` is the outermost (printed last).
#[derive(Clone, Debug, Default)]
pub struct Perimeters {
    /// Loops from the outside in; each entry holds the contours of one inset (the inset
    /// of the outer boundary, counter-clockwise, and of each hole, clockwise).
    pub loops: Vec<Vec<Contour>>,
    /// What is left inside the innermost loop, for skins and infill.
    pub inner: Region,
}

/// Insets a layer region into `count` perimeter loops of width `w`: loop k runs along the
/// inset at `w/2 + k·w`, so loop 0 just touches the outline. Insets that vanish (a thin
/// wall) stop the sequence.
pub fn perimeters(region: &Region, count: usize, w: f64) -> Perimeters {
    let mut out = Perimeters::default();
    for k in 0..count {
        let inset = offset(region, -(w * 0.5 + k as f64 * w));
        if inset.is_empty() || region_area(&inset) <= 0.0 {
            return out;
        }
        out.loops.push(inset.into_iter().flatten().collect());
    }
    out.inner = offset(region, -(count as f64 * w));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{path_length, signed_area};

    fn square(s: f64) -> Contour {
        vec![[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]]
    }

    #[test]
    fn square_insets_by_half_a_width_then_whole_widths() {
        let r = region_from_contours(&[square(10.0)]);
        let p = perimeters(&r, 2, 0.5);
        assert_eq!(p.loops.len(), 2);
        let l0: f64 = p.loops[0].iter().map(|c| path_length(c, true)).sum();
        assert!((l0 - 4.0 * 9.5).abs() < 1e-3, "{l0}");
        let l1: f64 = p.loops[1].iter().map(|c| path_length(c, true)).sum();
        assert!((l1 - 4.0 * 8.5).abs() < 1e-3, "{l1}");
        assert!((region_area(&p.inner) - 64.0).abs() < 1e-3);
    }

    #[test]
    fn holes_stay_clockwise_and_grow() {
        let hole: Contour = vec![[4.0, 4.0], [4.0, 6.0], [6.0, 6.0], [6.0, 4.0]];
        let r = region_from_contours(&[square(10.0), hole]);
        assert!((region_area(&r) - 96.0).abs() < 1e-6);
        let p = perimeters(&r, 1, 0.5);
        let holes: Vec<&Contour> = p.loops[0].iter().filter(|c| signed_area(c) < 0.0).collect();
        assert_eq!(holes.len(), 1);
        assert!((signed_area(holes[0]) + 2.5 * 2.5).abs() < 1e-3);
    }

    #[test]
    fn thin_wall_gets_fewer_loops() {
        let r = region_from_contours(&[vec![[0.0, 0.0], [10.0, 0.0], [10.0, 0.8], [0.0, 0.8]]]);
        let p = perimeters(&r, 3, 0.45);
        assert!(p.loops.len() < 3);
        assert!(p.inner.is_empty());
    }
}
