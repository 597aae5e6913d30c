//! The classic library: the primitives, transforms and combinations of the 2010
//! function-based modeler, with its names (in snake case) and exactly its formulas.
//! `docs/language.md` ("The classic library") lists every name with its formula.

mod combine;
mod primitives;
mod transforms;

pub use combine::{blend, combine, intersect, max, min, morph, subtract, union, union_all};
pub use primitives::{
    bug, close, cone, cube, cyl, drope, ellip, heart, hspace, para, prism, sinus, sphere,
    tetrahedral, torus,
};
pub use transforms::{
    deg_to_rad, reflect_xy, reflect_yz, reflect_zx, rotate_rx, rotate_ry, rotate_rz, rotate_x,
    rotate_y, rotate_z, scale_x, scale_xyz, scale_y, scale_z, trans_x, trans_y, trans_z, translate,
};

#[cfg(test)]
mod tests;
