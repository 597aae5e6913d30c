//! Vertex removal where the field is made of planes (Schroeder, Zarge and Lorensen 1992):
//! what half-edge collapses cannot do along a box's edges turned off the lattice.
//!
//! A half-edge collapse `b → a` fills `b`'s hole with a fan from `a`; along a crease that
//! runs across the lattice, a face's vertex a fraction of a cell from the crease stands
//! beside the crease vertices, no fan from a neighbour covers the hole without turning a
//! triangle over, and the collapses stop (a random turn of a cube kept 2,338 triangles
//! after them). Here the hole is filled by ear clipping in its plane instead, which
//! covers any simple polygon:
//!
//! * only where the field's unit gradients at `b` and its neighbours take at most two
//!   values (two planes, to [`PLANAR`](super::PLANAR)): on curved surfaces the octree merge and the
//!   collapses already do what the tolerance allows;
//! * on one plane the whole ring of neighbours is one polygon; on a crease, the ring is cut
//!   at two neighbours on both planes into a polygon on each, closed by the chord between
//!   them (which runs along the crease);
//! * ears are clipped best-shaped first, never along an edge the mesh already has (that
//!   would join three triangles on it), and every new triangle is held to the refiner's
//!   split threshold by the field, faces out by it, and turns at most 60° from its plane.

use glam::{DVec2, DVec3};

use super::planes::{ON_PLANE_SHARE, Plane};
use super::{Chunk, Decimator, MIN_TURN_COS, ONTO_CREASE_SHARE};
use crate::dc::sampler::Sampler;

/// The most neighbours a removed vertex may have: ear clipping is quadratic in them, and
/// rings this long are rare.
const MAX_RING: usize = 48;

/// One polygon of the hole: its vertices in order (counter-clockwise seen from outside) and
/// the plane it lies on.
struct Piece {
    ring: Vec<u32>,
    plane: Plane,
}

impl Chunk {
    /// Removes `b` and fills its hole, if the field is planar around it and every new
    /// triangle keeps the tolerance; true when it did.
    pub(super) fn try_remove<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, b: u32) -> bool {
        let Some(ring) = self.ring(b) else {
            return false;
        };
        if ring.len() < 3 || ring.len() > MAX_RING || ring.iter().any(|&v| !self.free[v as usize]) {
            return false;
        }
        let Some(planes) = self.planes_of(b, &ring) else {
            return false;
        };
        let eps = ON_PLANE_SHARE * d.tolerance;
        let on = |p: &Plane, v: u32| p.distance(self.pos[v as usize]) <= eps;
        let Some(pieces) = split_ring(&ring, &planes, on, &self.pos, self.pos[b as usize]) else {
            return false;
        };
        let mut new_tris = Vec::new();
        for piece in pieces.iter().filter(|p| p.ring.len() >= 3) {
            let Some(tris) = self.clip_ears(piece) else {
                return false;
            };
            new_tris.extend(tris.into_iter().map(|t| (t, piece.plane)));
        }
        if new_tris.is_empty()
            || !self.adds_no_edge_twice(&ring, &new_tris)
            || !self.keeps_the_surface(d, b, &new_tris)
        {
            return false;
        }
        self.replace_fan(b, new_tris.into_iter().map(|(t, _)| t));
        true
    }

    /// `b`'s neighbours in order around it, counter-clockwise seen from outside; `None`
    /// unless they make one loop.
    fn ring(&self, b: u32) -> Option<Vec<u32>> {
        let steps: Vec<(u32, u32)> = self
            .fan(b)
            .map(|t| {
                let tri = self.tris[t as usize];
                let k = tri.iter().position(|&v| v == b).unwrap_or(0);
                (tri[(k + 1) % 3], tri[(k + 2) % 3])
            })
            .collect();
        let &(first, mut next) = steps.first()?;
        let mut ring = vec![first];
        while next != first {
            if ring.len() >= steps.len() || ring.contains(&next) {
                return None;
            }
            ring.push(next);
            let here = next;
            let mut from = steps.iter().filter(|s| s.0 == here);
            next = from.next()?.1;
            if from.next().is_some() {
                return None;
            }
        }
        (ring.len() == steps.len()).then_some(ring)
    }

    /// Ear clipping of one piece in its plane, best-shaped ear first; `None` when some
    /// step finds no ear (the piece is not a simple polygon there) or only ears whose new
    /// edge the mesh already has.
    fn clip_ears(&self, piece: &Piece) -> Option<Vec<[u32; 3]>> {
        let n = piece.plane.n;
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        let flat: Vec<DVec2> = piece
            .ring
            .iter()
            .map(|&v| {
                let p = self.pos[v as usize];
                DVec2::new(p.dot(u), p.dot(w))
            })
            .collect();
        let mut left: Vec<usize> = (0..piece.ring.len()).collect();
        let mut out = Vec::with_capacity(piece.ring.len() - 2);
        while left.len() > 3 {
            let mut best: Option<(f64, usize)> = None;
            for i in 0..left.len() {
                let (p, c, q) = (
                    left[(i + left.len() - 1) % left.len()],
                    left[i],
                    left[(i + 1) % left.len()],
                );
                let (vp, vq) = (piece.ring[p], piece.ring[q]);
                if !is_ear(&flat, &left, p, c, q) || self.neighbours(vp).binary_search(&vq).is_ok()
                {
                    continue;
                }
                let shape = min_angle_sin(flat[p], flat[c], flat[q]);
                if best.is_none_or(|(s, _)| shape > s) {
                    best = Some((shape, i));
                }
            }
            let (_, i) = best?;
            let k = left.len();
            let (p, c, q) = (left[(i + k - 1) % k], left[i], left[(i + 1) % k]);
            out.push([p, c, q].map(|j| piece.ring[j]));
            left.remove(i);
        }
        let last = [left[0], left[1], left[2]];
        if cross(flat[last[0]], flat[last[1]], flat[last[2]]) <= 0.0 {
            return None;
        }
        out.push(last.map(|j| piece.ring[j]));
        Some(out)
    }

    /// Whether every edge the new triangles add (the chord between two pieces, the
    /// diagonals within one) is new to the mesh: one it has already would be shared by
    /// three triangles or more.
    fn adds_no_edge_twice(&self, ring: &[u32], new_tris: &[([u32; 3], Plane)]) -> bool {
        let k = ring.len();
        let on_ring = |x: u32, y: u32| {
            (0..k).any(|i| {
                let (p, q) = (ring[i], ring[(i + 1) % k]);
                (p, q) == (x, y) || (p, q) == (y, x)
            })
        };
        new_tris.iter().all(|(t, _)| {
            (0..3).all(|e| {
                let (x, y) = (t[e], t[(e + 1) % 3]);
                on_ring(x, y) || self.neighbours(x).binary_search(&y).is_err()
            })
        })
    }

    /// Whether the new triangles may replace `b`'s fan: no triangle the mesh already has,
    /// each within the refiner's split threshold of the surface by the field and facing
    /// out by it, turned at most 60° from its plane, and little volume swept.
    fn keeps_the_surface<S: Sampler>(
        &self,
        d: &mut Decimator<'_, S>,
        b: u32,
        new_tris: &[([u32; 3], Plane)],
    ) -> bool {
        let pb = self.pos[b as usize];
        let min_area = (d.tolerance * d.tolerance) * 1e-6;
        let bound = ONTO_CREASE_SHARE * d.tolerance;
        let mut six_volume = 0.0;
        for (t, plane) in new_tris {
            let exists = self
                .fan(t[0])
                .any(|o| t.iter().all(|v| self.tris[o as usize].contains(v)));
            if exists {
                return false;
            }
            let p = t.map(|v| self.pos[v as usize]);
            let normal = (p[1] - p[0]).cross(p[2] - p[0]);
            if normal.length() <= min_area || normal.normalize().dot(plane.n) < MIN_TURN_COS {
                return false;
            }
            six_volume += (p[0] - pb).dot((p[1] - pb).cross(p[2] - pb));
            if self.deviation(d, &p, bound, true) > bound {
                return false;
            }
        }
        let twice_area: f64 = self
            .fan(b)
            .map(|t| {
                let [p, q, r] = self.tris[t as usize].map(|v| self.pos[v as usize]);
                (q - p).cross(r - p).length()
            })
            .sum();
        six_volume.abs() / 6.0 <= d.tolerance * twice_area / 2.0
    }

    /// Takes `b` out and puts `new_tris` in its fan's place.
    fn replace_fan(&mut self, b: u32, new_tris: impl Iterator<Item = [u32; 3]>) {
        let fan: Vec<u32> = self.fan(b).collect();
        for t in fan {
            self.alive_t[t as usize] = false;
        }
        for t in new_tris {
            self.add_triangle(t);
        }
        self.alive_v[b as usize] = false;
        self.around[b as usize].clear();
    }
}

/// Cuts `b`'s ring into the polygons that fill its hole: the whole ring when it lies on
/// one plane; on a crease, the two runs between two neighbours on both planes, each on its
/// own plane and closed by the chord between those two, chosen nearest `b` (the vertex
/// removed lies on that chord when it is on the crease).
fn split_ring(
    ring: &[u32],
    planes: &[Plane],
    on: impl Fn(&Plane, u32) -> bool,
    pos: &[DVec3],
    pb: DVec3,
) -> Option<Vec<Piece>> {
    for plane in planes {
        if ring.iter().all(|&v| on(plane, v)) {
            return Some(vec![Piece {
                ring: ring.to_vec(),
                plane: *plane,
            }]);
        }
    }
    let [p0, p1] = planes else {
        return None;
    };
    let both: Vec<usize> = (0..ring.len())
        .filter(|&i| on(p0, ring[i]) && on(p1, ring[i]))
        .collect();
    let k = ring.len();
    // The run from `i` to `j`, both ends included.
    let run = |i: usize, j: usize| -> Vec<u32> {
        let mut out = vec![ring[i]];
        let mut x = i;
        while x != j {
            x = (x + 1) % k;
            out.push(ring[x]);
        }
        out
    };
    let mut best: Option<(f64, Vec<Piece>)> = None;
    for &i in &both {
        for &j in &both {
            if i == j {
                continue;
            }
            let (first, second) = (run(i, j), run(j, i));
            for (a, c) in [(p0, p1), (p1, p0)] {
                if !first.iter().all(|&v| on(a, v)) || !second.iter().all(|&v| on(c, v)) {
                    continue;
                }
                let Some(miss) = off_chord(pb, pos[ring[i] as usize], pos[ring[j] as usize]) else {
                    continue;
                };
                if best.as_ref().is_none_or(|(m, _)| miss < *m) {
                    let pieces = vec![
                        Piece {
                            ring: first.clone(),
                            plane: *a,
                        },
                        Piece {
                            ring: second.clone(),
                            plane: *c,
                        },
                    ];
                    best = Some((miss, pieces));
                }
            }
        }
    }
    best.map(|(_, pieces)| pieces)
}

/// How far `p` is from the chord `a b`; `None` unless it lies between the chord's ends.
fn off_chord(p: DVec3, a: DVec3, b: DVec3) -> Option<f64> {
    let ab = b - a;
    let t = (p - a).dot(ab) / ab.length_squared();
    (t > 0.0 && t < 1.0).then(|| p.distance(a + ab * t))
}

/// Whether corner `c` between `p` and `q` of the polygon left is an ear: convex, and no
/// other corner left inside it or on its sides.
fn is_ear(flat: &[DVec2], left: &[usize], p: usize, c: usize, q: usize) -> bool {
    let (a, b, e) = (flat[p], flat[c], flat[q]);
    let scale = (b - a).length_squared().max((e - b).length_squared());
    if cross(a, b, e) <= 1e-12 * scale {
        return false;
    }
    left.iter()
        .filter(|&&x| x != p && x != c && x != q)
        .all(|&x| {
            let y = flat[x];
            cross(a, b, y) < 0.0 || cross(b, e, y) < 0.0 || cross(e, a, y) < 0.0
        })
}

/// Twice the signed area of the triangle `a b c` in the plane.
fn cross(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// The sine of a triangle's smallest angle (0 for a degenerate one).
fn min_angle_sin(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    let twice = cross(a, b, c).abs();
    let [ab, bc, ca] = [(b - a).length(), (c - b).length(), (a - c).length()];
    // sin(angle at a) = 2 area / (|ab| |ca|), and so on.
    [ab * ca, ab * bc, bc * ca]
        .into_iter()
        .map(|l| if l > 0.0 { twice / l } else { 0.0 })
        .fold(f64::INFINITY, f64::min)
}
