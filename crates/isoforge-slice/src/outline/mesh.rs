//! Layer outlines from a triangle mesh: each triangle the plane crosses gives one oriented
//! segment between two of its edges, and segments are chained through the mesh's shared
//! edges (not by matching coordinates), so a closed mesh always gives closed loops.
//!
//! A vertex lying exactly on the plane counts as above it (simulation of simplicity), so
//! every crossed edge has one end below and one above and no segment degenerates.

use std::collections::HashMap;

use isoforge_mesh::Mesh;

use crate::geom::{Contour, simplify_closed_indices};
use crate::outline::march::chain;
use crate::{MeshProblem, SliceError};

/// Slices a closed, outward-oriented mesh.
pub struct MeshSlicer<'a> {
    mesh: &'a Mesh,
    /// Triangles sorted by their lowest z, with that z and their highest.
    order: Vec<(f32, f32, u32)>,
    tolerance: f64,
}

/// The mesh's bounding box, `(min, max)`, or `None` for no vertices.
pub fn mesh_bounds(mesh: &Mesh) -> Option<([f64; 3], [f64; 3])> {
    let [lo, hi] = mesh.bounds()?;
    Some((lo.map(f64::from), hi.map(f64::from)))
}

fn at(mesh: &Mesh, v: u32) -> [f64; 3] {
    mesh.vertices[v as usize].map(f64::from)
}

/// Checks that a mesh can be sliced: indices in range, finite coordinates, every edge
/// shared by exactly two triangles that run it in opposite directions (closed and
/// consistently oriented), and positive volume (normals pointing out).
pub fn check_sliceable(mesh: &Mesh) -> Result<(), SliceError> {
    if mesh.triangles.is_empty() {
        return Err(MeshProblem::NoTriangles.into());
    }
    let nv = mesh.vertices.len() as u32;
    if let Some((index, v)) = mesh
        .vertices
        .iter()
        .enumerate()
        .find(|(_, v)| v.iter().any(|c| !c.is_finite()))
    {
        return Err(MeshProblem::NotFinite {
            index,
            position: *v,
        }
        .into());
    }
    let mut directed: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangles.len() * 3);
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri.iter().any(|&v| v >= nv) {
            return Err(MeshProblem::BadIndex {
                triangle: t,
                vertices: nv as usize,
            }
            .into());
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if a == b {
                continue;
            }
            if directed.insert((a, b), t as u32).is_some() {
                return Err(MeshProblem::NotManifold { at: at(mesh, a) }.into());
            }
        }
    }
    let open: Vec<&(u32, u32)> = directed
        .keys()
        .filter(|&&(a, b)| !directed.contains_key(&(b, a)))
        .collect();
    // The lowest edge, not the map's first: the error names the same place on every run.
    if let Some(&&(a, _)) = open.iter().min() {
        return Err(MeshProblem::Open {
            edges: open.len(),
            near: at(mesh, a),
        }
        .into());
    }
    let volume = mesh.signed_volume();
    if volume < 0.0 {
        return Err(MeshProblem::InsideOut { volume }.into());
    }
    if volume == 0.0 {
        return Err(MeshProblem::NoVolume.into());
    }
    Ok(())
}

impl<'a> MeshSlicer<'a> {
    /// Checks the mesh ([`check_sliceable`]) and indexes its triangles by height.
    pub fn new(mesh: &'a Mesh, tolerance: f64) -> Result<MeshSlicer<'a>, SliceError> {
        check_sliceable(mesh)?;
        let mut order: Vec<(f32, f32, u32)> = mesh
            .triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let zs = tri.map(|v| mesh.vertices[v as usize][2]);
                (
                    zs[0].min(zs[1]).min(zs[2]),
                    zs[0].max(zs[1]).max(zs[2]),
                    t as u32,
                )
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(MeshSlicer {
            mesh,
            order,
            tolerance,
        })
    }

    /// The outline at height `z`: outer contours counter-clockwise, holes clockwise.
    pub fn outline(&self, z: f64) -> Vec<Contour> {
        self.outline_with_tilts(z).0
    }

    /// The outline at height `z`, and at each of its points how far the surface there
    /// faces down: −n_z of the unit normal of the triangle the outline crosses next.
    pub fn outline_with_tilts(&self, z: f64) -> (Vec<Contour>, Vec<Vec<f32>>) {
        let mesh = self.mesh;
        let zf = z as f32;
        let end = self.order.partition_point(|t| t.0 <= zf);
        let above = |v: u32| mesh.vertices[v as usize][2] as f64 >= z;
        let key = |a: u32, b: u32| if a < b { (a, b) } else { (b, a) };
        let mut segments = Vec::new();
        let mut tilt_of: HashMap<(u32, u32), f32> = HashMap::new();
        for &(_, zmax, t) in &self.order[..end] {
            if zmax < zf {
                continue;
            }
            let tri = mesh.triangles[t as usize];
            let up = tri.map(above);
            if up[0] == up[1] && up[1] == up[2] {
                continue;
            }
            // Walking the triangle a -> b -> c (counter-clockwise from outside), the edge
            // that goes from above to below starts the segment (material on its left).
            let (mut s, mut e) = (None, None);
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if up[k] && !up[(k + 1) % 3] {
                    s = Some(key(a, b));
                } else if !up[k] && up[(k + 1) % 3] {
                    e = Some(key(a, b));
                }
            }
            if let (Some(s), Some(e)) = (s, e) {
                segments.push((s, e));
                tilt_of.insert(s, facing_down(mesh, tri));
            }
        }
        let point = |(a, b): (u32, u32)| {
            let (pa, pb) = (at(mesh, a), at(mesh, b));
            let t = (z - pa[2]) / (pb[2] - pa[2]);
            [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
        };
        let mut contours = Vec::new();
        let mut tilts = Vec::new();
        for c in chain(&segments) {
            if !c.closed || c.edges.len() < 3 {
                continue;
            }
            let pts: Contour = c.edges.iter().map(|&e| point(e)).collect();
            let keep = simplify_closed_indices(&pts, self.tolerance);
            if keep.len() < 3 {
                continue;
            }
            contours.push(keep.iter().map(|&i| pts[i]).collect());
            tilts.push(
                keep.iter()
                    .map(|&i| tilt_of.get(&c.edges[i]).copied().unwrap_or(0.0))
                    .collect(),
            );
        }
        (contours, tilts)
    }
}

/// −n_z of a triangle's unit normal: 1 for a face looking straight down, 0 for a wall.
fn facing_down(mesh: &Mesh, tri: [u32; 3]) -> f32 {
    let [a, b, c] = tri.map(|v| at(mesh, v));
    let (u, v) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 { (-n[2] / len) as f32 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::contours_area;

    use isoforge_mesh::samples::octahedron;

    #[test]
    fn octahedron_section_is_a_ccw_square() {
        let m = octahedron();
        let s = MeshSlicer::new(&m, 0.0).unwrap();
        let o = s.outline(0.5);
        assert_eq!(o.len(), 1);
        // |x| + |y| <= 0.5: a square of area 2 * 0.5^2.
        assert!(
            (contours_area(&o) - 0.5).abs() < 1e-6,
            "{}",
            contours_area(&o)
        );
        // Through the vertices at z = 0 (on-plane vertices count as above).
        let o = s.outline(0.0);
        assert!((contours_area(&o) - 2.0).abs() < 1e-6);
    }

    #[test]
    fn open_mesh_is_refused() {
        let mut m = octahedron();
        m.triangles.pop();
        let e = MeshSlicer::new(&m, 0.0).err().unwrap();
        assert!(
            matches!(e, SliceError::Mesh(MeshProblem::Open { edges: 3, .. })),
            "{e}"
        );
    }

    #[test]
    fn inside_out_mesh_is_refused() {
        let mut m = octahedron();
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        let e = MeshSlicer::new(&m, 0.0).err().unwrap();
        assert!(
            matches!(e, SliceError::Mesh(MeshProblem::InsideOut { volume }) if volume < 0.0),
            "{e}"
        );
    }
}
