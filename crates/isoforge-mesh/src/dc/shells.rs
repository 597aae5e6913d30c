//! The last stage before the writer: a small closed part that came out inside out is turned
//! the right way out.
//!
//! A blob a cell or two wide, meshed at a tolerance of half a cell or more, comes out of
//! the merge as a handful of triangles, some of them facing into it (a lattice that coarse
//! cannot say which way such a shape faces), and the refiner's moves and splits can then
//! leave the whole part inside out: negative volume, the solid's side outward. The hunts
//! found six such balls (docs/meshing.md), each by a different path through the merge, the
//! collapses and the refiner, and each earlier one is now a guard there; the sixth (a ball
//! 1.3 cells wide at a tolerance of 3 cells) turned over in the refiner through a vertex
//! it moved 0.6 of a cell onto the ball.
//!
//! So this stage holds the triangles of each part while it is small and open, and when one
//! closes with at most [`SMALL`] triangles it compares the part's signed volume with the
//! field at the part's middle: a part of negative volume around a point the field says is
//! solid is written with every triangle turned (a cavity, whose volume is negative too,
//! has empty space at its middle and is left as it is). Only the order of each triangle's
//! corners changes, never which vertices it joins: the mesh stays closed and manifold.
//!
//! Triangles of large parts pass straight through: a triangle that uses a vertex some
//! written triangle used is written at once, with the small part it joins. What is held is
//! at most [`SMALL`] triangles per part still open, and one bit per vertex.

use std::io;

use glam::DVec3;

use super::narrowed::Narrowed;
use super::sampler::Sampler;
use crate::int_hash::IntMap;
use crate::sink::MeshSink;

/// Parts of more triangles than this are written as they come. The inside-out balls the
/// hunts found were 4 to 12 triangles; a ball ten cells wide is a few hundred triangles,
/// and no such ball came out inside out.
pub const SMALL: usize = 256;

/// One small part still held: its triangles, its directed edges not yet matched by the
/// reverse edge of another triangle, and its vertices.
#[derive(Default)]
struct Part {
    triangles: Vec<([u32; 3], [[f32; 3]; 3])>,
    open: IntMap<(u32, u32), ()>,
    vertices: Vec<u32>,
    /// An edge came twice in one direction: the part is not a consistently oriented
    /// surface, and it is written as it came.
    odd: bool,
}

impl Part {
    fn add(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            if self.open.remove(&(v, u)).is_none() && self.open.insert((u, v), ()).is_some() {
                self.odd = true;
            }
        }
        self.triangles.push((t, corners));
    }

    fn closed(&self) -> bool {
        self.open.is_empty() && !self.odd
    }

    /// Six times the signed volume, and the area-weighted middle of the surface.
    fn volume_and_middle(&self) -> (f64, DVec3) {
        let to_d = |p: [f32; 3]| DVec3::from(p.map(f64::from));
        let origin = self
            .triangles
            .first()
            .map_or(DVec3::ZERO, |(_, c)| to_d(c[0]));
        let (mut six_volume, mut weighted, mut area) = (0.0, DVec3::ZERO, 0.0);
        for (_, c) in &self.triangles {
            let [a, b, d] = c.map(|p| to_d(p) - origin);
            six_volume += a.dot(b.cross(d));
            let twice = (b - a).cross(d - a).length();
            weighted += (a + b + d) / 3.0 * twice;
            area += twice;
        }
        let middle = if area > 0.0 {
            origin + weighted / area
        } else {
            origin
        };
        (six_volume, middle)
    }
}

/// Turns small closed parts that came out inside out the right way out, on the way to
/// `inner` (see the module doc).
pub struct SmallShells<'a, S: Sampler> {
    sampler: &'a S,
    ev: S::Evals,
    field: Narrowed<S>,
    inner: &'a mut dyn MeshSink,
    /// One bit per vertex: whether a written triangle uses it.
    written: Vec<u64>,
    /// Vertices so far.
    vertices: u32,
    /// The held part each vertex of a held triangle belongs to.
    owner: IntMap<u32, u32>,
    parts: IntMap<u32, Part>,
    next_part: u32,
    /// Parts turned the right way out.
    pub turned: u64,
}

impl<'a, S: Sampler> SmallShells<'a, S> {
    /// Reads the field through `sampler` on a lattice of `cell`-sized cells.
    pub fn new(sampler: &'a S, cell: f64, inner: &'a mut dyn MeshSink) -> Self {
        SmallShells {
            sampler,
            ev: sampler.evals(),
            field: Narrowed::new(sampler, cell),
            inner,
            written: Vec::new(),
            vertices: 0,
            owner: IntMap::default(),
            parts: IntMap::default(),
            next_part: 0,
            turned: 0,
        }
    }

    /// Writes the parts still held (none, on a closed mesh); call once everything has come.
    pub fn finish(&mut self) -> io::Result<()> {
        let mut ids: Vec<u32> = self.parts.keys().copied().collect();
        ids.sort_unstable();
        for id in ids {
            self.write_part(id, false)?;
        }
        Ok(())
    }

    fn is_written(&self, v: u32) -> bool {
        self.written
            .get(v as usize / 64)
            .is_some_and(|w| w >> (v % 64) & 1 == 1)
    }

    fn mark_written(&mut self, v: u32) {
        if let Some(w) = self.written.get_mut(v as usize / 64) {
            *w |= 1 << (v % 64);
        }
    }

    /// Writes part `id`, each triangle turned if `turn`, and forgets it.
    fn write_part(&mut self, id: u32, turn: bool) -> io::Result<()> {
        let Some(part) = self.parts.remove(&id) else {
            return Ok(());
        };
        for v in part.vertices {
            self.owner.remove(&v);
            self.mark_written(v);
        }
        for (t, c) in part.triangles {
            if turn {
                self.inner
                    .triangle([t[0], t[2], t[1]], [c[0], c[2], c[1]])?;
            } else {
                self.inner.triangle(t, c)?;
            }
        }
        Ok(())
    }

    /// Writes a closed part, turned if it is inside out: negative volume around a middle
    /// the field says is solid.
    fn settle(&mut self, id: u32) -> io::Result<()> {
        let Some(part) = self.parts.get(&id) else {
            return Ok(());
        };
        let (six_volume, middle) = part.volume_and_middle();
        let turn = six_volume < 0.0 && self.field.grad(self.sampler, &mut self.ev, middle)[0] < 0.0;
        self.turned += u64::from(turn);
        self.write_part(id, turn)
    }

    /// The held parts `t`'s vertices are in, in a fixed order.
    fn held_parts(&self, t: [u32; 3]) -> Vec<u32> {
        let mut ids: Vec<u32> = t
            .iter()
            .filter_map(|v| self.owner.get(v).copied())
            .collect();
        ids.sort_unstable();
        ids.dedup();
        ids
    }

    /// The held part `t` belongs to: the parts its vertices are in, joined into the
    /// largest, or a new one.
    fn part_for(&mut self, t: [u32; 3]) -> u32 {
        let ids = self.held_parts(t);
        let Some(&keep) = ids
            .iter()
            .max_by_key(|&&id| (self.parts.get(&id).map_or(0, |p| p.triangles.len()), id))
        else {
            let id = self.next_part;
            self.next_part = self.next_part.wrapping_add(1);
            self.parts.insert(id, Part::default());
            return id;
        };
        for id in ids.into_iter().filter(|&id| id != keep) {
            let Some(other) = self.parts.remove(&id) else {
                continue;
            };
            for &v in &other.vertices {
                self.owner.insert(v, keep);
            }
            if let Some(part) = self.parts.get_mut(&keep) {
                part.vertices.extend(other.vertices);
                part.odd |= other.odd;
                for (t, c) in other.triangles {
                    part.add(t, c);
                }
            }
        }
        keep
    }
}

impl<S: Sampler> MeshSink for SmallShells<'_, S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        if self.vertices.is_multiple_of(64) {
            self.written.push(0);
        }
        self.vertices = self
            .vertices
            .checked_add(1)
            .ok_or_else(|| io::Error::other("more than 2^32 vertices"))?;
        self.inner.vertex(p)
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        // Part of a large part (or of a small one that joins it): written now, with the
        // held triangles it joins.
        if t.iter().any(|&v| self.is_written(v)) {
            for id in self.held_parts(t) {
                self.write_part(id, false)?;
            }
            for v in t {
                self.mark_written(v);
            }
            return self.inner.triangle(t, corners);
        }
        let id = self.part_for(t);
        let Some(part) = self.parts.get_mut(&id) else {
            return self.inner.triangle(t, corners);
        };
        part.add(t, corners);
        for v in t {
            if self.owner.insert(v, id).is_none()
                && let Some(part) = self.parts.get_mut(&id)
            {
                part.vertices.push(v);
            }
        }
        let Some(part) = self.parts.get(&id) else {
            return Ok(());
        };
        if part.triangles.len() > SMALL || part.odd {
            self.write_part(id, false)
        } else if part.closed() {
            self.settle(id)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use isoforge_field::{Bounds, ClippedField, Shape};

    use super::*;
    use crate::dc::sampler::TapeSampler;
    use crate::mesh::Mesh;

    /// The unit ball's field.
    fn ball() -> TapeSampler {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let s = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let bounds = Bounds::new([-2.0; 3], [2.0; 3]).expect("a box");
        TapeSampler::new(ClippedField::new(&s, bounds))
    }

    /// Vertices and triangles of one part.
    type Part = (Vec<[f32; 3]>, Vec<[u32; 3]>);

    /// A tetrahedron around `c` of size `r`, counter-clockwise seen from outside (or
    /// turned), with vertices from `first` on.
    fn tetrahedron(
        c: [f32; 3],
        r: f32,
        first: u32,
        turned: bool,
    ) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let p = [[r, r, r], [r, -r, -r], [-r, r, -r], [-r, -r, r]]
            .map(|d| [c[0] + d[0], c[1] + d[1], c[2] + d[2]]);
        let mut t = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        if turned {
            t.iter_mut().for_each(|t| t.swap(1, 2));
        }
        (
            p.to_vec(),
            t.into_iter().map(|t| t.map(|i| i + first)).collect(),
        )
    }

    fn through(parts: &[Part]) -> (Mesh, u64) {
        let sampler = ball();
        let mut out = Mesh::default();
        let mut shells = SmallShells::new(&sampler, 0.1, &mut out);
        for (vs, _) in parts {
            for &v in vs {
                shells.vertex(v).expect("vertex");
            }
        }
        for (vs, ts) in parts {
            let first = ts.iter().flatten().min().copied().unwrap_or(0);
            for &t in ts {
                let corners = t.map(|i| vs[(i - first) as usize]);
                shells.triangle(t, corners).expect("triangle");
            }
        }
        shells.finish().expect("finish");
        let turned = shells.turned;
        (out, turned)
    }

    #[test]
    fn a_small_part_inside_out_in_the_solid_is_turned() {
        let (mesh, turned) = through(&[tetrahedron([0.2, 0.0, 0.0], 0.1, 0, true)]);
        assert_eq!(turned, 1);
        assert!(
            crate::check::check(&mesh).volume > 0.0,
            "volume {}",
            crate::check::check(&mesh).volume
        );
        assert_eq!(mesh.triangles.len(), 4);
    }

    #[test]
    fn a_cavity_and_a_part_the_right_way_out_are_left_alone() {
        // A cavity: negative volume, empty space at its middle (outside the unit ball).
        let (cavity, turned) = through(&[tetrahedron([1.5, 0.0, 0.0], 0.1, 0, true)]);
        assert_eq!(turned, 0);
        assert!(crate::check::check(&cavity).volume < 0.0);
        let (blob, turned) = through(&[tetrahedron([0.2, 0.0, 0.0], 0.1, 0, false)]);
        assert_eq!(turned, 0);
        assert!(crate::check::check(&blob).volume > 0.0);
    }

    #[test]
    fn every_triangle_comes_out_once_whatever_the_parts() {
        // Two small parts and one whose triangles interleave with theirs.
        let a = tetrahedron([0.2, 0.0, 0.0], 0.1, 0, true);
        let b = tetrahedron([-0.3, 0.0, 0.0], 0.1, 4, false);
        let (mesh, turned) = through(&[a.clone(), b.clone()]);
        assert_eq!(turned, 1);
        assert_eq!(mesh.triangles.len(), 8);
        assert_eq!(mesh.vertices.len(), 8);
        let mut seen: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .map(|t| {
                let mut s = *t;
                s.sort_unstable();
                s
            })
            .collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 8, "each triangle once");
    }
}
