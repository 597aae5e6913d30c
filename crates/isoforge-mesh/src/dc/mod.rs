//! The interval octree and dual contouring.

use isoforge_field::{Bounds, Shape};

use crate::mesh::Mesh;

/// How to mesh.
#[derive(Clone, Debug)]
pub struct MeshSettings {
    /// The region; outside it counts as outside.
    pub bounds: Bounds,
    /// The finest level: 2^depth cells along the longest side.
    pub depth: u8,
}

impl MeshSettings {
    /// Settings for a region and depth.
    pub fn new(bounds: Bounds, depth: u8) -> Self {
        MeshSettings { bounds, depth }
    }
}

/// Meshes a shape over the settings' region.
pub fn mesh_shape(shape: &Shape, settings: &MeshSettings) -> Mesh {
    let _ = (shape, settings);
    todo!("dual contouring helper")
}
