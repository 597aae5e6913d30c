//! After the refiner: an edge whose middle strays from the surface is turned to the other
//! diagonal of its two triangles where that diagonal keeps nearer.
//!
//! The refiner splits edges but never changes which vertices a triangle joins, and
//! sometimes that is what is wrong: of the quadrilateral two triangles make, one diagonal
//! may cut under a crease or across a bulge while the other runs along the surface. Under
//! the grown heart of the offset-shell example at depth 7, a chord two cells long between
//! two merged leaves' vertices was left 2.03 tolerances off (the refiner did not split
//! it), where the other diagonal of its pair keeps within the tolerance.
//!
//! So the triangles are held in chunks of [`CHUNK`]; in each, every edge whose middle is
//! farther than [`STRAY_SHARE`] of the tolerance from the surface (|F| / |∇F|), between two
//! triangles that turn by more than [`MIN_TURN_COS`] (a flat pair gains nothing), is
//! turned when:
//!
//! * the new edge joins two vertices no edge of the mesh joins yet (one of them has all its
//!   triangles in the chunk, so that is known): the mesh stays closed and manifold;
//! * no corner of the pair is farther than [`OFF_SHARE`] of the tolerance from the surface;
//! * both new triangles face the way the field does at their centres and the way the old
//!   pair did (no fold), and neither is a needle ([`THINNEST`]);
//! * the farthest of the new pair's sample points (the new edge's quarters and middle, each
//!   triangle's centre and the points halfway from it to the edges' middles) is nearer the
//!   surface than the old pair's was, by [`GAIN`].
//!
//! A turned edge's four neighbours are looked at again; each pair's error only falls, and
//! the turns per chunk are bounded, so it ends. Edges across a chunk's seam stay as they
//! are. The vertices do not move and none is added: only which of them the triangles join.

use std::cell::RefCell;
use std::io;

use glam::DVec3;

use super::left_off::LeftOff;
use super::narrowed::Narrowed;
use super::refine::{height, longest_side};
use super::sampler::Sampler;
use crate::int_hash::IntMap;
use crate::sink::MeshSink;

/// Triangles per chunk: the refiner's output comes slab by slab, so a chunk holds whole
/// neighbourhoods but for its seams.
const CHUNK: usize = 1 << 15;

/// An edge is looked at when its middle is farther than this share of the tolerance from
/// the surface (the refiner's split threshold).
const STRAY_SHARE: f64 = 0.8;

/// A pair with a corner farther than this share of the tolerance from the surface is left
/// as it is (the refiner moves every vertex it can to within half the tolerance). Beside
/// such a corner every way of joining misses, and the sample points say little: without
/// this, turns on spaceship's rippled hull, each better by its own points, took its
/// largest distance from 5.26 to 5.90 tolerances at depth 8.
const OFF_SHARE: f64 = 0.5;

/// Two triangles whose normals are closer than this (cosine; 10°) are nearly flat across
/// their edge, and turning it changes little.
const MIN_TURN_COS: f64 = 0.985;

/// A turn must bring the pair's farthest point at least this much nearer (a share of
/// what it was), so that turns cannot go back and forth.
const GAIN: f64 = 0.9;

/// A new triangle lower than this share of its longest side is a needle: passed over
/// (written in single precision and read back, its normal is noise).
const THINNEST: f64 = 1e-3;

/// Turns per chunk at most, per triangle: a guard only (each turn lowers an error).
const TURNS_PER_TRIANGLE: usize = 2;

/// Turns straying edges to the other diagonal, on the way to `inner` (see the module doc).
pub struct Flipper<'a, S: Sampler> {
    sampler: &'a S,
    ev: S::Evals,
    field: Narrowed<S>,
    tolerance: f64,
    inner: &'a mut dyn MeshSink,
    /// Every vertex so far (as written: single precision).
    verts: Vec<[f32; 3]>,
    /// The chunk's triangles, in arrival order.
    tris: Vec<[u32; 3]>,
    /// A triangle of the chunk at each of its vertices.
    at: IntMap<u32, u32>,
    /// Edges turned so far.
    pub turned: u64,
    /// The places the refiner left off the surface (`left_off.rs`): a turn takes its
    /// edge's middle and its two triangles' centres off the mesh.
    left_off: Option<&'a RefCell<LeftOff>>,
}

impl<'a, S: Sampler> Flipper<'a, S> {
    /// Holds the mesh to within `tolerance` (model units), reading the field through
    /// `sampler` on a lattice of `cell`-sized cells.
    pub fn new(sampler: &'a S, tolerance: f64, cell: f64, inner: &'a mut dyn MeshSink) -> Self {
        Flipper {
            sampler,
            ev: sampler.evals(),
            field: Narrowed::new(sampler, cell),
            tolerance,
            inner,
            verts: Vec::new(),
            tris: Vec::new(),
            at: IntMap::default(),
            turned: 0,
            left_off: None,
        }
    }

    /// Forgets, in `places`, the places its turns take off the mesh.
    pub fn keeping_places(mut self, places: &'a RefCell<LeftOff>) -> Self {
        self.left_off = Some(places);
        self
    }

    /// Writes the last chunk; call once everything has come.
    pub fn finish(&mut self) -> io::Result<()> {
        self.flush()
    }

    /// Turns what pays in the chunk, writes it and starts the next.
    fn flush(&mut self) -> io::Result<()> {
        let mut tris = std::mem::take(&mut self.tris);
        self.at.clear();
        for (i, t) in tris.iter().enumerate() {
            for &v in t {
                self.at.insert(v, i as u32);
            }
        }
        self.turn_edges(&mut tris);
        for &t in &tris {
            let corners = t.map(|i| self.verts[i as usize]);
            self.inner.triangle(t, corners)?;
        }
        tris.clear();
        self.tris = tris;
        Ok(())
    }

    /// |F| / |∇F| at `p`: the first-order distance to the surface; `None` where the
    /// field has no slope to read it by (a kink, or off its numbers).
    fn distance(&mut self, p: DVec3) -> Option<f64> {
        let g = self.field.grad(self.sampler, &mut self.ev, p);
        let d = g[0].abs() / DVec3::new(g[1], g[2], g[3]).length();
        d.is_finite().then_some(d)
    }

    /// The farthest from the surface of the sample points of triangles (a, b, c) and
    /// (b, a, d): their edge a–b's quarters and middle, and in each its centre and the
    /// points halfway from there to its edges' middles (the outer edges are the same
    /// whichever way the pair is joined).
    fn pair_error(&mut self, a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Option<f64> {
        let mut far = 0.0f64;
        for t in [0.25, 0.5, 0.75] {
            far = far.max(self.distance(a.lerp(b, t))?);
        }
        for [x, y, z] in [[a, b, c], [b, a, d]] {
            let centre = (x + y + z) / 3.0;
            far = far.max(self.distance(centre)?);
            for (u, v) in [(x, y), (y, z), (z, x)] {
                far = far.max(self.distance((centre + (u + v) * 0.5) * 0.5)?);
            }
        }
        Some(far)
    }

    /// The field's gradient at `p`.
    fn gradient(&mut self, p: DVec3) -> DVec3 {
        let g = self.field.grad(self.sampler, &mut self.ev, p);
        DVec3::new(g[1], g[2], g[3])
    }

    /// The turns that pay among `tris` (see the module doc).
    fn turn_edges(&mut self, tris: &mut [[u32; 3]]) {
        // Directed edge -> the triangle it runs along.
        let mut along: IntMap<(u32, u32), u32> = IntMap::default();
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                along.insert((t[k], t[(k + 1) % 3]), i as u32);
            }
        }
        // Each undirected edge inside the chunk once, lower index first, in chunk order.
        let mut work: Vec<(u32, u32)> = Vec::new();
        for t in tris.iter() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a < b && along.contains_key(&(b, a)) {
                    work.push((a, b));
                }
            }
        }
        let mut budget = tris.len() * TURNS_PER_TRIANGLE;
        let mut next = 0;
        while next < work.len() && budget > 0 {
            let (a, b) = work[next];
            next += 1;
            let (Some(&t1), Some(&t2)) = (along.get(&(a, b)), along.get(&(b, a))) else {
                continue;
            };
            let Some(turn) = self.turn(tris, &along, a, b, t1, t2) else {
                continue;
            };
            // (a, b, c) and (b, a, d) become (a, d, c) and (d, b, c).
            let (c, d) = turn;
            if let Some(places) = self.left_off {
                let p = |v: u32| DVec3::from(self.verts[v as usize].map(f64::from));
                let (pa, pb, pc, pd) = (p(a), p(b), p(c), p(d));
                let mut places = places.borrow_mut();
                for gone in [(pa + pb) * 0.5, (pa + pb + pc) / 3.0, (pb + pa + pd) / 3.0] {
                    places.gone(gone.to_array());
                }
            }
            for (u, v) in [(a, b), (b, a), (b, c), (c, a), (a, d), (d, b)] {
                along.remove(&(u, v));
            }
            tris[t1 as usize] = [a, d, c];
            tris[t2 as usize] = [d, b, c];
            // a is only in the first now, b only in the second; c and d in both.
            self.at.insert(a, t1);
            self.at.insert(b, t2);
            for (i, t) in [(t1, [a, d, c]), (t2, [d, b, c])] {
                for k in 0..3 {
                    along.insert((t[k], t[(k + 1) % 3]), i);
                }
            }
            for (u, v) in [(a, d), (d, b), (b, c), (c, a)] {
                work.push((u.min(v), u.max(v)));
            }
            self.turned += 1;
            budget -= 1;
        }
    }

    /// Whether edge `a`–`b` (in triangles `t1` = (a, b, c) and `t2` = (b, a, d)) turns, and
    /// if so its new ends (c, d).
    fn turn(
        &mut self,
        tris: &[[u32; 3]],
        along: &IntMap<(u32, u32), u32>,
        a: u32,
        b: u32,
        t1: u32,
        t2: u32,
    ) -> Option<(u32, u32)> {
        let c = third(tris[t1 as usize], a, b)?;
        let d = third(tris[t2 as usize], b, a)?;
        if c == d {
            return None;
        }
        let p = |v: u32| DVec3::from(self.verts[v as usize].map(f64::from));
        let (pa, pb, pc, pd) = (p(a), p(b), p(c), p(d));
        let (n1, n2) = (normal(pa, pb, pc)?, normal(pb, pa, pd)?);
        if n1.dot(n2) > MIN_TURN_COS {
            return None;
        }
        let threshold = STRAY_SHARE * self.tolerance;
        let middle = self.distance((pa + pb) * 0.5)?;
        if middle <= threshold {
            return None;
        }
        // The new edge must be new: every edge from c (or from d) is in the chunk when all
        // of its triangles are.
        if along.contains_key(&(c, d)) || along.contains_key(&(d, c)) {
            return None;
        }
        let complete = |v: u32| {
            self.at
                .get(&v)
                .is_some_and(|&i| fan_complete(tris, along, v, tris[i as usize]))
        };
        if !(complete(c) || complete(d)) {
            return None;
        }
        let (m1, m2) = (normal(pa, pd, pc)?, normal(pd, pb, pc)?);
        let before = n1 + n2;
        if [(pa, pd, pc), (pd, pb, pc)]
            .iter()
            .any(|&(x, y, z)| needle(x, y, z))
            || m1.dot(before) <= 0.0
            || m2.dot(before) <= 0.0
        {
            return None;
        }
        let (g1, g2) = (
            self.gradient((pa + pd + pc) / 3.0),
            self.gradient((pd + pb + pc) / 3.0),
        );
        if m1.dot(g1) <= 0.0 || m2.dot(g2) <= 0.0 {
            return None;
        }
        for v in [pa, pb, pc, pd] {
            if self.distance(v)? > self.tolerance * OFF_SHARE {
                return None;
            }
        }
        let old = self.pair_error(pa, pb, pc, pd)?.max(middle);
        let new = self.pair_error(pc, pd, pb, pa)?;
        (new < old * GAIN).then_some((c, d))
    }
}

impl<S: Sampler> MeshSink for Flipper<'_, S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.verts.push(p);
        self.inner.vertex(p)
    }

    fn triangle(&mut self, t: [u32; 3], _corners: [[f32; 3]; 3]) -> io::Result<()> {
        if t.iter().any(|&v| v as usize >= self.verts.len()) {
            return Err(io::Error::other(format!(
                "triangle {t:?} before its vertices ({} so far)",
                self.verts.len()
            )));
        }
        self.tris.push(t);
        if self.tris.len() >= CHUNK {
            self.flush()?;
        }
        Ok(())
    }
}

/// The corner of `t` that is neither `a` nor `b`, where `t` runs from `a` to `b`.
fn third(t: [u32; 3], a: u32, b: u32) -> Option<u32> {
    (0..3)
        .find(|&k| t[k] == a && t[(k + 1) % 3] == b)
        .map(|k| t[(k + 2) % 3])
}

/// The unit normal of triangle (a, b, c), counter-clockwise; `None` if it has no area.
fn normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    (b - a).cross(c - a).try_normalize()
}

/// Whether triangle (a, b, c) is lower than [`THINNEST`] of its longest side.
fn needle(a: DVec3, b: DVec3, c: DVec3) -> bool {
    height([a, b, c]) <= THINNEST * longest_side([a, b, c])
}

/// Whether every triangle around vertex `v` is in the chunk: walking around `v` from
/// `start`, one of its triangles, the fan closes.
fn fan_complete(
    tris: &[[u32; 3]],
    along: &IntMap<(u32, u32), u32>,
    v: u32,
    start: [u32; 3],
) -> bool {
    let Some(k) = (0..3).find(|&k| start[k] == v) else {
        return false;
    };
    let first = start[(k + 1) % 3];
    let mut x = first;
    // Around v: triangle (v, x, y) is followed by the one along (v, y).
    for _ in 0..=tris.len() {
        let Some(&i) = along.get(&(v, x)) else {
            return false;
        };
        let Some(y) = third(tris[i as usize], v, x) else {
            return false;
        };
        if y == first {
            return true;
        }
        x = y;
    }
    false
}

#[cfg(test)]
mod tests {
    use isoforge_field::{Bounds, ClippedField, Shape};

    use super::*;
    use crate::check::check;
    use crate::dc::sampler::TapeSampler;
    use crate::mesh::Mesh;

    /// The cube [-1, 1]³.
    fn cube() -> TapeSampler {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let s = x.abs().max(&y.abs()).max(&z.abs()) - 1.0;
        let bounds = Bounds::new([-2.0; 3], [2.0; 3]).expect("a box");
        TapeSampler::new(ClippedField::new(&s, bounds))
    }

    /// Across the cube's edge where its top (z = 1) meets its front (y = −1): `a` on the
    /// top, `b` on the front, `c` and `d` on the edge itself. Triangles (a, b, c) and
    /// (b, a, d) face out; their edge a–b runs under the crease, a quarter from both faces
    /// at its middle, and c–d along it.
    const A: [f32; 3] = [0.0, -0.5, 1.0];
    const B: [f32; 3] = [0.0, -1.0, 0.5];
    const C: [f32; 3] = [0.5, -1.0, 1.0];
    const D: [f32; 3] = [-0.5, -1.0, 1.0];
    /// A point inside, for the triangles that close the mesh behind.
    const E: [f32; 3] = [0.0, -0.3, 0.3];

    /// The mesh (vertices a, b, c, d, e = 0..5) through a flipper, and the edges turned.
    fn through(tris: &[[u32; 3]]) -> (Mesh, u64) {
        let sampler = cube();
        let mut out = Mesh::default();
        let mut flipper = Flipper::new(&sampler, 0.01, 0.05, &mut out);
        for p in [A, B, C, D, E] {
            flipper.vertex(p).unwrap();
        }
        for &t in tris {
            flipper.triangle(t, [[0.0; 3]; 3]).unwrap();
        }
        flipper.finish().unwrap();
        let turned = flipper.turned;
        (out, turned)
    }

    fn has_edge(mesh: &Mesh, u: u32, v: u32) -> bool {
        mesh.triangles
            .iter()
            .any(|t| (0..3).any(|k| (t[k], t[(k + 1) % 3]) == (u, v)))
    }

    #[test]
    fn a_chord_under_a_crease_turns_onto_it() {
        let (a, b, c, d, e) = (0, 1, 2, 3, 4);
        // The pair in front; behind, a fan from e closes the mesh.
        let tris = [
            [a, b, c],
            [b, a, d],
            [a, c, e],
            [c, b, e],
            [b, d, e],
            [d, a, e],
        ];
        let (mesh, turned) = through(&tris);
        assert_eq!(turned, 1);
        assert!(
            has_edge(&mesh, d, c) && has_edge(&mesh, c, d),
            "{:?}",
            mesh.triangles
        );
        assert!(!has_edge(&mesh, a, b) && !has_edge(&mesh, b, a));
        let report = check(&mesh);
        assert!(report.is_closed_manifold(), "{:?}", mesh.triangles);
        assert!(report.volume > 0.0, "{report:?}");
    }

    #[test]
    fn a_triangle_before_its_vertices_is_an_error() {
        let sampler = cube();
        let mut out = Mesh::default();
        let mut flipper = Flipper::new(&sampler, 0.01, 0.05, &mut out);
        flipper.vertex(A).unwrap();
        let e = flipper.triangle([0, 1, 2], [[0.0; 3]; 3]).unwrap_err();
        assert!(e.to_string().contains("before its vertices"), "{e}");
    }

    #[test]
    fn an_edge_the_mesh_has_is_not_made_twice() {
        let (a, b, c, d) = (0, 1, 2, 3);
        // Behind, c–d is already an edge: turning a–b onto it would join c and d twice.
        let tris = [[a, b, c], [b, a, d], [a, c, d], [c, b, d]];
        let (mesh, turned) = through(&tris);
        assert_eq!(turned, 0);
        assert_eq!(mesh.triangles, tris);
    }
}
