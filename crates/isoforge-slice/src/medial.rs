//! Centre lines of thin regions, each point with the region's full width there: what thin
//! walls, gap fill and narrow skins are printed along, one line as wide as the region.
//!
//! The region is drawn on a fine pixel grid and thinned to a one-pixel skeleton (Zhang and
//! Suen, "A fast parallel algorithm for thinning digital patterns", CACM 1984); the
//! skeleton's short spurs into corners are pruned, its pixels chained into polylines, and
//! the width at each point is twice the exact distance to the region's edges (not the
//! pixel distance, which would be off by a pixel: 10% of a 0.4 mm wall at w/10 pixels).

use crate::geom::{Point, Region, bbox, dist, segment_distance};

/// A centre line and the region's full width at each of its points.
#[derive(Clone, Debug, PartialEq)]
pub struct CentreLine {
    /// The points, in order.
    pub points: Vec<Point>,
    /// The region's width at each point, mm.
    pub widths: Vec<f64>,
}

/// A spur shorter than this many times the half-width where it joins is the skeleton
/// running into a corner, not a branch of the region: a strip of half-width d ends in two
/// corner spurs of about 1.4 d.
const SPUR_PER_HALF_WIDTH: f64 = 2.5;

/// At most this many pixels per region; a larger one is drawn with coarser pixels.
const MAX_PIXELS: usize = 16_000_000;

/// The centre lines of `region` traced on pixels of `pixel` mm (a tenth of a line width
/// resolves walls down to about three pixels across).
pub fn centre_lines(region: &Region, pixel: f64) -> Vec<CentreLine> {
    let Some((lo, hi)) = bbox(region.iter().flatten().flatten()) else {
        return Vec::new();
    };
    if !(pixel > 0.0 && pixel.is_finite()) {
        return Vec::new();
    }
    let mut p = pixel;
    let span = [hi[0] - lo[0], hi[1] - lo[1]];
    let pixels = |p: f64| ((span[0] / p) as usize + 5) * ((span[1] / p) as usize + 5);
    while pixels(p) > MAX_PIXELS {
        p *= 1.5;
    }
    let mut grid = Grid::new(lo, span, p);
    grid.fill(region);
    grid.thin();
    let edges = EdgeIndex::new(region, (p * 16.0).max(0.5));
    grid.prune_spurs(&edges);
    grid.trace()
        .into_iter()
        .filter_map(|pix| {
            let raw: Vec<Point> = pix.iter().map(|&k| grid.center(k)).collect();
            let (pts, widths) = recentre(&raw, &edges, p);
            let keep = simplify_with_widths(&pts, &widths, p * 0.5, WIDTH_TOLERANCE);
            let points: Vec<Point> = keep.iter().map(|&i| pts[i]).collect();
            let widths: Vec<f64> = keep.iter().map(|&i| widths[i]).collect();
            (points.len() >= 2).then_some(CentreLine { points, widths })
        })
        .collect()
}

/// Widths along a centre line are kept to this, mm (a twentieth of a 0.4 mm wall).
const WIDTH_TOLERANCE: f64 = 0.02;

/// Moves each skeleton pixel onto the true centre: the midpoint of the region's chord
/// across the line there (two rays, one to each side), whose length is the width. The
/// pixel skeleton alone sits up to half a pixel off the centre and its staircase wobbles.
fn recentre(raw: &[Point], edges: &EdgeIndex, p: f64) -> (Vec<Point>, Vec<f64>) {
    let n = raw.len();
    let closed = n > 3 && dist(raw[0], raw[n - 1]) < 1e-9;
    let mut pts = Vec::with_capacity(n);
    let mut widths = Vec::with_capacity(n);
    for i in 0..n {
        // The direction over a few pixels either side smooths the staircase.
        let (a, b) = if closed {
            (raw[(i + n - 1 - 3) % (n - 1)], raw[(i + 3) % (n - 1)])
        } else {
            (raw[i.saturating_sub(3)], raw[(i + 3).min(n - 1)])
        };
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy);
        let q = raw[i];
        let near = edges.distance(q);
        if l <= 0.0 {
            pts.push(q);
            widths.push(2.0 * near);
            continue;
        }
        let v = [-dy / l, dx / l];
        let reach = 2.0 * near + 4.0 * p;
        match (edges.ray(q, v, reach), edges.ray(q, [-v[0], -v[1]], reach)) {
            (Some(s), Some(t)) => {
                let shift = 0.5 * (s - t);
                pts.push([q[0] + v[0] * shift, q[1] + v[1] * shift]);
                widths.push(s + t);
            }
            _ => {
                pts.push(q);
                widths.push(2.0 * near);
            }
        }
    }
    (pts, widths)
}

/// Douglas-Peucker over points and widths: a point is kept when it strays more than `tol`
/// from the simplified line or its width more than `wtol` from the width interpolated
/// there. Returns the indices kept.
fn simplify_with_widths(p: &[Point], w: &[f64], tol: f64, wtol: f64) -> Vec<usize> {
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
        let span = dist(p[i], p[j]).max(1e-12);
        let mut best = (0.0, i);
        for k in i + 1..j {
            let along = (dist(p[i], p[k]) / span).clamp(0.0, 1.0);
            let wi = w[i] + (w[j] - w[i]) * along;
            let e = (segment_distance(p[k], p[i], p[j]) / tol).max((w[k] - wi).abs() / wtol);
            if e > best.0 {
                best = (e, k);
            }
        }
        if best.0 > 1.0 {
            keep[best.1] = true;
            stack.push((i, best.1));
            stack.push((best.1, j));
        }
    }
    (0..n).filter(|&i| keep[i]).collect()
}

/// A binary image over the region's box with a border of empty pixels.
struct Grid {
    origin: Point,
    p: f64,
    nx: usize,
    ny: usize,
    on: Vec<bool>,
}

/// Neighbour offsets in Zhang-Suen order: N, NE, E, SE, S, SW, W, NW (rows grow upward).
const RING: [(i64, i64); 8] = [
    (0, 1),
    (1, 1),
    (1, 0),
    (1, -1),
    (0, -1),
    (-1, -1),
    (-1, 0),
    (-1, 1),
];

impl Grid {
    fn new(lo: Point, span: [f64; 2], p: f64) -> Grid {
        let nx = (span[0] / p).ceil() as usize + 5;
        let ny = (span[1] / p).ceil() as usize + 5;
        Grid {
            origin: [lo[0] - 2.0 * p, lo[1] - 2.0 * p],
            p,
            nx,
            ny,
            on: vec![false; nx * ny],
        }
    }

    fn center(&self, k: usize) -> Point {
        let (i, j) = (k % self.nx, k / self.nx);
        [
            self.origin[0] + (i as f64 + 0.5) * self.p,
            self.origin[1] + (j as f64 + 0.5) * self.p,
        ]
    }

    /// Sets the pixels whose centres lie inside (even-odd over all contours).
    fn fill(&mut self, region: &Region) {
        let mut xs = Vec::new();
        for j in 0..self.ny {
            let y = self.origin[1] + (j as f64 + 0.5) * self.p;
            xs.clear();
            for c in region.iter().flatten() {
                let n = c.len();
                for k in 0..n {
                    let (a, b) = (c[k], c[(k + 1) % n]);
                    if (a[1] > y) != (b[1] > y) {
                        xs.push(a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]));
                    }
                }
            }
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks_exact(2) {
                let i0 = ((pair[0] - self.origin[0]) / self.p - 0.5).ceil().max(0.0) as usize;
                let i1 = ((pair[1] - self.origin[0]) / self.p - 0.5).floor();
                if i1 < 0.0 {
                    continue;
                }
                let i1 = (i1 as usize).min(self.nx - 1);
                for i in i0..=i1 {
                    self.on[j * self.nx + i] = true;
                }
            }
        }
    }

    fn at(&self, k: usize, d: (i64, i64)) -> bool {
        let (i, j) = ((k % self.nx) as i64 + d.0, (k / self.nx) as i64 + d.1);
        i >= 0
            && j >= 0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self.on[j as usize * self.nx + i as usize]
    }

    fn index(&self, k: usize, d: (i64, i64)) -> usize {
        let (i, j) = ((k % self.nx) as i64 + d.0, (k / self.nx) as i64 + d.1);
        j as usize * self.nx + i as usize
    }

    /// Zhang-Suen thinning, visiting only the pixels still set.
    fn thin(&mut self) {
        let mut live: Vec<usize> = (0..self.on.len()).filter(|&k| self.on[k]).collect();
        let mut doomed = Vec::new();
        loop {
            let mut changed = false;
            for step in 0..2 {
                doomed.clear();
                for &k in &live {
                    let n = RING.map(|d| self.at(k, d));
                    let b = n.iter().filter(|&&v| v).count();
                    if !(2..=6).contains(&b) {
                        continue;
                    }
                    let a = (0..8).filter(|&i| !n[i] && n[(i + 1) % 8]).count();
                    if a != 1 {
                        continue;
                    }
                    let (p2, p4, p6, p8) = (n[0], n[2], n[4], n[6]);
                    let ok = if step == 0 {
                        !(p4 && p6 && (p2 || p8))
                    } else {
                        !(p2 && p8 && (p4 || p6))
                    };
                    if ok {
                        doomed.push(k);
                    }
                }
                for &k in &doomed {
                    self.on[k] = false;
                }
                changed |= !doomed.is_empty();
                live.retain(|&k| self.on[k]);
            }
            if !changed {
                break;
            }
        }
    }

    /// The skeleton neighbours of a pixel: its set 4-neighbours, and its set diagonal ones
    /// not already reached through a set 4-neighbour (so staircases are not triangles).
    fn neighbours(&self, k: usize) -> Vec<usize> {
        let mut out = Vec::with_capacity(4);
        for (idx, &d) in RING.iter().enumerate() {
            if !self.at(k, d) {
                continue;
            }
            if idx % 2 == 1 {
                let (a, b) = (RING[idx - 1], RING[(idx + 1) % 8]);
                if self.at(k, a) || self.at(k, b) {
                    continue;
                }
            }
            out.push(self.index(k, d));
        }
        out
    }

    /// Removes spurs: runs from an end pixel to a junction shorter than
    /// `SPUR_PER_HALF_WIDTH` half-widths of the region at the junction.
    fn prune_spurs(&mut self, edges: &EdgeIndex) {
        for _ in 0..2 {
            let ends: Vec<usize> = (0..self.on.len())
                .filter(|&k| self.on[k] && self.neighbours(k).len() == 1)
                .collect();
            let mut removed = false;
            for e in ends {
                if !self.on[e] {
                    continue;
                }
                let mut run = vec![e];
                let mut prev = usize::MAX;
                let mut cur = e;
                let junction = loop {
                    let next: Vec<usize> = self
                        .neighbours(cur)
                        .into_iter()
                        .filter(|&n| n != prev)
                        .collect();
                    if next.len() != 1 {
                        break if next.is_empty() { None } else { Some(cur) };
                    }
                    prev = cur;
                    cur = next[0];
                    if self.neighbours(cur).len() > 2 {
                        break Some(cur);
                    }
                    run.push(cur);
                };
                let Some(j) = junction else { continue };
                let half = edges.distance(self.center(j));
                if run.len() as f64 * self.p < SPUR_PER_HALF_WIDTH * half + self.p {
                    for k in run {
                        self.on[k] = false;
                    }
                    removed = true;
                }
            }
            if !removed {
                break;
            }
        }
    }

    /// The skeleton as chains of pixels between ends and junctions, then closed loops.
    fn trace(&self) -> Vec<Vec<usize>> {
        let set: Vec<usize> = (0..self.on.len()).filter(|&k| self.on[k]).collect();
        let degree = |k: usize| self.neighbours(k).len();
        let mut used_edge = std::collections::HashSet::new();
        let key = |a: usize, b: usize| if a < b { (a, b) } else { (b, a) };
        let mut chains = Vec::new();
        let walk = |start: usize, first: usize, used: &mut std::collections::HashSet<_>| {
            let mut chain = vec![start];
            let (mut prev, mut cur) = (start, first);
            used.insert(key(prev, cur));
            loop {
                chain.push(cur);
                if degree(cur) != 2 || cur == start {
                    break;
                }
                let Some(next) = self
                    .neighbours(cur)
                    .into_iter()
                    .find(|&n| n != prev && !used.contains(&key(cur, n)))
                else {
                    break;
                };
                used.insert(key(cur, next));
                prev = cur;
                cur = next;
            }
            chain
        };
        for &k in &set {
            if degree(k) == 2 {
                continue;
            }
            for n in self.neighbours(k) {
                if !used_edge.contains(&key(k, n)) {
                    chains.push(walk(k, n, &mut used_edge));
                }
            }
        }
        for &k in &set {
            if degree(k) != 2 {
                continue;
            }
            for n in self.neighbours(k) {
                if !used_edge.contains(&key(k, n)) {
                    chains.push(walk(k, n, &mut used_edge));
                }
            }
        }
        chains.retain(|c| c.len() >= 2);
        chains
    }
}

/// The region's edges bucketed on a coarse grid, for exact distance queries.
pub struct EdgeIndex {
    origin: Point,
    cell: f64,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<(Point, Point)>>,
}

impl EdgeIndex {
    /// Buckets the edges of `region` in cells of `cell` mm.
    pub fn new(region: &Region, cell: f64) -> EdgeIndex {
        let (lo, hi) = bbox(region.iter().flatten().flatten()).unwrap_or(([0.0; 2], [0.0; 2]));
        let nx = ((hi[0] - lo[0]) / cell) as usize + 1;
        let ny = ((hi[1] - lo[1]) / cell) as usize + 1;
        let mut buckets = vec![Vec::new(); nx * ny];
        let cell_of = |p: Point| {
            (
                (((p[0] - lo[0]) / cell) as usize).min(nx - 1),
                (((p[1] - lo[1]) / cell) as usize).min(ny - 1),
            )
        };
        for c in region.iter().flatten() {
            let n = c.len();
            for k in 0..n {
                let (a, b) = (c[k], c[(k + 1) % n]);
                let (ia, ja) = cell_of(a);
                let (ib, jb) = cell_of(b);
                for j in ja.min(jb)..=ja.max(jb) {
                    for i in ia.min(ib)..=ia.max(ib) {
                        buckets[j * nx + i].push((a, b));
                    }
                }
            }
        }
        EdgeIndex {
            origin: lo,
            cell,
            nx,
            ny,
            buckets,
        }
    }

    /// How far a ray from `q` along the unit vector `dir` goes before it meets an edge,
    /// if it does within `reach`.
    pub fn ray(&self, q: Point, dir: Point, reach: f64) -> Option<f64> {
        let end = [q[0] + dir[0] * reach, q[1] + dir[1] * reach];
        let cell =
            |x: f64, o: f64, n: usize| (((x - o) / self.cell).floor().max(0.0) as usize).min(n - 1);
        let (i0, i1) = (
            cell(q[0].min(end[0]), self.origin[0], self.nx),
            cell(q[0].max(end[0]), self.origin[0], self.nx),
        );
        let (j0, j1) = (
            cell(q[1].min(end[1]), self.origin[1], self.ny),
            cell(q[1].max(end[1]), self.origin[1], self.ny),
        );
        let mut best: Option<f64> = None;
        for j in j0..=j1 {
            for i in i0..=i1 {
                for &(a, b) in &self.buckets[j * self.nx + i] {
                    // q + t·dir = a + s·(b − a), 0 ≤ s ≤ 1, t ≥ 0.
                    let e = [b[0] - a[0], b[1] - a[1]];
                    let den = dir[0] * e[1] - dir[1] * e[0];
                    if den.abs() < 1e-15 {
                        continue;
                    }
                    let aq = [a[0] - q[0], a[1] - q[1]];
                    let t = (aq[0] * e[1] - aq[1] * e[0]) / den;
                    let s = (aq[0] * dir[1] - aq[1] * dir[0]) / den;
                    if t >= 0.0 && t <= reach && (0.0..=1.0).contains(&s) {
                        best = Some(best.map_or(t, |b: f64| b.min(t)));
                    }
                }
            }
        }
        best
    }

    /// The exact distance from `q` to the nearest edge.
    pub fn distance(&self, q: Point) -> f64 {
        let ci = ((q[0] - self.origin[0]) / self.cell).floor() as i64;
        let cj = ((q[1] - self.origin[1]) / self.cell).floor() as i64;
        let mut best = f64::INFINITY;
        for ring in 0..(self.nx.max(self.ny) as i64 + 1) {
            // Every cell of this ring is at least (ring - 1) cells away.
            if best < (ring - 1).max(0) as f64 * self.cell {
                break;
            }
            for j in cj - ring..=cj + ring {
                for i in ci - ring..=ci + ring {
                    if (i - ci).abs() != ring && (j - cj).abs() != ring {
                        continue;
                    }
                    if i < 0 || j < 0 || i as usize >= self.nx || j as usize >= self.ny {
                        continue;
                    }
                    for &(a, b) in &self.buckets[j as usize * self.nx + i as usize] {
                        best = best.min(segment_distance(q, a, b));
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;
    use crate::geom::dist;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Region {
        region_from_contours(&[vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
    }

    fn length(l: &CentreLine) -> f64 {
        l.points.windows(2).map(|w| dist(w[0], w[1])).sum()
    }

    #[test]
    fn a_strip_has_one_centre_line_of_its_width() {
        for t in [0.3, 0.4, 0.6, 0.8] {
            let lines = centre_lines(&rect(0.0, 0.0, 20.0, t), 0.045);
            assert_eq!(lines.len(), 1, "{t}: {lines:?}");
            let l = &lines[0];
            assert!(
                (length(l) - (20.0 - t)).abs() < 0.3,
                "{t}: length {}",
                length(l)
            );
            for (p, w) in l.points.iter().zip(&l.widths) {
                assert!((p[1] - t / 2.0).abs() < 0.05, "{t}: {p:?}");
                if p[0] > t && p[0] < 20.0 - t {
                    assert!((w - t).abs() < 0.03, "{t}: width {w} at {p:?}");
                }
            }
        }
    }

    #[test]
    fn a_ring_gives_a_closed_centre_line() {
        let outer: Vec<Point> = (0..200)
            .map(|i| {
                let a = i as f64 / 200.0 * std::f64::consts::TAU;
                [10.0 * a.cos(), 10.0 * a.sin()]
            })
            .collect();
        let inner: Vec<Point> = outer
            .iter()
            .rev()
            .map(|p| [p[0] * 0.95, p[1] * 0.95])
            .collect();
        let lines = centre_lines(&region_from_contours(&[outer, inner]), 0.05);
        assert_eq!(lines.len(), 1, "{}", lines.len());
        let l = &lines[0];
        assert!(dist(l.points[0], *l.points.last().unwrap()) < 0.2);
        let len = length(l);
        assert!((len - std::f64::consts::TAU * 9.75).abs() < 1.0, "{len}");
    }

    #[test]
    fn a_t_junction_keeps_its_three_arms() {
        let r = crate::clip::union(&rect(0.0, 0.0, 20.0, 0.5), &rect(9.75, 0.0, 10.25, 10.0));
        let lines = centre_lines(&r, 0.04);
        let total: f64 = lines.iter().map(length).sum();
        assert!(total > 28.0 && total < 31.0, "{total}: {}", lines.len());
    }
}
