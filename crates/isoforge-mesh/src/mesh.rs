//! The indexed triangle mesh every stage shares.

/// An indexed triangle mesh: shared vertices, triangles wound counter-clockwise seen from
/// outside (so normals point out).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in millimetres.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as three indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}
