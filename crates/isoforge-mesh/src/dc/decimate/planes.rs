//! Where the field is made of planes (a box, a prism, any shape cut by flat faces), its
//! vertices are put on them before the collapses: what dual contouring's vertices along an
//! edge turned off the lattice miss.
//!
//! Along such an edge, a finest cell's vertex can sit half a cell inside the solid, between
//! the two faces, with triangles on it that cut the edge (a random turn of a cube missed
//! its tolerance by 4 there, and the collapses stopped: every way of moving such a vertex
//! onto a neighbour turned a triangle over). Two steps, both where the field's gradient
//! says which plane a vertex is on (one gradient per vertex, kept in [`Chunk::plane`]):
//!
//! * a vertex off every plane around it moves onto them: onto the line where two meet
//!   (the crease) if it can, else onto the nearer plane where the field says that is
//!   the surface; at most [`SNAP_CELLS`], and never turning a triangle over;
//! * an edge from one plane's vertex to the other's that cuts the crease by more than the
//!   tolerance is split where it crosses the crease: the vertices beside it can then move
//!   onto the crease without turning a triangle over, and `removal.rs` keeps the crease by
//!   chords along it.
//!
//! A new vertex must be on the surface by the field, so on curved faces (whose tangent
//! planes also count as planes here) nothing moves off the surface either.

use glam::DVec3;

use super::{Chunk, Decimator, PLANAR};
use crate::dc::sampler::Sampler;

/// A vertex lies on a plane when it is within this share of the tolerance of it (the
/// mesher's vertices on a turned cube's faces are within half a tolerance of them).
pub(super) const ON_PLANE_SHARE: f64 = 1.0;

/// The farthest a vertex is moved, or a crease point put from its edge, in finest cells
/// (vertices cutting a turned cube's edges were up to 0.6 of a cell off it).
const SNAP_CELLS: f64 = 1.0;

/// A vertex moved or added lands within this share of the tolerance of the surface, by
/// the field.
const ON_SURFACE_SHARE: f64 = 0.1;

/// An edge is split at a crease only where its planes' normals are more than 30° apart
/// (cosine): at a shallower crease, a chord across it stays near both planes.
const CREASE_SPLIT_COS: f64 = 0.866;

/// A split's crease point keeps at least this share of the edge from either end.
const SPLIT_END: f64 = 0.05;

/// A plane of the field: points `x` with `n · x = c`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plane {
    pub n: DVec3,
    pub c: f64,
}

impl Plane {
    /// How far `p` is from the plane.
    pub fn distance(&self, p: DVec3) -> f64 {
        (self.n.dot(p) - self.c).abs()
    }

    /// The point of the plane nearest `p`.
    fn foot(&self, p: DVec3) -> DVec3 {
        p - self.n * (self.n.dot(p) - self.c)
    }

    fn same(&self, o: &Plane) -> bool {
        self.n.distance(o.n) < PLANAR
    }
}

impl Chunk {
    /// The field's plane at each vertex.
    pub(super) fn measure_planes<S: Sampler>(&mut self, d: &mut Decimator<'_, S>) {
        self.plane = (0..self.pos.len())
            .map(|v| {
                (self.free[v] && self.alive_v[v])
                    .then(|| plane_at(d, self.pos[v]))
                    .flatten()
            })
            .collect();
    }

    /// The planes at `b` and its ring, `b`'s first; `None` when they are more than two
    /// (or the field says nothing at one of them).
    pub(super) fn planes_of(&self, b: u32, ring: &[u32]) -> Option<Vec<Plane>> {
        let planes = std::iter::once(b).chain(ring.iter().copied());
        at_most_two(planes.map(|v| self.plane[v as usize]), Plane::same)
    }

    /// The field's unit gradient at vertex `v`: its plane's normal where measured, else
    /// evaluated; `None` where the field says nothing.
    pub(super) fn normal_at<S: Sampler>(&self, d: &mut Decimator<'_, S>, v: u32) -> Option<DVec3> {
        if let Some(p) = self.plane.get(v as usize).copied().flatten() {
            return Some(p.n);
        }
        let g = d.field.grad(d.sampler, &mut d.ev, self.pos[v as usize]);
        let n = DVec3::new(g[1], g[2], g[3]).normalize_or_zero();
        (n != DVec3::ZERO && n.is_finite()).then_some(n)
    }

    /// Moves each vertex that is off every plane around it onto them (module doc).
    pub(super) fn snap_onto_planes<S: Sampler>(&mut self, d: &mut Decimator<'_, S>) {
        let eps = ON_PLANE_SHARE * d.tolerance;
        for v in 0..self.pos.len() as u32 {
            if !self.free[v as usize] || !self.alive_v[v as usize] {
                continue;
            }
            let Some(planes) = self.planes_of(v, &self.neighbours(v)) else {
                continue;
            };
            let p = self.pos[v as usize];
            if planes.iter().any(|pl| pl.distance(p) <= eps) {
                continue;
            }
            // The crease first (a vertex there lets `removal.rs` keep the crease by chords
            // along it), then the planes, nearer first.
            let mut targets: Vec<DVec3> = Vec::with_capacity(3);
            if let [a, b] = planes.as_slice() {
                targets.extend(onto_line(p, a, b));
            }
            let mut feet: Vec<DVec3> = planes.iter().map(|pl| pl.foot(p)).collect();
            feet.sort_by(|x, y| x.distance(p).total_cmp(&y.distance(p)));
            targets.extend(feet);
            let to = targets.into_iter().find(|&t| {
                t.distance(p) <= SNAP_CELLS * d.cell
                    && on_surface(d, t, ON_SURFACE_SHARE * d.tolerance)
                    && self.moves_without_flipping(v, t)
            });
            if let Some(to) = to {
                self.move_vertex(d, v, to);
            }
        }
    }

    /// Splits, at the crease, each edge between two planes' vertices that cuts it (module
    /// doc).
    pub(super) fn split_across_creases<S: Sampler>(&mut self, d: &mut Decimator<'_, S>) {
        // Triangles added by a split are looked at too, as the loop reaches them.
        let mut t = 0;
        while t < self.tris.len() {
            if self.alive_t[t] {
                let tri = self.tris[t];
                for k in 0..3 {
                    if self.split_if_across(d, tri[k], tri[(k + 1) % 3]) {
                        break;
                    }
                }
            }
            t += 1;
        }
    }

    /// Splits edge `x y` at the crease of their planes if it cuts that crease; true when it
    /// did.
    fn split_if_across<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, x: u32, y: u32) -> bool {
        let eps = ON_PLANE_SHARE * d.tolerance;
        let (Some(a), Some(b)) = (self.plane[x as usize], self.plane[y as usize]) else {
            return false;
        };
        if !self.free[x as usize] || !self.free[y as usize] {
            return false;
        }
        let (px, py) = (self.pos[x as usize], self.pos[y as usize]);
        // Two planes at a real crease, each end on its own only.
        if a.same(&b) || a.n.dot(b.n) > CREASE_SPLIT_COS {
            return false;
        }
        let on = |plane: &Plane, p: DVec3| plane.distance(p) <= eps;
        if !on(&a, px) || !on(&b, py) || on(&a, py) || on(&b, px) {
            return false;
        }
        // The crease point at the chord's place along the crease.
        let Some(at) = onto_line((px + py) * 0.5, &a, &b) else {
            return false;
        };
        let chord = py - px;
        let s = (at - px).dot(chord) / chord.length_squared();
        let cut = px.lerp(py, s.clamp(0.0, 1.0)).distance(at);
        if !(SPLIT_END..=1.0 - SPLIT_END).contains(&s)
            || cut <= eps
            || cut > SNAP_CELLS * d.cell
            || !on_surface(d, at, ON_SURFACE_SHARE * d.tolerance)
        {
            return false;
        }
        // Each of the two triangles on the edge is cut in two; no piece may turn over.
        let sides: Vec<u32> = self
            .fan(x)
            .filter(|&t| self.tris[t as usize].contains(&y))
            .collect();
        if sides.len() != 2 {
            return false;
        }
        let new = self.pos.len() as u32;
        let mut pieces = Vec::with_capacity(4);
        for &t in &sides {
            let tri = self.tris[t as usize];
            let before = normal(tri.map(|v| self.pos[v as usize]));
            for gone in [x, y] {
                let piece = tri.map(|v| if v == gone { new } else { v });
                let after = normal(piece.map(|v| if v == new { at } else { self.pos[v as usize] }));
                if after.dot(before) <= 0.0 || after.length() <= 1e-12 * d.cell * d.cell {
                    return false;
                }
                pieces.push(piece);
            }
        }
        let plane = plane_at(d, at);
        self.add_vertex(at, plane);
        for t in sides {
            self.alive_t[t as usize] = false;
        }
        for piece in pieces {
            self.add_triangle(piece);
        }
        true
    }

    /// Whether moving `v` to `to` keeps every triangle around it facing the way it did.
    fn moves_without_flipping(&self, v: u32, to: DVec3) -> bool {
        self.fan(v).all(|t| {
            let tri = self.tris[t as usize];
            let before = normal(tri.map(|w| self.pos[w as usize]));
            let after = normal(tri.map(|w| if w == v { to } else { self.pos[w as usize] }));
            after.dot(before) > 0.0
        })
    }

    fn move_vertex<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, v: u32, to: DVec3) {
        self.pos[v as usize] = to;
        self.plane[v as usize] = plane_at(d, to);
        if let Some(out) = d.verts.get_mut(v as usize) {
            *out = to.as_vec3().to_array();
        }
        for t in self.around[v as usize].clone() {
            self.dev[t as usize] = f64::NAN;
        }
    }
}

/// The plane of the field at `p`, by its gradient there (where the field is linear,
/// F / |∇F| is the distance to that plane exactly).
fn plane_at<S: Sampler>(d: &mut Decimator<'_, S>, p: DVec3) -> Option<Plane> {
    let g = d.field.grad(d.sampler, &mut d.ev, p);
    let grad = DVec3::new(g[1], g[2], g[3]);
    let n = grad.normalize_or_zero();
    (n != DVec3::ZERO && n.is_finite() && g[0].is_finite()).then(|| Plane {
        n,
        c: n.dot(p) - g[0] / grad.length(),
    })
}

/// The distinct ones among `items` (by `same`), first seen first; `None` as soon as one is
/// missing or a third turns up.
pub(super) fn at_most_two<T: Copy>(
    items: impl IntoIterator<Item = Option<T>>,
    same: impl Fn(&T, &T) -> bool,
) -> Option<Vec<T>> {
    let mut distinct: Vec<T> = Vec::with_capacity(2);
    for item in items {
        let item = item?;
        if distinct.iter().any(|x| same(x, &item)) {
            continue;
        }
        if distinct.len() == 2 {
            return None;
        }
        distinct.push(item);
    }
    Some(distinct)
}

/// Whether `p` is within `within` of the surface, by the field's first-order distance.
fn on_surface<S: Sampler>(d: &mut Decimator<'_, S>, p: DVec3, within: f64) -> bool {
    let g = d.field.grad(d.sampler, &mut d.ev, p);
    g[0].abs() <= within * DVec3::new(g[1], g[2], g[3]).length()
}

/// The point nearest `p` on the line where planes `a` and `b` meet (`None` when they are
/// nearly parallel).
pub(super) fn onto_line(p: DVec3, a: &Plane, b: &Plane) -> Option<DVec3> {
    let dir = a.n.cross(b.n);
    let l2 = dir.length_squared();
    if l2 < 1e-6 {
        return None;
    }
    // A point on both planes, then along the line to where it is nearest `p`.
    let on = (b.n.cross(dir) * a.c + dir.cross(a.n) * b.c) / l2;
    Some(on + dir * (p - on).dot(dir) / l2)
}

/// A triangle's normal, as long as twice its area.
fn normal(t: [DVec3; 3]) -> DVec3 {
    (t[1] - t[0]).cross(t[2] - t[0])
}
