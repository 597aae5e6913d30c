//! The mesh checker: closed, manifold, oriented; volume, area, bounds.

use crate::mesh::Mesh;

/// What the checker found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshReport {}

impl MeshReport {
    /// True when the mesh is watertight, manifold and consistently oriented.
    pub fn is_closed_manifold(&self) -> bool {
        todo!("mesh io helper")
    }
}

/// Checks a mesh.
pub fn check(mesh: &Mesh) -> MeshReport {
    let _ = mesh;
    todo!("mesh io helper")
}
