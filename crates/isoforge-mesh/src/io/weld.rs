//! Welding triangle soup into an indexed mesh: vertices at exactly the same position become
//! one vertex. STL and 3MF-less soups need it; the checker can only see shared edges once
//! corners are shared.

use super::ParseError;
use crate::int_hash::IntMap;
use crate::mesh::Mesh;

/// Builds an indexed mesh from positions, merging exact duplicates (with `-0.0` taken as
/// `0.0`). Vertices keep the order in which they were first seen.
pub(crate) struct Welder {
    map: IntMap<[u32; 3], u32>,
    mesh: Mesh,
}

impl Welder {
    /// A welder expecting about `triangles` triangles.
    pub(crate) fn with_capacity(triangles: usize) -> Self {
        // An closed mesh has about half as many vertices as triangles; cap the guess so a
        // lying header cannot make us reserve gigabytes.
        let tris = triangles.min(1 << 24);
        let mut map = IntMap::default();
        map.reserve(tris / 2 + 16);
        Welder {
            map,
            mesh: Mesh {
                vertices: Vec::with_capacity(tris / 2 + 16),
                triangles: Vec::with_capacity(tris),
            },
        }
    }

    /// The index of the vertex at `p`, adding it if new.
    pub(crate) fn vertex(&mut self, p: [f32; 3]) -> Result<u32, ParseError> {
        // Adding +0.0 turns -0.0 into +0.0 and leaves every other value alone.
        let p = p.map(|v| v + 0.0);
        let key = p.map(f32::to_bits);
        let next = self.mesh.vertices.len();
        if let Some(&i) = self.map.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(next).map_err(|_| super::too_many_vertices(super::Place::File))?;
        self.map.insert(key, i);
        self.mesh.vertices.push(p);
        Ok(i)
    }

    /// Adds a triangle given by its corner positions.
    pub(crate) fn triangle(&mut self, corners: [[f32; 3]; 3]) -> Result<(), ParseError> {
        let a = self.vertex(corners[0])?;
        let b = self.vertex(corners[1])?;
        let c = self.vertex(corners[2])?;
        self.mesh.triangles.push([a, b, c]);
        Ok(())
    }

    /// The welded mesh.
    pub(crate) fn finish(self) -> Mesh {
        self.mesh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welds_exact_duplicates_and_negative_zero() {
        let mut w = Welder::with_capacity(2);
        w.triangle([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
        w.triangle([[-0.0, 0.0, -0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
            .unwrap();
        let m = w.finish();
        assert_eq!(m.vertices.len(), 3);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 1]]);
        assert!(
            m.vertices
                .iter()
                .flatten()
                .all(|v| v.to_bits() != (-0.0f32).to_bits())
        );
    }

    #[test]
    fn keeps_near_but_distinct_positions_apart() {
        let mut w = Welder::with_capacity(1);
        let e = f32::from_bits(1);
        w.triangle([[0.0, 0.0, 0.0], [e, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
        assert_eq!(w.finish().vertices.len(), 3);
    }
}
