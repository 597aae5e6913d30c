//! Combing: travel that stays inside the part, where oozing lands on material that will
//! be covered anyway, so it needs no retraction.
//!
//! A straight travel that leaves the comb region through one of its contours and comes
//! back in through the same contour is bent to follow that contour between the two
//! crossings, the shorter way round (a travel across a hole goes around the hole). A
//! travel that would have to cross from one contour to another (to another island)
//! cannot be combed.

use crate::geom::{Contour, Point, Region, dist, inside_region, polyline_length};

/// A combed route is refused when it is longer than this many times the straight travel
/// plus this many mm: the detour would cost more time than a retraction.
const DETOUR_FACTOR: f64 = 3.0;
const DETOUR_SLACK: f64 = 15.0;

/// The comb region's contours with their bounding boxes, for crossing tests.
pub struct Comb<'a> {
    region: &'a Region,
    contours: Vec<(&'a Contour, Point, Point)>,
}

impl<'a> Comb<'a> {
    /// Prepares a region for routing.
    pub fn new(region: &'a Region) -> Comb<'a> {
        let contours = region
            .iter()
            .flatten()
            .filter_map(|c| {
                let (lo, hi) = crate::geom::bbox(c.iter())?;
                Some((c, lo, hi))
            })
            .collect();
        Comb { region, contours }
    }

    /// A route from `a` to `b` inside the region (the points after `a`, ending at `b`), or
    /// `None` when there is none this simple.
    pub fn route(&self, a: Point, b: Point) -> Option<Vec<Point>> {
        if self.contours.is_empty()
            || !inside_region(a, self.region)
            || !inside_region(b, self.region)
        {
            return None;
        }
        // Every crossing of a-b with a contour edge: (t along a-b, contour, edge index).
        let mut hits: Vec<(f64, usize, usize, Point)> = Vec::new();
        let (lo, hi) = (
            [a[0].min(b[0]), a[1].min(b[1])],
            [a[0].max(b[0]), a[1].max(b[1])],
        );
        for (ci, (c, clo, chi)) in self.contours.iter().enumerate() {
            if chi[0] < lo[0] || clo[0] > hi[0] || chi[1] < lo[1] || clo[1] > hi[1] {
                continue;
            }
            let n = c.len();
            for k in 0..n {
                let (p, q) = (c[k], c[(k + 1) % n]);
                if let Some((t, x)) = crossing(a, b, p, q) {
                    hits.push((t, ci, k, x));
                }
            }
        }
        if hits.is_empty() {
            return Some(vec![b]);
        }
        hits.sort_by(|x, y| x.0.total_cmp(&y.0));
        if !hits.len().is_multiple_of(2) {
            return None;
        }
        let mut route = Vec::new();
        for pair in hits.chunks_exact(2) {
            let ((_, c_out, e_out, p_out), (_, c_in, e_in, p_in)) = (pair[0], pair[1]);
            if c_out != c_in {
                return None;
            }
            route.push(p_out);
            route.extend(around(self.contours[c_out].0, e_out, p_out, e_in, p_in));
            route.push(p_in);
        }
        route.push(b);
        let straight = dist(a, b);
        let mut full = vec![a];
        full.extend(&route);
        if polyline_length(&full) > DETOUR_FACTOR * straight + DETOUR_SLACK {
            return None;
        }
        Some(route)
    }
}

/// Where segment a-b properly crosses segment p-q: (t along a-b, the point).
fn crossing(a: Point, b: Point, p: Point, q: Point) -> Option<(f64, Point)> {
    let r = [b[0] - a[0], b[1] - a[1]];
    let s = [q[0] - p[0], q[1] - p[1]];
    let den = r[0] * s[1] - r[1] * s[0];
    if den.abs() < 1e-15 {
        return None;
    }
    let ap = [p[0] - a[0], p[1] - a[1]];
    let t = (ap[0] * s[1] - ap[1] * s[0]) / den;
    let u = (ap[0] * r[1] - ap[1] * r[0]) / den;
    // Half-open on the contour edge, so a crossing through a vertex counts once.
    if (0.0..=1.0).contains(&t) && (0.0..1.0).contains(&u) {
        Some((t, [a[0] + t * r[0], a[1] + t * r[1]]))
    } else {
        None
    }
}

/// The contour's vertices between a crossing on edge `e_out` and one on edge `e_in`,
/// whichever way round is shorter.
fn around(c: &Contour, e_out: usize, p_out: Point, e_in: usize, p_in: Point) -> Vec<Point> {
    let n = c.len();
    // Forward: vertices e_out+1 ..= e_in (mod n).
    let mut fwd = Vec::new();
    let mut k = (e_out + 1) % n;
    if e_out != e_in {
        loop {
            fwd.push(c[k]);
            if k == e_in {
                break;
            }
            k = (k + 1) % n;
        }
    }
    // Backward: vertices e_out, e_out-1, ..., e_in+1.
    let mut bwd = Vec::new();
    if e_out != e_in {
        let mut k = e_out;
        loop {
            bwd.push(c[k]);
            let next = (k + n - 1) % n;
            if next == e_in {
                break;
            }
            k = next;
        }
    }
    let len = |v: &Vec<Point>| {
        let mut p = vec![p_out];
        p.extend(v);
        p.push(p_in);
        polyline_length(&p)
    };
    if len(&fwd) <= len(&bwd) { fwd } else { bwd }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;

    fn ring() -> Region {
        let sq = |a: f64, b: f64| vec![[a, a], [b, a], [b, b], [a, b]];
        let hole: Contour = sq(4.0, 16.0).into_iter().rev().collect();
        region_from_contours(&[sq(0.0, 20.0), hole])
    }

    #[test]
    fn a_travel_across_a_hole_goes_around_it() {
        let r = ring();
        let comb = Comb::new(&r);
        let route = comb.route([2.0, 10.0], [18.0, 10.0]).expect("a route");
        let mut full = vec![[2.0, 10.0]];
        full.extend(&route);
        for w in full.windows(2) {
            let mid = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
            assert!(
                inside_region(mid, &r) || !crate::geom::inside_region(mid, &ring()),
                "{mid:?}"
            );
            // Never over the hole.
            assert!(
                !(mid[0] > 4.0 + 1e-9
                    && mid[0] < 16.0 - 1e-9
                    && mid[1] > 4.0 + 1e-9
                    && mid[1] < 16.0 - 1e-9),
                "{mid:?}"
            );
        }
        assert_eq!(route.last(), Some(&[18.0, 10.0]));
    }

    #[test]
    fn a_travel_inside_is_straight_and_one_between_islands_is_refused() {
        let r = ring();
        let comb = Comb::new(&r);
        assert_eq!(comb.route([1.0, 1.0], [19.0, 1.0]), Some(vec![[19.0, 1.0]]));
        let sq = |a: f64, b: f64| vec![[a, 0.0], [b, 0.0], [b, 5.0], [a, 5.0]];
        let two = region_from_contours(&[sq(0.0, 5.0), sq(10.0, 15.0)]);
        let comb = Comb::new(&two);
        assert_eq!(comb.route([2.0, 2.0], [12.0, 2.0]), None);
    }
}
