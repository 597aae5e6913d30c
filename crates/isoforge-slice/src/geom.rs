//! Plane geometry shared by every stage: points, contours, regions, and the few measures
//! (area, orientation, distance, simplification) the slicer needs.

/// A point in the layer plane, millimetres.
pub type Point = [f64; 2];

/// A closed polygon; the last point connects back to the first (not repeated).
pub type Contour = Vec<Point>;

/// A region: shapes as i_overlay returns them, each an outer contour (counter-clockwise)
/// followed by its holes (clockwise).
pub type Region = Vec<Vec<Contour>>;

/// Twice nothing: the signed area of a closed contour, positive when counter-clockwise.
pub fn signed_area(c: &[Point]) -> f64 {
    let n = c.len();
    if n < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..n {
        let a = c[i];
        let b = c[(i + 1) % n];
        s += a[0] * b[1] - b[0] * a[1];
    }
    0.5 * s
}

/// The area of a region (outer contours minus holes, by their orientation).
pub fn region_area(r: &Region) -> f64 {
    r.iter().flatten().map(|c| signed_area(c)).sum()
}

/// The area enclosed by oriented contours (holes count negative).
#[cfg(test)]
pub fn contours_area(cs: &[Contour]) -> f64 {
    cs.iter().map(|c| signed_area(c)).sum()
}

/// The length of a polyline (`closed` adds the closing edge).
#[cfg(test)]
pub fn path_length(p: &[Point], closed: bool) -> f64 {
    let mut l: f64 = p.windows(2).map(|w| dist(w[0], w[1])).sum();
    if closed && p.len() > 2 {
        l += dist(p[p.len() - 1], p[0]);
    }
    l
}

/// Euclidean distance.
pub fn dist(a: Point, b: Point) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to the segment `a`-`b`.
pub fn segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Axis-aligned bounding box of many points: `([xmin, ymin], [xmax, ymax])`, or `None`
/// when there are none.
pub fn bbox<'a>(points: impl IntoIterator<Item = &'a Point>) -> Option<(Point, Point)> {
    let mut it = points.into_iter();
    let first = *it.next()?;
    let (mut lo, mut hi) = (first, first);
    for p in it {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    Some((lo, hi))
}

/// True when the segments `a`-`b` and `c`-`d` cross (proper or touching).
pub fn segments_cross(a: Point, b: Point, c: Point, d: Point) -> bool {
    fn orient(p: Point, q: Point, r: Point) -> f64 {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    }
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    (d1 * d2 <= 0.0) && (d3 * d4 <= 0.0) && !(d1 == 0.0 && d2 == 0.0)
}

/// Douglas-Peucker simplification of a closed contour: drops points that lie within
/// `tol` of the simplified outline. Keeps at least a triangle. Dense marching-squares
/// contours slow polygon offsetting down superlinearly (docs/constants.md), so every
/// outline goes through this before perimeters are built.
pub fn simplify_closed(c: &[Point], tol: f64) -> Contour {
    simplify_closed_indices(c, tol)
        .into_iter()
        .map(|i| c[i])
        .collect()
}

/// [`simplify_closed`], as the indices of the points kept, in order.
pub fn simplify_closed_indices(c: &[Point], tol: f64) -> Vec<usize> {
    let n = c.len();
    if n <= 4 || tol <= 0.0 {
        return (0..n).collect();
    }
    // Split the loop at the point farthest from the first one: both halves are open
    // polylines with well-separated ends, which Douglas-Peucker handles well.
    let far = (1..n)
        .max_by(|&i, &j| dist(c[0], c[i]).total_cmp(&dist(c[0], c[j])))
        .unwrap_or(n / 2);
    let mut keep = vec![false; n + 1];
    keep[0] = true;
    keep[far] = true;
    keep[n] = true;
    let at = |i: usize| c[i % n];
    let mut stack = vec![(0usize, far), (far, n)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let (a, b) = (at(i), at(j));
        let mut best = (0.0, i);
        for k in i + 1..j {
            let d = segment_distance(at(k), a, b);
            if d > best.0 {
                best = (d, k);
            }
        }
        if best.0 > tol {
            keep[best.1] = true;
            stack.push((i, best.1));
            stack.push((best.1, j));
        }
    }
    let out: Vec<usize> = (0..n).filter(|&i| keep[i]).collect();
    if out.len() < 3 { (0..n).collect() } else { out }
}

/// Douglas-Peucker simplification of an open polyline: the indices of the points kept
/// (always the first and the last), every dropped point within `tol` of the result.
pub fn simplify_open(p: &[Point], tol: f64) -> Vec<usize> {
    let n = p.len();
    if n <= 2 {
        return (0..n).collect();
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let mut best = (0.0, i);
        for k in i + 1..j {
            let d = segment_distance(p[k], p[i], p[j]);
            if d > best.0 {
                best = (d, k);
            }
        }
        if best.0 > tol {
            keep[best.1] = true;
            stack.push((i, best.1));
            stack.push((best.1, j));
        }
    }
    (0..n).filter(|&i| keep[i]).collect()
}

/// The length of a polyline.
pub fn polyline_length(p: &[Point]) -> f64 {
    p.windows(2).map(|w| dist(w[0], w[1])).sum()
}

/// True when `p` lies inside the region (holes excluded).
pub fn inside_region(p: Point, r: &Region) -> bool {
    r.iter().any(|shape| inside_contours(p, shape))
}

/// Even-odd point-in-polygon over many contours.
pub fn inside_contours(p: Point, cs: &[Contour]) -> bool {
    let mut inside = false;
    for c in cs {
        let n = c.len();
        for i in 0..n {
            let a = c[i];
            let b = c[(i + 1) % n];
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    inside = !inside;
                }
            }
        }
    }
    inside
}

/// Distance from `p` to the nearest edge of any contour.
pub fn distance_to_contours(p: Point, cs: &[Contour]) -> f64 {
    let mut best = f64::INFINITY;
    for c in cs {
        let n = c.len();
        for i in 0..n {
            best = best.min(segment_distance(p, c[i], c[(i + 1) % n]));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(r: f64, n: usize) -> Contour {
        (0..n)
            .map(|i| {
                let t = i as f64 / n as f64 * std::f64::consts::TAU;
                [r * t.cos(), r * t.sin()]
            })
            .collect()
    }

    #[test]
    fn area_sign_follows_orientation() {
        let sq = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        assert_eq!(signed_area(&sq), 4.0);
        let rev: Contour = sq.iter().rev().copied().collect();
        assert_eq!(signed_area(&rev), -4.0);
    }

    #[test]
    fn douglas_peucker_keeps_shape_within_tolerance() {
        let c = circle(10.0, 4000);
        let s = simplify_closed(&c, 0.01);
        assert!(s.len() < 400, "{} points left", s.len());
        assert!(s.len() > 20);
        for p in &c {
            let d = distance_to_contours(*p, std::slice::from_ref(&s));
            assert!(d <= 0.0100001, "{d}");
        }
    }

    #[test]
    fn point_in_polygon_with_hole() {
        let outer = circle(10.0, 64);
        let hole: Contour = circle(5.0, 64).into_iter().rev().collect();
        let cs = vec![outer, hole];
        assert!(inside_contours([7.0, 0.0], &cs));
        assert!(!inside_contours([0.0, 0.0], &cs));
        assert!(!inside_contours([11.0, 0.0], &cs));
    }
}
