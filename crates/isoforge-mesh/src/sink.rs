//! Where the mesher puts its output as it goes: a [`MeshSink`] takes vertices and triangles
//! one at a time, so a mesh can go to a file without ever being held whole (the writers in
//! [`crate::io::stream`]), to a [`Mesh`] in memory, or through a checker
//! ([`crate::check::StreamCheck`]) on its way.

use std::io;

use crate::mesh::Mesh;

/// Receives a mesh piece by piece. Vertices are numbered in the order they come, from 0;
/// a triangle comes after its three vertices.
pub trait MeshSink {
    /// The next vertex.
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()>;
    /// A triangle of earlier vertices, counter-clockwise seen from outside; `corners` are
    /// their positions (for formats without shared vertices).
    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()>;
}

impl MeshSink for Mesh {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.vertices.push(p);
        Ok(())
    }

    fn triangle(&mut self, t: [u32; 3], _corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.triangles.push(t);
        Ok(())
    }
}

impl<S: MeshSink + ?Sized> MeshSink for &mut S {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        (**self).vertex(p)
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        (**self).triangle(t, corners)
    }
}

/// Counts what passes, and sums the volume and area as it goes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Vertices seen.
    pub vertices: u64,
    /// Triangles seen.
    pub triangles: u64,
    /// Six times the signed volume, around `reference`.
    six_volume: f64,
    /// Twice the area.
    two_area: f64,
    /// The point the volume's tetrahedra share (near the mesh, for precision).
    reference: [f64; 3],
    /// The bounding box of the vertices, if any.
    pub bounds: Option<[[f32; 3]; 2]>,
}

impl Tally {
    /// An empty tally whose volume is summed around `reference` (any point near the mesh:
    /// the result does not depend on it, its precision does).
    pub fn around(reference: [f64; 3]) -> Self {
        Tally {
            reference,
            ..Tally::default()
        }
    }

    /// The enclosed volume (positive for outward-facing triangles).
    pub fn volume(&self) -> f64 {
        self.six_volume / 6.0
    }

    /// The surface area.
    pub fn area(&self) -> f64 {
        self.two_area / 2.0
    }

    /// Counts a vertex.
    pub fn add_vertex(&mut self, p: [f32; 3]) {
        self.vertices += 1;
        self.bounds = Some(match self.bounds {
            None => [p, p],
            Some([lo, hi]) => [
                [0, 1, 2].map(|a| lo[a].min(p[a])),
                [0, 1, 2].map(|a| hi[a].max(p[a])),
            ],
        });
    }

    /// Counts a triangle given by its corners.
    pub fn add_triangle(&mut self, corners: [[f32; 3]; 3]) {
        use glam::DVec3;
        self.triangles += 1;
        let r = DVec3::from(self.reference);
        let [a, b, c] = corners.map(|p| glam::Vec3::from(p).as_dvec3() - r);
        let n = (b - a).cross(c - a);
        self.six_volume += a.dot(b.cross(c));
        self.two_area += n.length();
    }
}

impl MeshSink for Tally {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.add_vertex(p);
        Ok(())
    }

    fn triangle(&mut self, _t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.add_triangle(corners);
        Ok(())
    }
}

/// Gives `mesh` to `sink` as the mesher would: its vertices, then its triangles.
#[cfg(test)]
pub(crate) fn replay(mesh: &Mesh, sink: &mut dyn MeshSink) {
    for &v in &mesh.vertices {
        sink.vertex(v).expect("vertex");
    }
    for &t in &mesh.triangles {
        sink.triangle(t, mesh.corners(t).map(|p| p.as_vec3().to_array()))
            .expect("triangle");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;

    #[test]
    fn a_mesh_sink_collects_what_it_is_given() {
        let cube = samples::cube(2.0);
        let mut copy = Mesh::default();
        replay(&cube, &mut copy);
        assert_eq!(copy, cube);
    }

    #[test]
    fn the_tally_matches_the_mesh_figures() {
        let cube = samples::cuboid([1.0, 2.0, 3.0], [2.0, 4.0, 6.0]);
        let mut t = Tally::around([1.5, 3.0, 4.5]);
        replay(&cube, &mut t);
        assert_eq!(t.vertices, 8);
        assert_eq!(t.triangles, 12);
        assert!((t.volume() - 6.0).abs() < 1e-9);
        assert!((t.area() - cube.area()).abs() < 1e-9);
        assert_eq!(t.bounds, cube.bounds());
    }
}
