//! Flaps: two triangles folded back onto each other across their edge, unfolded by
//! flipping the edge.
//!
//! Where merged leaves meet a curved crease, dual contouring can join the crease's
//! vertices into a flap: on cube_holes (fixtures/slice) at depth 6, a bottom triangle of
//! the merge's reached across the rim of a 5 mm hole to a chord 0.22 mm inside it, and
//! three triangles between the rim's vertices lay folded back under it, facing up. The mesh
//! is closed (a flat flap holds no volume), but the chord is 6.4 tolerances off, and the
//! refiner's splits of a folded pair leave pieces folded too (3.2 tolerances at depth 7).
//!
//! The pair `a b c`, `b a e` becomes `a e c`, `e b c` (the same quadrilateral, the other
//! diagonal) when that turns the fold into two triangles facing the same way: the new
//! pair's normals agree, both face out by the field, neither is farther from the surface
//! than the old pair was, and the pair lies flat (the tetrahedron between the two
//! diagonals holds at most a tolerance's depth over it). Vertices do not move, so nothing
//! else changes; the link condition holds when `c e` is not an edge already and `a` and
//! `b` keep three neighbours.

use glam::DVec3;

use super::{Chunk, Decimator};
use crate::dc::sampler::Sampler;

/// Two triangles across an edge whose normals are farther apart than this (cosine, 154°)
/// are a flap.
const FLAP_COS: f64 = -0.9;

/// The flipped pair's normals must be this close (cosine, 26°): the quadrilateral is
/// nearly flat and convex from the side it faces.
const AGREE_COS: f64 = 0.9;

/// Passes over the mesh at most: a flip can make the next triangle along a flap.
const PASSES: usize = 4;

impl Chunk {
    /// Flips the edges of flaps, pass after pass while a pass flips one.
    pub(super) fn unfold_flaps<S: Sampler>(&mut self, d: &mut Decimator<'_, S>) {
        for _ in 0..PASSES {
            let mut flipped = false;
            for t in 0..self.tris.len() as u32 {
                for k in 0..3 {
                    if self.alive_t[t as usize] && self.try_flip(d, t, k) {
                        flipped = true;
                    }
                }
            }
            if !flipped {
                break;
            }
        }
    }

    /// Flips the edge of triangle `t` from its corner `k` to the next, if it is a flap's.
    fn try_flip<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, t: u32, k: usize) -> bool {
        let tri = self.tris[t as usize];
        let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
        // The one other triangle on edge a-b (two or more: not a manifold edge, left alone).
        let one = {
            let mut across = self
                .fan(a)
                .filter(|&u| u != t && self.tris[u as usize].contains(&b));
            (across.next(), across.next())
        };
        let (Some(u), None) = one else {
            return false;
        };
        let other = self.tris[u as usize];
        let Some(&e) = other.iter().find(|&&v| v != a && v != b) else {
            return false;
        };
        // The other side runs b → a (a consistently oriented mesh).
        let j = other.iter().position(|&v| v == b).unwrap_or(0);
        if other[(j + 1) % 3] != a || e == c {
            return false;
        }
        if ![a, b, c, e].iter().all(|&v| self.free[v as usize]) {
            return false;
        }
        let normal = |t: [u32; 3]| {
            let [p, q, r] = t.map(|v| self.pos[v as usize]);
            (q - p).cross(r - p).normalize_or_zero()
        };
        if normal([a, b, c]).dot(normal([b, a, e])) >= FLAP_COS {
            return false;
        }
        let new = [[a, e, c], [e, b, c]];
        let (m0, m1) = (normal(new[0]), normal(new[1]));
        if m0 == DVec3::ZERO || m1 == DVec3::ZERO || m0.dot(m1) < AGREE_COS {
            return false;
        }
        // A flap lies flat: the tetrahedron between the two diagonals holds no more than a
        // tolerance's depth over the pair (a thin wedge's two faces are no flap).
        let [pa, pb, pc, pe] = [a, b, c, e].map(|v| self.pos[v as usize]);
        let six_volume = (pb - pa).cross(pc - pa).dot(pe - pa).abs();
        let twice_area = (pe - pa).cross(pc - pa).length() + (pb - pe).cross(pc - pe).length();
        if six_volume / 6.0 > d.tolerance * twice_area / 2.0 {
            return false;
        }
        if self.neighbours(c).binary_search(&e).is_ok()
            || self.neighbours(a).len() <= 3
            || self.neighbours(b).len() <= 3
        {
            return false;
        }
        let allowance = d
            .tolerance
            .max(self.known_deviation(d, t))
            .max(self.known_deviation(d, u));
        let within = new.iter().all(|&n| {
            let corners = n.map(|v| self.pos[v as usize]);
            self.deviation(d, &corners, allowance, true) <= allowance
        });
        if !within {
            return false;
        }
        self.alive_t[t as usize] = false;
        self.alive_t[u as usize] = false;
        for n in new {
            self.add_triangle(n);
        }
        true
    }
}
