//! Infill lines: rectilinear hatching (solid skins, `rectilinear` and `grid` infill) and the
//! gyroid's cross-section (`gyroid` infill), clipped to a region.
//!
//! Hatch lines sit on a grid anchored at the origin, so lines of successive layers with the
//! same angle stack on each other.

use i_overlay::core::fill_rule::FillRule;
use i_overlay::float::clip::FloatClip;
use i_overlay::string::clip::ClipRule;

use crate::geom::{Point, Region, dist};
use crate::outline::march::{cell_segments, chain, edge_corners};

/// Clipped pieces shorter than this (mm) are dropped: they would only dab the nozzle.
const MIN_PIECE: f64 = 0.05;

/// The gyroid's cross-section line length per unit area is about 2.43 / period (its area
/// per volume, 3.09 / period, times π/4 for a plane section); `infill::tests` measures it.
const GYROID_LENGTH_PER_AREA: f64 = 2.43;

/// Parallel lines `spacing` mm apart at `angle` radians, clipped to `region` (even-odd
/// scanlines over all its contours, so holes are skipped).
pub fn hatch(region: &Region, angle: f64, spacing: f64) -> Vec<Vec<Point>> {
    if region.is_empty() || spacing.is_nan() || spacing <= 0.0 || !spacing.is_finite() {
        return Vec::new();
    }
    let (s, c) = angle.sin_cos();
    // Rotate by -angle so the lines are horizontal.
    let rot = |p: &Point| [c * p[0] + s * p[1], -s * p[0] + c * p[1]];
    let unrot = |p: Point| [c * p[0] - s * p[1], s * p[0] + c * p[1]];
    let mut edges: Vec<(Point, Point)> = Vec::new();
    let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
    for contour in region.iter().flatten() {
        let pts: Vec<Point> = contour.iter().map(rot).collect();
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            ymin = ymin.min(a[1]);
            ymax = ymax.max(a[1]);
            if a[1] != b[1] {
                edges.push(if a[1] < b[1] { (a, b) } else { (b, a) });
            }
        }
    }
    if edges.is_empty() {
        return Vec::new();
    }
    edges.sort_by(|a, b| a.0[1].total_cmp(&b.0[1]));
    let first = (ymin / spacing).floor() as i64;
    let last = (ymax / spacing).ceil() as i64;
    let mut lines = Vec::new();
    let mut xs: Vec<f64> = Vec::new();
    for k in first..=last {
        // Half a spacing off the grid line: a scanline through a vertex is then rare,
        // and the lines' centres sit symmetrically inside the region.
        let y = (k as f64 + 0.5) * spacing;
        xs.clear();
        let end = edges.partition_point(|e| e.0[1] <= y);
        for (a, b) in &edges[..end] {
            if b[1] > y {
                xs.push(a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
            }
        }
        xs.sort_by(f64::total_cmp);
        for pair in xs.chunks_exact(2) {
            if pair[1] - pair[0] >= MIN_PIECE {
                lines.push(vec![unrot([pair[0], y]), unrot([pair[1], y])]);
            }
        }
    }
    lines
}

/// The gyroid period (mm) that lays `density` of the area with lines `w` wide.
pub fn gyroid_period(density: f64, w: f64) -> f64 {
    GYROID_LENGTH_PER_AREA * w / density
}

/// The gyroid's section sin x cos y + sin y cos z + sin z cos x = 0 at height `z`, scaled
/// to `period` mm, traced over the region's box by marching squares and clipped to it.
pub fn gyroid(region: &Region, z: f64, period: f64) -> Vec<Vec<Point>> {
    let Some((lo, hi)) = crate::geom::bbox(region.iter().flatten().flatten()) else {
        return Vec::new();
    };
    if period.is_nan() || period <= 0.0 || !period.is_finite() {
        return Vec::new();
    }
    let k = std::f64::consts::TAU / period;
    let (sz, cz) = (k * z).sin_cos();
    let f = |x: f64, y: f64| {
        let (sx, cx) = (k * x).sin_cos();
        let (sy, cy) = (k * y).sin_cos();
        sx * cy + sy * cz + sz * cx
    };
    // 24 cells per period keep the traced curve within ~0.3% of the period.
    let h = period / 24.0;
    let (i0, j0) = (
        (lo[0] / h).floor() as i32 - 1,
        (lo[1] / h).floor() as i32 - 1,
    );
    let (i1, j1) = ((hi[0] / h).ceil() as i32 + 1, (hi[1] / h).ceil() as i32 + 1);
    if (i1 - i0) as i64 * (j1 - j0) as i64 > 50_000_000 {
        return Vec::new();
    }
    let nx = (i1 - i0 + 1) as usize;
    let vals: Vec<f64> = (j0..=j1)
        .flat_map(|j| (i0..=i1).map(move |i| (i, j)))
        .map(|(i, j)| f(i as f64 * h, j as f64 * h))
        .collect();
    let v = |i: i32, j: i32| vals[(j - j0) as usize * nx + (i - i0) as usize];
    let mut segs = Vec::new();
    for j in j0..j1 {
        for i in i0..i1 {
            let c = [v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)].map(|x| x < 0.0);
            let center = || f((i as f64 + 0.5) * h, (j as f64 + 0.5) * h) < 0.0;
            cell_segments(i, j, c, center, &mut segs);
        }
    }
    let point = |e| {
        let [a, b] = edge_corners(e);
        let (fa, fb) = (v(a.0, a.1), v(b.0, b.1));
        let t = fa / (fa - fb);
        let (pa, pb) = (
            [a.0 as f64 * h, a.1 as f64 * h],
            [b.0 as f64 * h, b.1 as f64 * h],
        );
        [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
    };
    let lines: Vec<Vec<Point>> = chain(&segs)
        .into_iter()
        .map(|c| {
            let mut pts: Vec<Point> = c.edges.into_iter().map(point).collect();
            if c.closed
                && let Some(&p) = pts.first()
            {
                pts.push(p);
            }
            pts
        })
        .filter(|p| p.len() >= 2)
        .collect();
    clip(&lines, region)
}

/// Clips polylines to a region.
pub fn clip(lines: &[Vec<Point>], region: &Region) -> Vec<Vec<Point>> {
    if lines.is_empty() || region.is_empty() {
        return Vec::new();
    }
    let rule = ClipRule {
        invert: false,
        boundary_included: false,
    };
    lines
        .to_vec()
        .clip_by(region, FillRule::NonZero, rule)
        .into_iter()
        .filter(|p| {
            p.len() >= 2 && p.windows(2).map(|w| dist(w[0], w[1])).sum::<f64>() >= MIN_PIECE
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::path_length;
    use crate::perimeters::region_from_contours;

    fn square(s: f64) -> Region {
        region_from_contours(&[vec![[0.0, 0.0], [s, 0.0], [s, s], [0.0, s]]])
    }

    #[test]
    fn hatch_covers_the_area_at_its_spacing() {
        let r = square(20.0);
        for angle in [0.0, 0.3, std::f64::consts::FRAC_PI_4, 2.0] {
            let lines = hatch(&r, angle, 0.5);
            let len: f64 = lines.iter().map(|l| path_length(l, false)).sum();
            // length x spacing = area, within the ragged ends.
            assert!(
                (len * 0.5 - 400.0).abs() < 8.0,
                "angle {angle}: {}",
                len * 0.5
            );
        }
    }

    #[test]
    fn hatch_skips_holes() {
        let hole = vec![[5.0, 5.0], [5.0, 15.0], [15.0, 15.0], [15.0, 5.0]];
        let outer = vec![[0.0, 0.0], [20.0, 0.0], [20.0, 20.0], [0.0, 20.0]];
        let r = region_from_contours(&[outer, hole]);
        let lines = hatch(&r, 0.0, 0.5);
        let len: f64 = lines.iter().map(|l| path_length(l, false)).sum();
        assert!((len * 0.5 - 300.0).abs() < 1.0, "{}", len * 0.5);
        for l in &lines {
            let m = [(l[0][0] + l[1][0]) / 2.0, (l[0][1] + l[1][1]) / 2.0];
            assert!(!(m[0] > 5.0 && m[0] < 15.0 && m[1] > 5.0 && m[1] < 15.0));
        }
    }

    #[test]
    fn gyroid_density_matches_its_setting() {
        let r = square(60.0);
        for density in [0.1, 0.2, 0.4] {
            let w = 0.45;
            let mut total = 0.0;
            let zs = [0.0, 0.7, 1.9, 3.3];
            for z in zs {
                let lines = gyroid(&r, z, gyroid_period(density, w));
                total += lines.iter().map(|l| path_length(l, false)).sum::<f64>();
            }
            let got = total / zs.len() as f64 * w / 3600.0;
            assert!(
                (got / density - 1.0).abs() < 0.12,
                "density {density}: {got}"
            );
        }
    }

    #[test]
    fn clipped_gyroid_stays_inside() {
        let r = square(10.0);
        for l in gyroid(&r, 1.0, 3.0) {
            for p in l {
                assert!(
                    p[0] >= -1e-6 && p[0] <= 10.0 + 1e-6 && p[1] >= -1e-6 && p[1] <= 10.0 + 1e-6
                );
            }
        }
    }
}
