//! Overhang perimeters: the stretches of an outer wall that hang over air (their centre
//! more than half a nozzle beyond the layer below, as PrusaSlicer judges it) or lie on a
//! surface that faces down more steeply than the support angle (from the model's exact
//! normals: the field's gradient, or the mesh's facets). They are printed at bridge speed
//! with the bridge fan.

use std::collections::HashMap;

use crate::geom::{Point, Region, dist, inside_region, segment_distance};

/// Walls are judged in pieces of at most this length, mm.
const PIECE: f64 = 1.0;

/// Steep outline points, bucketed for "is one near here?" queries.
pub struct SteepIndex {
    cell: f64,
    buckets: HashMap<(i64, i64), Vec<Point>>,
}

impl SteepIndex {
    /// Indexes `points` for queries within `radius` mm.
    pub fn new(points: &[Point], radius: f64) -> SteepIndex {
        let cell = radius.max(1e-3);
        let mut buckets: HashMap<(i64, i64), Vec<Point>> = HashMap::new();
        for &p in points {
            buckets
                .entry(((p[0] / cell).floor() as i64, (p[1] / cell).floor() as i64))
                .or_default()
                .push(p);
        }
        SteepIndex { cell, buckets }
    }

    /// True when a steep point lies within the radius of the segment `a`-`b`.
    pub fn near(&self, a: Point, b: Point) -> bool {
        if self.buckets.is_empty() {
            return false;
        }
        let cell = |v: f64| (v / self.cell).floor() as i64;
        let (i0, i1) = (cell(a[0].min(b[0])) - 1, cell(a[0].max(b[0])) + 1);
        let (j0, j1) = (cell(a[1].min(b[1])) - 1, cell(a[1].max(b[1])) + 1);
        (i0..=i1).any(|i| {
            (j0..=j1).any(|j| {
                self.buckets
                    .get(&(i, j))
                    .is_some_and(|v| v.iter().any(|q| segment_distance(*q, a, b) <= self.cell))
            })
        })
    }
}

/// Splits a wall path into runs, each marked overhanging or not. `supported` is the layer
/// below grown by half a nozzle (`None` on the bed: nothing hangs there).
pub fn split_wall(
    path: &[Point],
    supported: Option<&Region>,
    steep: &SteepIndex,
) -> Vec<(bool, Vec<Point>)> {
    let mut runs: Vec<(bool, Vec<Point>)> = Vec::new();
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = (dist(a, b) / PIECE).ceil().max(1.0) as usize;
        for k in 0..n {
            let (t0, t1) = (k as f64 / n as f64, (k + 1) as f64 / n as f64);
            let p0 = [a[0] + t0 * (b[0] - a[0]), a[1] + t0 * (b[1] - a[1])];
            let p1 = [a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])];
            let mid = [(p0[0] + p1[0]) * 0.5, (p0[1] + p1[1]) * 0.5];
            let over_air = supported.is_some_and(|r| !inside_region(mid, r));
            let hangs = over_air || steep.near(p0, p1);
            let end = k + 1 == n;
            match runs.last_mut() {
                Some((h, pts)) if *h == hangs => {
                    if end {
                        pts.push(p1);
                    }
                }
                last => {
                    // Close the previous run where this one starts.
                    if let Some((_, pts)) = last
                        && pts.last() != Some(&p0)
                    {
                        pts.push(p0);
                    }
                    let mut pts = vec![p0];
                    if end {
                        pts.push(p1);
                    }
                    runs.push((hangs, pts));
                }
            }
        }
    }
    runs.retain(|r| r.1.len() >= 2);
    runs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;

    #[test]
    fn the_part_beyond_the_layer_below_hangs() {
        let below =
            region_from_contours(&[vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]]);
        let path = vec![[0.0, 5.0], [20.0, 5.0]];
        let runs = split_wall(&path, Some(&below), &SteepIndex::new(&[], 0.45));
        assert_eq!(runs.len(), 2);
        assert!(!runs[0].0 && runs[1].0);
        assert!((runs[0].1.last().unwrap()[0] - 10.0).abs() < 1e-9);
    }

    #[test]
    fn steep_points_mark_the_wall_near_them() {
        let steep = SteepIndex::new(&[[15.0, 5.2]], 0.45);
        let runs = split_wall(&[[0.0, 5.0], [20.0, 5.0]], None, &steep);
        let hanging: f64 = runs
            .iter()
            .filter(|r| r.0)
            .map(|r| crate::geom::polyline_length(&r.1))
            .sum();
        assert!(hanging > 0.0 && hanging <= 2.0, "{hanging}");
    }
}
