//! A bounding-volume hierarchy over the edges of closed 2D rings: the nearest edge to a
//! point, the crossing parity of a ray (inside or outside), and a lower bound of the
//! distance from a box to every edge, each in about log(n) steps instead of n.
//!
//! The tree is built once by median splits along the longer side of each node's box, and
//! stored flat (children after their parent), so queries walk an array with a small stack.

use glam::DVec2;

/// Edges per leaf: small leaves keep boxes tight, and four segment tests cost about what
/// one more level of boxes would.
const LEAF_EDGES: usize = 4;

/// One edge of a ring, `a` to `b`, with where it starts along its ring.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Edge {
    /// Start point.
    pub a: DVec2,
    /// End point.
    pub b: DVec2,
    /// Which ring it belongs to.
    pub ring: u32,
    /// Arc length along the ring at `a`.
    pub s0: f64,
}

impl Edge {
    /// The closest point of the edge to `p`, as the fraction along it (0 at `a`).
    pub fn closest_fraction(&self, p: DVec2) -> f64 {
        let d = self.b - self.a;
        let len2 = d.length_squared();
        if len2 <= 0.0 {
            return 0.0;
        }
        ((p - self.a).dot(d) / len2).clamp(0.0, 1.0)
    }
    /// Squared distance from `p`.
    pub fn distance_squared(&self, p: DVec2) -> f64 {
        let t = self.closest_fraction(p);
        (self.a + (self.b - self.a) * t).distance_squared(p)
    }
    /// Length.
    pub fn length(&self) -> f64 {
        self.a.distance(self.b)
    }
}

/// An axis-aligned 2D box.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Box2 {
    /// Lowest corner.
    pub min: DVec2,
    /// Highest corner.
    pub max: DVec2,
}

impl Box2 {
    /// The empty box (grows from nothing).
    pub const EMPTY: Box2 = Box2 {
        min: DVec2::splat(f64::INFINITY),
        max: DVec2::splat(f64::NEG_INFINITY),
    };
    /// The box around two points.
    pub fn of(a: DVec2, b: DVec2) -> Box2 {
        Box2 {
            min: a.min(b),
            max: a.max(b),
        }
    }
    /// The smallest box holding both.
    pub fn union(self, o: Box2) -> Box2 {
        Box2 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// Squared distance from a point (0 inside).
    pub fn distance_squared(&self, p: DVec2) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec2::ZERO);
        d.length_squared()
    }
    /// Squared distance between two boxes (0 if they touch).
    pub fn box_distance_squared(&self, o: &Box2) -> f64 {
        let d = (self.min - o.max).max(o.min - self.max).max(DVec2::ZERO);
        d.length_squared()
    }
    /// The corners, counter-clockwise from `min`.
    pub fn corners(&self) -> [DVec2; 4] {
        [
            self.min,
            DVec2::new(self.max.x, self.min.y),
            self.max,
            DVec2::new(self.min.x, self.max.y),
        ]
    }
    /// True when the point lies in the box (faces included).
    pub fn contains(&self, p: DVec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// Whether the segment `a`-`b` meets the box (Liang-Barsky clipping).
fn segment_meets_box(a: DVec2, b: DVec2, bx: &Box2) -> bool {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d.x, a.x - bx.min.x),
        (d.x, bx.max.x - a.x),
        (-d.y, a.y - bx.min.y),
        (d.y, bx.max.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// The exact distance between a segment and a box: zero if they meet, else the smallest
/// of the endpoints' distances to the box and the corners' distances to the segment (two
/// disjoint convex sets in the plane are closest at a vertex of one of them).
pub fn segment_box_distance(e: &Edge, bx: &Box2) -> f64 {
    if segment_meets_box(e.a, e.b, bx) {
        return 0.0;
    }
    let mut d2 = bx.distance_squared(e.a).min(bx.distance_squared(e.b));
    for c in bx.corners() {
        d2 = d2.min(e.distance_squared(c));
    }
    d2.sqrt()
}

#[derive(Copy, Clone, Debug)]
struct Node {
    bounds: Box2,
    /// Leaf: first edge index; inner: index of the right child (the left one follows).
    index: u32,
    /// Leaf: number of edges; inner: 0.
    count: u32,
}

/// The nearest edge to a point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Nearest {
    /// Index into [`EdgeTree::edges`].
    pub edge: usize,
    /// Fraction along the edge of the closest point.
    pub t: f64,
    /// Squared distance.
    pub distance_squared: f64,
}

/// The hierarchy. Edges are reordered so that each leaf's are contiguous.
#[derive(Clone, Debug)]
pub struct EdgeTree {
    edges: Vec<Edge>,
    nodes: Vec<Node>,
}

impl EdgeTree {
    /// Builds the tree over closed rings (the last point joins the first).
    pub fn new(rings: &[Vec<DVec2>]) -> EdgeTree {
        let mut edges = Vec::new();
        for (r, ring) in rings.iter().enumerate() {
            let mut s = 0.0;
            for i in 0..ring.len() {
                let e = Edge {
                    a: ring[i],
                    b: ring[(i + 1) % ring.len()],
                    ring: r as u32,
                    s0: s,
                };
                s += e.length();
                edges.push(e);
            }
        }
        let mut tree = EdgeTree {
            edges,
            nodes: Vec::new(),
        };
        if !tree.edges.is_empty() {
            let n = tree.edges.len();
            tree.build(0, n);
        }
        tree
    }

    /// The edges, in tree order.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The box around everything.
    pub fn bounds(&self) -> Box2 {
        self.nodes.first().map_or(Box2::EMPTY, |n| n.bounds)
    }

    fn build(&mut self, start: usize, end: usize) -> usize {
        let bounds = self.edges[start..end]
            .iter()
            .fold(Box2::EMPTY, |b, e| b.union(Box2::of(e.a, e.b)));
        let me = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            index: start as u32,
            count: (end - start) as u32,
        });
        if end - start <= LEAF_EDGES {
            return me;
        }
        let size = bounds.max - bounds.min;
        let mid = (start + end) / 2;
        let key = |e: &Edge| {
            let c = (e.a + e.b) * 0.5;
            if size.x >= size.y { c.x } else { c.y }
        };
        self.edges[start..end]
            .select_nth_unstable_by(mid - start, |p, q| key(p).total_cmp(&key(q)));
        self.build(start, mid);
        let right = self.build(mid, end);
        self.nodes[me].index = right as u32;
        self.nodes[me].count = 0;
        me
    }

    /// The nearest edge to `p` (`None` only for a tree without edges).
    pub fn nearest(&self, p: DVec2) -> Option<Nearest> {
        let mut best: Option<Nearest> = None;
        let mut best_d2 = f64::INFINITY;
        let mut stack = [0u32; 64];
        let mut top = 0;
        if self.nodes.is_empty() {
            return None;
        }
        stack[0] = 0;
        top += 1;
        while top > 0 {
            top -= 1;
            let id = stack[top] as usize;
            let node = &self.nodes[id];
            if node.bounds.distance_squared(p) >= best_d2 {
                continue;
            }
            if node.count > 0 {
                let first = node.index as usize;
                for (k, e) in self.edges[first..first + node.count as usize]
                    .iter()
                    .enumerate()
                {
                    let t = e.closest_fraction(p);
                    let d2 = (e.a + (e.b - e.a) * t).distance_squared(p);
                    if d2 < best_d2 {
                        best_d2 = d2;
                        best = Some(Nearest {
                            edge: first + k,
                            t,
                            distance_squared: d2,
                        });
                    }
                }
            } else if top + 2 <= stack.len() {
                // Visit the nearer child first (pushed last) so the bound tightens early.
                let (l, r) = (id + 1, node.index as usize);
                let (dl, dr) = (
                    self.nodes[l].bounds.distance_squared(p),
                    self.nodes[r].bounds.distance_squared(p),
                );
                let (far, near) = if dl <= dr { (r, l) } else { (l, r) };
                stack[top] = far as u32;
                stack[top + 1] = near as u32;
                top += 2;
            }
        }
        best
    }

    /// True when `p` is inside by the even-odd rule: the number of edges a ray from `p`
    /// towards +x crosses is odd. An edge counts when it straddles the ray's line with the
    /// half-open rule `(a.y > p.y) != (b.y > p.y)`, so a ray through a vertex counts once.
    pub fn inside(&self, p: DVec2) -> bool {
        let mut odd = false;
        let mut stack = [0u32; 64];
        let mut top = 0;
        if self.nodes.is_empty() {
            return false;
        }
        stack[0] = 0;
        top += 1;
        while top > 0 {
            top -= 1;
            let id = stack[top] as usize;
            let node = &self.nodes[id];
            let b = &node.bounds;
            if p.y < b.min.y || p.y > b.max.y || p.x > b.max.x {
                continue;
            }
            if node.count > 0 {
                let first = node.index as usize;
                for e in &self.edges[first..first + node.count as usize] {
                    if (e.a.y > p.y) != (e.b.y > p.y) {
                        let x = e.a.x + (p.y - e.a.y) * (e.b.x - e.a.x) / (e.b.y - e.a.y);
                        if x > p.x {
                            odd = !odd;
                        }
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = (id + 1) as u32;
                stack[top + 1] = node.index;
                top += 2;
            }
        }
        odd
    }

    /// The smallest distance from the box to any edge (0 when an edge meets it).
    pub fn box_distance(&self, bx: &Box2) -> f64 {
        let mut best = f64::INFINITY;
        self.visit_near(bx, f64::INFINITY, &mut |e| {
            best = best.min(segment_box_distance(e, bx));
            best
        });
        best
    }

    /// Calls `f` on every edge whose box lies within `reach` of `bx` and within the best
    /// distance `f` has returned so far (`f` returns the current bound; return `reach` to
    /// keep it fixed).
    pub fn visit_near(&self, bx: &Box2, reach: f64, f: &mut dyn FnMut(&Edge) -> f64) {
        let mut bound = reach;
        let mut stack = [0u32; 64];
        let mut top = 0;
        if self.nodes.is_empty() {
            return;
        }
        stack[0] = 0;
        top += 1;
        while top > 0 {
            top -= 1;
            let id = stack[top] as usize;
            let node = &self.nodes[id];
            let d2 = node.bounds.box_distance_squared(bx);
            if d2 > bound * bound {
                continue;
            }
            if node.count > 0 {
                let first = node.index as usize;
                for e in &self.edges[first..first + node.count as usize] {
                    if Box2::of(e.a, e.b).box_distance_squared(bx) <= bound * bound {
                        bound = bound.min(f(e));
                    }
                }
            } else if top + 2 <= stack.len() {
                stack[top] = (id + 1) as u32;
                stack[top + 1] = node.index;
                top += 2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec<DVec2>> {
        vec![vec![
            DVec2::new(-1.0, -1.0),
            DVec2::new(1.0, -1.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(-1.0, 1.0),
        ]]
    }

    fn brute_nearest(t: &EdgeTree, p: DVec2) -> f64 {
        t.edges()
            .iter()
            .map(|e| e.distance_squared(p))
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn nearest_and_inside_on_a_square() {
        let t = EdgeTree::new(&square());
        let n = t.nearest(DVec2::new(0.0, 3.0)).unwrap();
        assert!((n.distance_squared - 4.0).abs() < 1e-12);
        assert!(t.inside(DVec2::new(0.0, 0.0)));
        assert!(t.inside(DVec2::new(0.99, -0.99)));
        assert!(!t.inside(DVec2::new(1.01, 0.0)));
        // A ray through a vertex counts once.
        assert!(t.inside(DVec2::new(0.0, 1.0 - 1e-12)));
        assert!(!t.inside(DVec2::new(-2.0, 1.0)));
    }

    #[test]
    fn many_edges_agree_with_brute_force() {
        // A 1000-point star: the tree must find what a scan finds.
        let ring: Vec<DVec2> = (0..1000)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 1000.0;
                let r = 3.0 + (7.0 * a).sin();
                DVec2::new(r * a.cos(), r * a.sin())
            })
            .collect();
        let t = EdgeTree::new(&[ring]);
        for i in 0..500 {
            let p = DVec2::new((i as f64 * 0.37).sin() * 5.0, (i as f64 * 0.91).cos() * 5.0);
            let n = t.nearest(p).unwrap();
            assert!((n.distance_squared - brute_nearest(&t, p)).abs() < 1e-12);
        }
    }

    #[test]
    fn box_distance_is_a_lower_bound_and_exact_for_a_segment() {
        let t = EdgeTree::new(&square());
        let bx = Box2 {
            min: DVec2::new(2.0, -0.5),
            max: DVec2::new(3.0, 0.5),
        };
        assert!((t.box_distance(&bx) - 1.0).abs() < 1e-12);
        let inside = Box2 {
            min: DVec2::new(-0.5, -0.5),
            max: DVec2::new(0.5, 0.5),
        };
        assert!((t.box_distance(&inside) - 0.5).abs() < 1e-12);
        let straddle = Box2 {
            min: DVec2::new(0.5, -0.5),
            max: DVec2::new(1.5, 0.5),
        };
        assert_eq!(t.box_distance(&straddle), 0.0);
        // A diagonal segment passing a box's corner: the corner (1, 1) is nearest.
        let e = Edge {
            a: DVec2::new(0.0, 3.0),
            b: DVec2::new(3.0, 0.0),
            ring: 0,
            s0: 0.0,
        };
        let unit = Box2 {
            min: DVec2::ZERO,
            max: DVec2::ONE,
        };
        assert!((segment_box_distance(&e, &unit) - 0.5f64.sqrt()).abs() < 1e-12);
    }
}
