//! What holds the first layer down and primes the nozzle: the skirt (loops at a distance),
//! the brim (loops touching the part's outside) and the raft (layers under the part).

use crate::clip::{offset, region_from_contours};
use crate::geom::{Contour, Region, signed_area};

/// The raft reaches this far beyond the part, mm (PrusaSlicer's raft expansion is 1.5).
pub const RAFT_MARGIN: f64 = 1.5;

/// The raft's base lines are this many line widths apart (coarse, to grip the bed);
/// its top layer is solid.
pub const RAFT_BASE_SPACING_PER_LINE: f64 = 2.0;

/// The outer contours of a region, without holes: a brim goes around the outside only.
fn outsides(region: &Region) -> Region {
    let outer: Vec<Contour> = region
        .iter()
        .filter_map(|s| s.first())
        .filter(|c| signed_area(c) > 0.0)
        .cloned()
        .collect();
    region_from_contours(&outer)
}

/// Brim loops around the first layer's outside, `width` mm wide, from the outermost in
/// (the last one printed touches the part). Each loop is one contour per piece.
pub fn brim(first: &Region, width: f64, w: f64) -> Vec<Contour> {
    if width <= 0.0 || first.is_empty() {
        return Vec::new();
    }
    let base = outsides(first);
    let loops = (width / w).round().max(1.0) as usize;
    (0..loops)
        .rev()
        .flat_map(|k| {
            offset(&base, w * (0.5 + k as f64))
                .into_iter()
                .filter_map(|shape| shape.into_iter().next())
        })
        .collect()
}

/// Skirt loops `distance` mm outside `around` (the first layer with its brim), from the
/// outermost in.
pub fn skirt(around: &Region, loops: usize, distance: f64, w: f64) -> Vec<Contour> {
    if loops == 0 || around.is_empty() {
        return Vec::new();
    }
    let base = outsides(around);
    (0..loops)
        .rev()
        .flat_map(|k| {
            offset(&base, distance + w * (0.5 + k as f64))
                .into_iter()
                .filter_map(|shape| shape.into_iter().next())
        })
        .collect()
}

/// The raft's area: the first layer (and its support) grown by [`RAFT_MARGIN`], holes
/// filled.
pub fn raft_area(first: &Region) -> Region {
    offset(&outsides(first), RAFT_MARGIN)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{path_length, region_area};

    fn square(a: f64, b: f64) -> Contour {
        vec![[a, a], [b, a], [b, b], [a, b]]
    }

    #[test]
    fn a_brim_goes_around_the_outside_only() {
        let hole: Contour = square(4.0, 6.0).into_iter().rev().collect();
        let r = region_from_contours(&[square(0.0, 10.0), hole]);
        let b = brim(&r, 2.0, 0.5);
        assert_eq!(b.len(), 4);
        // The last loop touches the part: half a line out.
        assert!((path_length(&b[3], true) - 4.0 * 10.5).abs() < 1e-6);
        assert!((path_length(&b[0], true) - 4.0 * 13.5).abs() < 1e-6);
        assert!(b.iter().all(|c| signed_area(c) > 0.0));
    }

    #[test]
    fn the_raft_covers_the_part_and_its_holes() {
        let hole: Contour = square(4.0, 6.0).into_iter().rev().collect();
        let r = region_from_contours(&[square(0.0, 10.0), hole]);
        let a = region_area(&raft_area(&r));
        assert!((a - 13.0 * 13.0).abs() < 1e-3, "{a}");
    }
}
