//! The indexed triangle mesh every stage shares.

use glam::{DVec3, Vec3};

/// An indexed triangle mesh: shared vertices, triangles wound counter-clockwise seen from
/// outside (so normals point out).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in millimetres.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as three indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// The axis-aligned box of all vertices as `[min, max]`, or `None` for a mesh without
    /// vertices.
    pub fn bounds(&self) -> Option<[[f32; 3]; 2]> {
        let first = Vec3::from(*self.vertices.first()?);
        let (lo, hi) = self.vertices.iter().fold((first, first), |(lo, hi), &v| {
            (lo.min(Vec3::from(v)), hi.max(Vec3::from(v)))
        });
        Some([lo.to_array(), hi.to_array()])
    }

    /// The three corners of a triangle, in f64. Indices must be in range (see
    /// [`Mesh::has_valid_indices`]).
    pub fn corners(&self, t: [u32; 3]) -> [DVec3; 3] {
        t.map(|i| Vec3::from(self.vertices[i as usize]).as_dvec3())
    }

    /// True when every triangle index names a vertex.
    pub fn has_valid_indices(&self) -> bool {
        let n = self.vertices.len();
        self.triangles
            .iter()
            .all(|t| t.iter().all(|&i| (i as usize) < n))
    }

    /// The signed volume enclosed, by the divergence theorem: the sum of the tetrahedra each
    /// triangle spans with a reference point. Positive when the triangles face outward.
    /// Summed in f64 around the bounding box's centre, so large offsets from the origin do
    /// not cost precision.
    pub fn signed_volume(&self) -> f64 {
        let Some([lo, hi]) = self.bounds() else {
            return 0.0;
        };
        let c = (Vec3::from(lo).as_dvec3() + Vec3::from(hi).as_dvec3()) * 0.5;
        let mut six_v = 0.0;
        for &t in &self.triangles {
            let [a, b, d] = self.corners(t).map(|p| p - c);
            six_v += a.dot(b.cross(d));
        }
        six_v / 6.0
    }

    /// The total surface area.
    pub fn area(&self) -> f64 {
        self.triangles
            .iter()
            .map(|&t| triangle_area(self.corners(t)))
            .sum()
    }

    /// The unit normal of a triangle from its winding (zero for a degenerate triangle).
    pub fn triangle_normal(&self, t: [u32; 3]) -> [f32; 3] {
        let [a, b, c] = self.corners(t);
        let n = (b - a).cross(c - a);
        let len = n.length();
        if len > 0.0 && len.is_finite() {
            (n / len).as_vec3().to_array()
        } else {
            [0.0; 3]
        }
    }
}

/// The area of a triangle given by its corners.
fn triangle_area([a, b, c]: [DVec3; 3]) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tetrahedron() -> Mesh {
        Mesh {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn tetrahedron_volume_area_bounds() {
        let m = unit_tetrahedron();
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-12);
        let want = 1.5 + 3f64.sqrt() / 2.0;
        assert!((m.area() - want).abs() < 1e-9);
        assert_eq!(m.bounds(), Some([[0.0; 3], [1.0; 3]]));
        assert_eq!(m.triangle_normal([0, 2, 1]), [0.0, 0.0, -1.0]);
    }

    #[test]
    fn flipped_tetrahedron_has_negative_volume() {
        let mut m = unit_tetrahedron();
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        assert!((m.signed_volume() + 1.0 / 6.0).abs() < 1e-12);
    }

    #[test]
    fn far_from_origin_volume_stays_exact() {
        let mut m = unit_tetrahedron();
        for v in &mut m.vertices {
            v[0] += 1.0e6;
        }
        assert!((m.signed_volume() - 1.0 / 6.0).abs() < 1e-9);
    }
}
