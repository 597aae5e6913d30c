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

/// One hatch row: its index, its y and the x intervals inside the region.
pub type Row = (i64, f64, Vec<(f64, f64)>);

/// Hatch lines in the frame where they run along x: row `k` at height `(k + 0.5)·spacing`
/// holds the x intervals inside the region, left to right.
#[derive(Clone, Debug, Default)]
pub struct Rows {
    /// The lines' angle, radians.
    pub angle: f64,
    /// Distance between rows, mm.
    pub spacing: f64,
    /// (row index, y, intervals) from the lowest row up; empty rows left out.
    pub rows: Vec<Row>,
}

impl Rows {
    /// A point of the rotated frame in bed coordinates.
    pub fn to_bed(&self, p: Point) -> Point {
        let (s, c) = self.angle.sin_cos();
        [c * p[0] - s * p[1], s * p[0] + c * p[1]]
    }

    /// A bed point in the rotated frame.
    pub fn to_rows(&self, p: Point) -> Point {
        let (s, c) = self.angle.sin_cos();
        [c * p[0] + s * p[1], -s * p[0] + c * p[1]]
    }

    /// Every interval as a two-point line in bed coordinates.
    pub fn lines(&self) -> Vec<Vec<Point>> {
        self.rows
            .iter()
            .flat_map(|(_, y, xs)| {
                xs.iter()
                    .map(move |&(a, b)| vec![self.to_bed([a, *y]), self.to_bed([b, *y])])
            })
            .collect()
    }
}

/// The hatch rows of `region` at `angle` radians, `spacing` mm apart (even-odd scanlines
/// over all its contours, so holes are skipped). Rows sit on a grid anchored at the origin,
/// so lines of successive layers at the same angle stack.
pub fn hatch_rows(region: &Region, angle: f64, spacing: f64) -> Rows {
    let mut out = Rows {
        angle,
        spacing,
        rows: Vec::new(),
    };
    if region.is_empty() || spacing.is_nan() || spacing <= 0.0 || !spacing.is_finite() {
        return out;
    }
    let mut edges: Vec<(Point, Point)> = Vec::new();
    let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
    for contour in region.iter().flatten() {
        let pts: Vec<Point> = contour.iter().map(|p| out.to_rows(*p)).collect();
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            ymin = ymin.min(a[1]);
            ymax = ymax.max(a[1]);
            if a[1] != b[1] {
                edges.push(if a[1] < b[1] { (a, b) } else { (b, a) });
            }
        }
    }
    if edges.is_empty() || (ymax - ymin) / spacing > 1e7 {
        return out;
    }
    edges.sort_by(|a, b| a.0[1].total_cmp(&b.0[1]));
    let first = (ymin / spacing).floor() as i64;
    let last = (ymax / spacing).ceil() as i64;
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
        let segs: Vec<(f64, f64)> = xs
            .chunks_exact(2)
            .filter(|p| p[1] - p[0] >= MIN_PIECE)
            .map(|p| (p[0], p[1]))
            .collect();
        if !segs.is_empty() {
            out.rows.push((k, y, segs));
        }
    }
    out
}

/// Parallel lines `spacing` mm apart at `angle` radians, clipped to `region`.
#[cfg(test)]
pub fn hatch(region: &Region, angle: f64, spacing: f64) -> Vec<Vec<Point>> {
    hatch_rows(region, angle, spacing).lines()
}

/// How hatch lines are strung together.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Lay {
    /// Each line on its own.
    Separate,
    /// Neighbouring lines joined end to end (a zigzag) where the join is short and inside
    /// the region: one extrusion instead of many, no travel between them.
    Connected,
    /// Joined as `Connected`, and every line printed only after the lines below it that it
    /// touches: one sweep across the surface, so no line ever lands between two cooled
    /// ones (no seam lines on top surfaces).
    Monotonic,
}

/// Joins longer than this many row spacings are not made (the boundary runs nearly along
/// the lines there, and the join would lay a long line on the perimeter).
const MAX_JOIN_PER_SPACING: f64 = 1.5;

/// A join point this close to the region's edge is on it, mm.
const JOIN_EDGE_TOLERANCE: f64 = 1e-3;

/// Strings the rows into polylines, starting near `pos` (bed coordinates).
pub fn lay_rows(rows: &Rows, region: &Region, lay: Lay, pos: Point) -> Vec<Vec<Point>> {
    if lay == Lay::Separate {
        return rows.lines();
    }
    // Segments by row: (row position in `rows`, x0, x1); used flags alongside.
    let mut used: Vec<Vec<bool>> = rows.rows.iter().map(|r| vec![false; r.2.len()]).collect();
    let total: usize = used.iter().map(Vec::len).sum();
    let max_join = MAX_JOIN_PER_SPACING * rows.spacing;
    let overlaps = |a: (f64, f64), b: (f64, f64)| a.0 < b.1 && b.0 < a.1;
    // Monotonic: a segment may be printed once every segment of the row below (the
    // previous row index) that overlaps it is printed.
    let ready = |used: &Vec<Vec<bool>>, r: usize, i: usize| -> bool {
        if lay != Lay::Monotonic || r == 0 {
            return true;
        }
        let (k, _, segs) = &rows.rows[r];
        let (kb, _, below) = &rows.rows[r - 1];
        if kb + 1 != *k {
            return true;
        }
        below
            .iter()
            .enumerate()
            .all(|(j, b)| used[r - 1][j] || !overlaps(*b, segs[i]))
    };
    // A join runs along the region's edge (both its ends are on it): a point on the edge
    // counts as inside.
    let contours: Vec<crate::geom::Contour> = region.iter().flatten().cloned().collect();
    let inside = |a: Point, b: Point| -> bool {
        [0.25, 0.5, 0.75].iter().all(|t| {
            let p = rows.to_bed([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            crate::geom::inside_region(p, region)
                || crate::geom::distance_to_contours(p, &contours) < JOIN_EDGE_TOLERANCE
        })
    };
    let mut here = rows.to_rows(pos);
    let mut out = Vec::new();
    let mut done = 0;
    while done < total {
        // The nearest ready segment end.
        let mut best: Option<(f64, usize, usize, bool)> = None;
        for (r, (_, y, segs)) in rows.rows.iter().enumerate() {
            for (i, &(x0, x1)) in segs.iter().enumerate() {
                if used[r][i] || !ready(&used, r, i) {
                    continue;
                }
                for (x, from_right) in [(x0, false), (x1, true)] {
                    let d = dist(here, [x, *y]);
                    if best.is_none_or(|b| d < b.0) {
                        best = Some((d, r, i, from_right));
                    }
                }
            }
        }
        let Some((_, mut r, mut i, mut from_right)) = best else {
            break;
        };
        let mut line: Vec<Point> = Vec::new();
        loop {
            used[r][i] = true;
            done += 1;
            let (_, y, segs) = &rows.rows[r];
            let (x0, x1) = segs[i];
            let (a, b) = if from_right { (x1, x0) } else { (x0, x1) };
            line.push([a, *y]);
            line.push([b, *y]);
            here = [b, *y];
            // Join to the next row up (monotonic sweeps upward only), or down.
            let mut next = None;
            let candidates: &[usize] = if lay == Lay::Monotonic {
                &[1]
            } else {
                &[1, usize::MAX]
            };
            for &step in candidates {
                let nr = if step == 1 { r + 1 } else { r.wrapping_sub(1) };
                let Some((nk, ny, nsegs)) = rows.rows.get(nr) else {
                    continue;
                };
                let k = rows.rows[r].0;
                if (nk - k).abs() != 1 {
                    continue;
                }
                // The end on the same side as where this line ended.
                let ended_right = !from_right;
                let pick = nsegs
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| !used[nr][j])
                    .map(|(j, s)| (j, if ended_right { s.1 } else { s.0 }))
                    .min_by(|x, y| (x.1 - b).abs().total_cmp(&(y.1 - b).abs()));
                if let Some((j, xe)) = pick {
                    let to = [xe, *ny];
                    if dist(here, to) <= max_join && ready(&used, nr, j) && inside(here, to) {
                        next = Some((nr, j, ended_right));
                        break;
                    }
                }
            }
            match next {
                Some((nr, j, fr)) => {
                    r = nr;
                    i = j;
                    from_right = fr;
                }
                None => break,
            }
        }
        out.push(line.into_iter().map(|p| rows.to_bed(p)).collect());
    }
    out
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
    use crate::clip::region_from_contours;
    use crate::geom::path_length;

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
