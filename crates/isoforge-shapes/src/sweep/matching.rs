//! Making two rings of different point counts correspond vertex to vertex, for `skin`
//! (the methods of BOSL2's `skin`, in our own implementation):
//! - resampling to a common count, by length or evenly per segment ([`resample`]);
//! - `reindex`: the cyclic shift with the shortest total connecting edges;
//! - `distance`: duplicating vertices so that the total length of the connecting edges is
//!   smallest (dynamic programming over every cyclic shift; `fast_distance` keeps vertex
//!   0 on vertex 0);
//! - `tangent`: each edge of a polygon joins the point of a convex curve where the curve
//!   runs parallel to it, and the curve points between join the polygon's vertices.

use glam::DVec2;

/// How points are added when a ring is resampled (BOSL2's `sampling`).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// New points spread by length: long edges get more.
    Length,
    /// The same number of new points on every edge.
    Segment,
}

/// Resamples a closed ring to exactly `n` points (`n` at least its own count), keeping
/// its vertices and adding points on its edges.
pub fn resample(ring: &[DVec2], n: usize, sampling: Sampling) -> Vec<DVec2> {
    let m = ring.len();
    if n <= m || m == 0 {
        return ring.to_vec();
    }
    let extra = n - m;
    let lengths: Vec<f64> = (0..m)
        .map(|i| ring[i].distance(ring[(i + 1) % m]))
        .collect();
    let total: f64 = lengths.iter().sum();
    let mut counts = vec![0usize; m];
    match sampling {
        Sampling::Segment => {
            for (i, c) in counts.iter_mut().enumerate() {
                *c = extra / m + usize::from(i < extra % m);
            }
        }
        Sampling::Length => {
            // Largest-remainder apportionment of the new points by edge length.
            let want: Vec<f64> = lengths
                .iter()
                .map(|l| {
                    if total > 0.0 {
                        l / total * extra as f64
                    } else {
                        extra as f64 / m as f64
                    }
                })
                .collect();
            let mut given = 0;
            for i in 0..m {
                counts[i] = want[i].floor() as usize;
                given += counts[i];
            }
            let mut order: Vec<usize> = (0..m).collect();
            order.sort_by(|&a, &b| {
                let ra = want[a] - want[a].floor();
                let rb = want[b] - want[b].floor();
                rb.total_cmp(&ra).then(a.cmp(&b))
            });
            for &i in order.iter().take(extra - given) {
                counts[i] += 1;
            }
        }
    }
    let mut out = Vec::with_capacity(n);
    for i in 0..m {
        let (a, b) = (ring[i], ring[(i + 1) % m]);
        let parts = counts[i] + 1;
        for k in 0..parts {
            out.push(a.lerp(b, k as f64 / parts as f64));
        }
    }
    out
}

/// Each edge divided into `refine` equal parts.
pub fn refine(ring: &[DVec2], refine: usize) -> Vec<DVec2> {
    resample(ring, ring.len() * refine.max(1), Sampling::Segment)
}

/// `ring` rotated to start at index `k`.
fn shifted(ring: &[DVec2], k: usize) -> Vec<DVec2> {
    let n = ring.len();
    (0..n).map(|i| ring[(i + k) % n]).collect()
}

/// `reindex`: `b` (same count as `a`) rotated to minimize the summed distance between
/// matched points.
pub fn reindex(a: &[DVec2], b: &[DVec2]) -> Vec<DVec2> {
    let n = b.len();
    let cost = |k: usize| (0..n).map(|i| a[i].distance(b[(i + k) % n])).sum::<f64>();
    let best = (0..n)
        .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
        .unwrap_or(0);
    shifted(b, best)
}

/// The largest dynamic-programming table (cells times shifts) the `distance` method
/// fills before it narrows its search to shifts near the best direct alignment: about a
/// second of work.
const DISTANCE_BUDGET: usize = 300_000_000;

/// Shifts searched either side of the direct alignment when the budget is exceeded.
const DISTANCE_WINDOW: usize = 16;

/// Matched index pairs (small, big), in order around both rings.
type Pairs = Vec<(usize, usize)>;

/// The cheapest monotone matching of `small` (m points) against `big` (n points), both
/// closed and starting matched at index 0: returns its cost and the matched index pairs
/// (every index of both appears, in order). Gives up (returns `None`) once every entry of
/// a row exceeds `abort`.
fn dp_match(small: &[DVec2], big: &[DVec2], abort: f64) -> Option<(f64, Pairs)> {
    let (m, n) = (small.len(), big.len());
    let w = n + 1;
    let dist = |i: usize, j: usize| small[i % m].distance(big[j % n]);
    // cost[i][j]: the cheapest path from (0, 0) to (i, j); (m, n) is (0, 0) again, so its
    // own distance is not counted twice.
    let mut cost = vec![f64::INFINITY; (m + 1) * w];
    let mut from = vec![0u8; (m + 1) * w];
    cost[0] = 0.0;
    for i in 0..=m {
        let mut row_min = f64::INFINITY;
        for j in 0..=n {
            if i == 0 && j == 0 {
                row_min = 0.0;
                continue;
            }
            let here = if i == m && j == n { 0.0 } else { dist(i, j) };
            let mut best = f64::INFINITY;
            let mut dir = 0u8;
            if i > 0 && j > 0 && cost[(i - 1) * w + j - 1] < best {
                best = cost[(i - 1) * w + j - 1];
                dir = 0;
            }
            if j > 0 && cost[i * w + j - 1] < best {
                best = cost[i * w + j - 1];
                dir = 1;
            }
            if i > 0 && cost[(i - 1) * w + j] < best {
                best = cost[(i - 1) * w + j];
                dir = 2;
            }
            cost[i * w + j] = best + here;
            from[i * w + j] = dir;
            row_min = row_min.min(cost[i * w + j]);
        }
        if row_min > abort {
            return None;
        }
    }
    let total = cost[m * w + n] + dist(0, 0);
    let (mut i, mut j) = (m, n);
    let mut pairs = Vec::new();
    while i > 0 || j > 0 {
        pairs.push((i % m, j % n));
        match from[i * w + j] {
            0 => {
                i -= 1;
                j -= 1;
            }
            1 => j -= 1,
            _ => i -= 1,
        }
    }
    pairs.reverse();
    Some((total, pairs))
}

/// `distance` (or `fast_distance` with `all_shifts = false`): both rings with vertices
/// repeated so that they have equal counts and the connecting edges are shortest.
pub fn distance_match(a: &[DVec2], b: &[DVec2], all_shifts: bool) -> (Vec<DVec2>, Vec<DVec2>) {
    let swap = a.len() > b.len();
    let (small, big) = if swap { (b, a) } else { (a, b) };
    let (m, n) = (small.len(), big.len());
    let shifts: Vec<usize> = if !all_shifts {
        vec![0]
    } else if m * n * n <= DISTANCE_BUDGET {
        (0..n).collect()
    } else {
        // Too big to try every start: try those near where a length-resampled small ring
        // lines up best with the big one.
        let even = resample(small, n, Sampling::Length);
        let direct = |k: usize| {
            (0..n)
                .map(|i| even[i].distance(big[(i + k) % n]))
                .sum::<f64>()
        };
        let centre = (0..n)
            .min_by(|&x, &y| direct(x).total_cmp(&direct(y)))
            .unwrap_or(0);
        (0..=2 * DISTANCE_WINDOW)
            .map(|d| (centre + n + d - DISTANCE_WINDOW.min(n)) % n)
            .collect()
    };
    let mut best: Option<(f64, usize, Pairs)> = None;
    for k in shifts {
        let rotated = shifted(big, k);
        let abort = best.as_ref().map_or(f64::INFINITY, |b| b.0);
        if let Some((cost, pairs)) = dp_match(small, &rotated, abort)
            && best.as_ref().is_none_or(|b| cost < b.0)
        {
            best = Some((cost, k, pairs));
        }
    }
    let (_, k, pairs) = best.unwrap_or((0.0, 0, (0..m.min(n)).map(|i| (i, i)).collect()));
    let rotated = shifted(big, k);
    let new_small: Vec<DVec2> = pairs.iter().map(|&(i, _)| small[i]).collect();
    let new_big: Vec<DVec2> = pairs.iter().map(|&(_, j)| rotated[j]).collect();
    if swap {
        (new_big, new_small)
    } else {
        (new_small, new_big)
    }
}

/// Why the tangent method could not match two rings.
#[derive(Debug, Clone, PartialEq)]
pub struct TangentFailure;

/// `tangent`: the ring with fewer points is the polygon, the other a convex curve. Each
/// polygon edge meets the curve where the curve runs parallel to it (the curve's farthest
/// point in the edge's outward direction); the curve points from one such point to the
/// next all join the polygon vertex between the two edges.
pub fn tangent_match(a: &[DVec2], b: &[DVec2]) -> Result<(Vec<DVec2>, Vec<DVec2>), TangentFailure> {
    let swap = a.len() > b.len();
    let (small, big) = if swap { (b, a) } else { (a, b) };
    let (m, n) = (small.len(), big.len());
    if m < 3 || n < m {
        return Err(TangentFailure);
    }
    let centroid = |r: &[DVec2]| r.iter().copied().sum::<DVec2>() / r.len() as f64;
    let cb = centroid(big);
    // The tangent point of each polygon edge, as an index into the curve.
    let cuts: Vec<usize> = (0..m)
        .map(|i| {
            let e = small[(i + 1) % m] - small[i];
            let outward = DVec2::new(e.y, -e.x);
            (0..n)
                .max_by(|&x, &y| {
                    let px = (big[x] - cb).dot(outward);
                    let py = (big[y] - cb).dot(outward);
                    px.total_cmp(&py)
                })
                .unwrap_or(0)
        })
        .collect();
    // Curve points after the cut of edge i−1, up to and including the cut of edge i, join
    // vertex i.
    let counts: Vec<usize> = (0..m)
        .map(|i| (cuts[i] + n - cuts[(i + m - 1) % m]) % n)
        .collect();
    if counts.iter().sum::<usize>() != n {
        return Err(TangentFailure);
    }
    let start = (cuts[m - 1] + 1) % n;
    let new_big = shifted(big, start);
    let mut new_small = Vec::with_capacity(n);
    for i in 0..m {
        new_small.extend(std::iter::repeat_n(small[i], counts[i]));
    }
    Ok(if swap {
        (new_big, new_small)
    } else {
        (new_small, new_big)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ngon(n: usize, r: f64, phase: f64) -> Vec<DVec2> {
        (0..n)
            .map(|i| {
                let a = phase + i as f64 * std::f64::consts::TAU / n as f64;
                DVec2::new(r * a.cos(), r * a.sin())
            })
            .collect()
    }

    #[test]
    fn resampling_keeps_vertices_and_reaches_the_count() {
        let sq = ngon(4, 1.0, 0.0);
        for s in [Sampling::Length, Sampling::Segment] {
            let r = resample(&sq, 11, s);
            assert_eq!(r.len(), 11);
            for v in &sq {
                assert!(r.contains(v));
            }
        }
        // By length, a 3-by-1 rectangle's long sides get three times the points.
        let rect = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(3.0, 0.0),
            DVec2::new(3.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let r = resample(&rect, 12, Sampling::Length);
        let on_bottom = r.iter().filter(|p| p.y == 0.0).count();
        assert_eq!(
            on_bottom,
            4 + 1,
            "3 new points and 2 corners on the bottom edge"
        );
    }

    #[test]
    fn distance_matching_duplicates_to_equal_counts() {
        let sq = ngon(4, 1.0, 0.0);
        let hex = ngon(6, 1.0, 0.1);
        let (a, b) = distance_match(&sq, &hex, true);
        assert_eq!(a.len(), b.len());
        assert!(a.len() >= 6);
        // Every vertex of both appears.
        for v in sq.iter() {
            assert!(a.contains(v));
        }
        for v in hex.iter() {
            assert!(b.contains(v));
        }
        // The matching is no worse than the plain index-by-index one after resampling.
        let cost: f64 = a.iter().zip(&b).map(|(p, q)| p.distance(*q)).sum();
        let plain: f64 = resample(&sq, 6, Sampling::Segment)
            .iter()
            .zip(&hex)
            .map(|(p, q)| p.distance(*q))
            .sum();
        assert!(cost <= plain + 1e-9, "{cost} vs {plain}");
    }

    #[test]
    fn tangent_matching_splits_the_curve_among_the_vertices() {
        let sq = ngon(4, 2.0, std::f64::consts::FRAC_PI_4);
        let circle = ngon(64, 1.0, 0.0);
        let (a, b) = tangent_match(&sq, &circle).unwrap();
        assert_eq!(a.len(), 64);
        assert_eq!(b.len(), 64);
        // Each square vertex takes the quarter of the circle around its own direction.
        for (p, q) in a.iter().zip(&b) {
            assert!(p.normalize().dot(q.normalize()) > 0.6, "{p} joined {q}");
        }
    }

    #[test]
    fn reindex_finds_the_rotation() {
        let a = ngon(8, 1.0, 0.0);
        let b = shifted(&a, 3);
        assert_eq!(reindex(&a, &b), a);
    }
}
