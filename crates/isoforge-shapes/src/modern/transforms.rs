//! Transforms as functions of a shape: each substitutes the inverse transform into the
//! field (a transform moves the solid; the field is looked up where the point came from).
//!
//! Rotations follow the right-hand rule: `rotate_z(s, 90)` turns +x onto +y. Moves,
//! rotations, mirrors and uniform scaling keep an exact distance exact; scaling by a
//! vector multiplies by the smallest factor, which keeps the field a distance bound (never
//! more than the true distance), and `twist` keeps the surface but not distances.

use glam::{DMat3, DVec3};
use isoforge_field::{Shape, find_bounds};

use super::{ModernError, finite, finite3};

fn xyz() -> [Shape; 3] {
    [Shape::x(), Shape::y(), Shape::z()]
}

/// `move(s, v)`: the solid moved by `v`.
pub fn move_by(s: &Shape, v: [f64; 3]) -> Result<Shape, ModernError> {
    let v = finite3("the offset", v)?;
    let [x, y, z] = xyz();
    Ok(s.remap(&(x - v[0]), &(y - v[1]), &(z - v[2])))
}

/// `scale(s, k)`: the solid scaled by `k` about the origin (a negative factor mirrors).
pub fn scale_uniform(s: &Shape, k: f64) -> Result<Shape, ModernError> {
    scale(s, [k; 3])
}

/// `scale(s, [kx, ky, kz])`: scaled by a factor per axis about the origin.
pub fn scale(s: &Shape, k: [f64; 3]) -> Result<Shape, ModernError> {
    for f in k {
        if f == 0.0 || !f.is_finite() {
            return Err(ModernError::NotFinite {
                what: "a scale factor (it must also be non-zero)",
                value: f,
            });
        }
    }
    let [x, y, z] = xyz();
    let moved = s.remap(&(x / k[0]), &(y / k[1]), &(z / k[2]));
    let least = k[0].abs().min(k[1].abs()).min(k[2].abs());
    Ok(if least == 1.0 { moved } else { moved * least })
}

/// The shape turned by the rotation matrix `m`: looked up at `mᵀ p`.
pub fn turned(s: &Shape, m: DMat3) -> Shape {
    let [x, y, z] = xyz();
    // Row i of mᵀ is column i of m.
    let row = |c: DVec3| {
        let mut terms = [(c.x, &x), (c.y, &y), (c.z, &z)]
            .into_iter()
            .filter(|(k, _)| *k != 0.0)
            .map(|(k, v)| if k == 1.0 { v.clone() } else { v * k });
        let first = terms.next().unwrap_or_else(|| Shape::constant(0.0));
        terms.fold(first, |sum, t| sum + t)
    };
    s.remap(&row(m.x_axis), &row(m.y_axis), &row(m.z_axis))
}

/// A rotation matrix from degrees, with exact zeros and ones at quarter turns (so a
/// rotation by 90° keeps a box's faces exactly on the lattice).
fn cos_sin(deg: f64) -> (f64, f64) {
    let quarter = deg / 90.0;
    if quarter == quarter.round() && quarter.abs() < 1e15 {
        match (quarter as i64).rem_euclid(4) {
            0 => (1.0, 0.0),
            1 => (0.0, 1.0),
            2 => (-1.0, 0.0),
            _ => (0.0, -1.0),
        }
    } else {
        let r = deg.to_radians();
        (r.cos(), r.sin())
    }
}

/// The matrix of a turn by `deg` about the x axis.
pub fn matrix_x(deg: f64) -> Result<DMat3, ModernError> {
    let (c, sn) = cos_sin(finite("the angle", deg)?);
    Ok(DMat3::from_cols(
        DVec3::X,
        DVec3::new(0.0, c, sn),
        DVec3::new(0.0, -sn, c),
    ))
}

/// The matrix of a turn by `deg` about the y axis.
pub fn matrix_y(deg: f64) -> Result<DMat3, ModernError> {
    let (c, sn) = cos_sin(finite("the angle", deg)?);
    Ok(DMat3::from_cols(
        DVec3::new(c, 0.0, -sn),
        DVec3::Y,
        DVec3::new(sn, 0.0, c),
    ))
}

/// The matrix of a turn by `deg` about the z axis.
pub fn matrix_z(deg: f64) -> Result<DMat3, ModernError> {
    let (c, sn) = cos_sin(finite("the angle", deg)?);
    Ok(DMat3::from_cols(
        DVec3::new(c, sn, 0.0),
        DVec3::new(-sn, c, 0.0),
        DVec3::Z,
    ))
}

/// The matrix of a turn by `deg` about an axis through the origin (Rodrigues).
pub fn matrix_axis(axis: [f64; 3], deg: f64) -> Result<DMat3, ModernError> {
    let a = DVec3::from(finite3("the axis", axis)?);
    let len = a.length();
    if len == 0.0 {
        return Err(ModernError::ZeroVector { what: "the axis" });
    }
    let (c, sn) = cos_sin(finite("the angle", deg)?);
    Ok(rotation(a / len, c, sn))
}

/// `rotate_x(s, deg)`: turned about the x axis.
pub fn rotate_x(s: &Shape, deg: f64) -> Result<Shape, ModernError> {
    Ok(turned(s, matrix_x(deg)?))
}

/// `rotate_y(s, deg)`: turned about the y axis.
pub fn rotate_y(s: &Shape, deg: f64) -> Result<Shape, ModernError> {
    Ok(turned(s, matrix_y(deg)?))
}

/// `rotate_z(s, deg)`: turned about the z axis.
pub fn rotate_z(s: &Shape, deg: f64) -> Result<Shape, ModernError> {
    Ok(turned(s, matrix_z(deg)?))
}

/// `rotate(s, axis, deg)`: turned about an axis through the origin.
pub fn rotate(s: &Shape, axis: [f64; 3], deg: f64) -> Result<Shape, ModernError> {
    Ok(turned(s, matrix_axis(axis, deg)?))
}

/// The rotation about unit axis `a` with cosine `c` and sine `s` (Rodrigues' formula).
pub fn rotation(a: DVec3, c: f64, s: f64) -> DMat3 {
    let k = DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    );
    DMat3::IDENTITY + k * s + k * k * (1.0 - c)
}

/// `mirror_x(s)`: reflected in the plane x = 0.
pub fn mirror_x(s: &Shape) -> Shape {
    let [x, y, z] = xyz();
    s.remap(&-x, &y, &z)
}

/// `mirror_y(s)`: reflected in the plane y = 0.
pub fn mirror_y(s: &Shape) -> Shape {
    let [x, y, z] = xyz();
    s.remap(&x, &-y, &z)
}

/// `mirror_z(s)`: reflected in the plane z = 0.
pub fn mirror_z(s: &Shape) -> Shape {
    let [x, y, z] = xyz();
    s.remap(&x, &y, &-z)
}

/// `twist(s, deg_per_mm)`: each slice z = h turned about the z axis by `h · deg_per_mm`
/// degrees (right-handed).
///
/// A twist keeps each point's distance from the z axis and its height, so a bounded solid
/// stays within the cylinder about z that holds its region; the field is cut to that
/// cylinder (grown by a margin, so the surface is never on it). Without it, intervals
/// over a box far off the axis see every turn of the slice (x·cos + y·sin may be zero),
/// nothing far away is pruned, and a twisted box had no region of its own: a model
/// `twist(box(..), 10)` asked for `bounds()`, and a hull of it could not be built.
pub fn twist(s: &Shape, deg_per_mm: f64) -> Result<Shape, ModernError> {
    let rate = finite("the twist rate", deg_per_mm)?.to_radians();
    let [x, y, z] = xyz();
    let angle = &z * rate;
    let (c, sn) = (angle.cos(), angle.sin());
    let xs = &x * &c + &y * &sn;
    let ys = &y * &c - &x * &sn;
    let twisted = s.remap(&xs, &ys, &z);
    let Ok(region) = find_bounds(s) else {
        // Not bounded (a gyroid, a half-space): nothing to cut to.
        return Ok(twisted);
    };
    let (lo, hi) = (region.min, region.max);
    let radius = [lo[0], hi[0]]
        .iter()
        .flat_map(|&a| [lo[1], hi[1]].map(|b| a.hypot(b)))
        .fold(0.0, f64::max);
    let margin = 0.05 * radius.max(hi[2] - lo[2]);
    let around = (x.square() + y.square()).sqrt() - (radius + margin);
    let along = (Shape::constant(lo[2] - margin) - &z).max(&(&z - (hi[2] + margin)));
    Ok(twisted.max(&around.max(&along)))
}
