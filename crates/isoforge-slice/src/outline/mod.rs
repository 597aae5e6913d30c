//! Layer outlines: closed, oriented polygons (outer counter-clockwise, holes clockwise) of
//! a solid's cross-section at one height, from a field ([`field`]) or a mesh ([`mesh`]).

pub mod field;
pub mod march;
pub mod mesh;

pub use field::FieldSlicer;
pub use mesh::MeshSlicer;

#[cfg(test)]
mod tests;
