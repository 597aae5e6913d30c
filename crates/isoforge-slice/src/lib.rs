//! Slicing for isoforge: layer outlines straight from the field (or from a mesh), FDM
//! G-code, and resin/voxel layer images.
