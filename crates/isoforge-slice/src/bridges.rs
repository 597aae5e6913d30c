//! The direction to lay a bridge: the one whose lines most often start and end on
//! supported material (anchored on both sides), and among those the one with the
//! shortest lines (the least sag).

use crate::geom::{Region, dist, inside_region};
use crate::infill::hatch_rows;

/// Candidate directions are tried every this many degrees.
const STEP_DEGREES: usize = 5;

/// Probe lines are this many line widths apart: enough lines to judge a direction, few
/// enough to try 36 directions quickly.
const PROBE_SPACING_PER_LINE: f64 = 2.0;

/// The direction (radians, 0 to π) for bridge lines over `area`, given the `anchors`
/// (the supported material under it, grown a little so lines ending on its edge count).
pub fn bridge_angle(area: &Region, anchors: &Region, w: f64) -> f64 {
    let mut best = (f64::NEG_INFINITY, f64::INFINITY, 0.0);
    for k in 0..180 / STEP_DEGREES {
        let angle = (k * STEP_DEGREES) as f64 * std::f64::consts::PI / 180.0;
        let rows = hatch_rows(area, angle, PROBE_SPACING_PER_LINE * w);
        let (mut anchored, mut total, mut lines) = (0.0, 0.0, 0usize);
        for (_, y, segs) in &rows.rows {
            for &(x0, x1) in segs {
                let (a, b) = (rows.to_bed([x0, *y]), rows.to_bed([x1, *y]));
                let len = dist(a, b);
                total += len;
                lines += 1;
                if inside_region(a, anchors) && inside_region(b, anchors) {
                    anchored += len;
                }
            }
        }
        if lines == 0 {
            continue;
        }
        let share = anchored / total;
        let mean = total / lines as f64;
        // More anchored first; equal (to a percent) then shorter.
        let better = share > best.0 + 0.01 || ((share - best.0).abs() <= 0.01 && mean < best.1);
        if better {
            best = (share, mean, angle);
        }
    }
    best.2
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::{region_from_contours, union};

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Region {
        region_from_contours(&[vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
    }

    #[test]
    fn lines_span_from_support_to_support() {
        // A gap 20 mm long in x, 10 mm wide in y, supported at both x ends.
        let area = rect(-12.0, -5.0, 12.0, 5.0);
        let anchors = union(&rect(-15.0, -6.0, -10.0, 6.0), &rect(10.0, -6.0, 15.0, 6.0));
        let a = bridge_angle(&area, &anchors, 0.45);
        assert!(a.sin().abs() < 0.05, "{}", a.to_degrees());
        // Supported along y instead: the lines turn.
        let anchors = union(&rect(-13.0, -8.0, 13.0, -4.0), &rect(-13.0, 4.0, 13.0, 8.0));
        let a = bridge_angle(&area, &anchors, 0.45);
        assert!(a.cos().abs() < 0.05, "{}", a.to_degrees());
    }
}
