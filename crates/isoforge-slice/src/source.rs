//! What is sliced: a field over a region, or a mesh. Both give the same thing per layer, an
//! oriented outline, and the model's height range.

use isoforge_field::{Bounds, Shape};
use isoforge_mesh::Mesh;

use crate::SliceError;
use crate::geom::Contour;
use crate::outline::mesh::mesh_bounds;
use crate::outline::{FieldSlicer, MeshSlicer};

/// A model to slice.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A field, evaluated inside its region (outside counts as outside).
    Field(&'a Shape, Bounds),
    /// A closed, outward-oriented triangle mesh.
    Mesh(&'a Mesh),
}

impl<'a> Source<'a> {
    /// A field over a region.
    pub fn field(shape: &'a Shape, bounds: Bounds) -> Self {
        Source::Field(shape, bounds)
    }
    /// A mesh.
    pub fn mesh(mesh: &'a Mesh) -> Self {
        Source::Mesh(mesh)
    }

    /// Prepares outlines with finest cells of `cell` mm (fields only) and simplification
    /// within `tolerance` mm. Checks a mesh and finds the model's height range.
    pub fn prepare(&self, cell: f64, tolerance: f64) -> Result<Sliceable<'a>, SliceError> {
        match *self {
            Source::Field(shape, bounds) => {
                let slicer = FieldSlicer::new(shape, bounds, cell, tolerance);
                let (z0, z1) = slicer.z_extent(cell).ok_or(SliceError::EmptyRegion {
                    min: bounds.min,
                    max: bounds.max,
                })?;
                Ok(Sliceable {
                    inner: Inner::Field(slicer),
                    z_range: (z0, z1),
                })
            }
            Source::Mesh(mesh) => {
                let slicer = MeshSlicer::new(mesh, tolerance)?;
                let (lo, hi) = mesh_bounds(mesh).ok_or(SliceError::EmptyMesh)?;
                Ok(Sliceable {
                    inner: Inner::Mesh(slicer),
                    z_range: (lo[2], hi[2]),
                })
            }
        }
    }
}

enum Inner<'a> {
    Field(FieldSlicer),
    Mesh(MeshSlicer<'a>),
}

/// A model ready to be cut into layers.
pub struct Sliceable<'a> {
    inner: Inner<'a>,
    /// The lowest and highest z with material, model coordinates.
    pub z_range: (f64, f64),
}

impl Sliceable<'_> {
    /// The outline at model height `z` for a layer spanning `slab`.
    pub fn outline(&self, z: f64, slab: (f64, f64)) -> Vec<Contour> {
        match &self.inner {
            Inner::Field(f) => f.outline(z, slab),
            Inner::Mesh(m) => m.outline(z),
        }
    }

    /// The outline at model height `z` with, at each point, how far the surface faces
    /// down there (−n_z of its unit normal: from the field's gradient, or the mesh facet).
    pub fn outline_with_tilts(&self, z: f64, slab: (f64, f64)) -> (Vec<Contour>, Vec<Vec<f32>>) {
        match &self.inner {
            Inner::Field(f) => {
                let c = f.outline(z, slab);
                let t = f.tilts(&c, z);
                (c, t)
            }
            Inner::Mesh(m) => m.outline_with_tilts(z),
        }
    }

    /// The field slicer, when the model is a field (raster output evaluates it per pixel).
    pub fn field(&self) -> Option<&FieldSlicer> {
        match &self.inner {
            Inner::Field(f) => Some(f),
            Inner::Mesh(_) => None,
        }
    }
}

/// One layer: its top in print coordinates (the bed at 0), its thickness, and the model
/// height its outline is taken at (the middle of the layer).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Layer {
    /// Top of the layer above the bed, mm.
    pub top: f64,
    /// Thickness, mm.
    pub height: f64,
    /// Model z of the section (mid-layer).
    pub model_z: f64,
}

/// A model that overshoots a whole number of layers by less than this fraction of a layer
/// gets no layer of its own for the sliver: a mesh whose top is at 10.001 mm is 50 layers
/// of 0.2 mm, not 51 (mesh vertices stored as f32 and mesher placement put tops a few µm
/// off; a sliver layer would print a nearly empty layer in the air).
pub const OVERSHOOT_TOLERANCE: f64 = 0.1;

/// The most layers one job may have: 250 mm at 5 µm. More is a mistake in the layer
/// height, refused before any work with the estimate.
pub const MAX_LAYERS: usize = 50_000;

/// How many layers cover `total` mm: the first `first` mm thick, then `height` mm each.
pub fn layer_count(total: f64, first: f64, height: f64) -> usize {
    if total.is_nan() || total <= 0.0 {
        return 0;
    }
    let rest = (total - first) / height;
    if rest <= OVERSHOOT_TOLERANCE {
        return 1;
    }
    1 + (rest - OVERSHOOT_TOLERANCE).ceil() as usize
}

/// The layers for a model of height range `z_range`: the first `first` mm thick, then
/// `height` mm each, until the model's top is covered (within [`OVERSHOOT_TOLERANCE`]).
/// Callers check the count against [`MAX_LAYERS`] first.
pub fn layer_stack(z_range: (f64, f64), first: f64, height: f64) -> Vec<Layer> {
    let total = z_range.1 - z_range.0;
    let n = layer_count(total, first, height).min(MAX_LAYERS);
    let mut layers = Vec::with_capacity(n);
    let mut bottom = 0.0;
    let mut h = first;
    for _ in 0..n {
        let top = bottom + h;
        layers.push(Layer {
            top,
            height: h,
            model_z: z_range.0 + (bottom + top.min(total)) * 0.5,
        });
        bottom = top;
        h = height;
    }
    layers
}

/// Refuses a stack of more than [`MAX_LAYERS`] layers, naming the estimate.
pub fn check_layer_count(total: f64, first: f64, height: f64) -> Result<(), SliceError> {
    let layers = layer_count(total, first, height);
    if layers > MAX_LAYERS {
        return Err(SliceError::TooManyLayers {
            height: total,
            layer_height: height,
            layers,
            max: MAX_LAYERS,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_cover_the_height() {
        let l = layer_stack((-10.0, 10.0), 0.3, 0.2);
        assert_eq!(l[0].top, 0.3);
        assert!((l.last().unwrap().top - 20.1).abs() < 1e-9);
        assert_eq!(l.len(), 1 + 99);
        assert!((l[0].model_z - (-10.0 + 0.15)).abs() < 1e-12);
        let l = layer_stack((0.0, 1.0), 0.2, 0.2);
        assert_eq!(l.len(), 5);
    }

    #[test]
    fn a_top_a_few_microns_over_a_whole_layer_gets_no_extra_layer() {
        assert_eq!(layer_count(10.001, 0.2, 0.2), 50);
        assert_eq!(layer_count(10.002, 0.2, 0.2), 50);
        assert_eq!(layer_count(22.3501, 0.05, 0.05), 447);
        // A real sliver (a quarter of a layer) still gets its layer.
        assert_eq!(layer_count(10.05, 0.2, 0.2), 51);
        assert_eq!(layer_count(9.999, 0.2, 0.2), 50);
    }

    #[test]
    fn too_many_layers_are_refused_with_the_estimate() {
        match check_layer_count(250.0, 1e-9, 1e-9) {
            Err(SliceError::TooManyLayers { layers, .. }) => assert!(layers > MAX_LAYERS),
            other => panic!("{other:?}"),
        }
        assert!(check_layer_count(250.0, 0.2, 0.2).is_ok());
    }
}
