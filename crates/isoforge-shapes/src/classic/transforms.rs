//! The classic transforms: substitution of x, y, z, as the 2010 modeler defined them.
//!
//! A transform replaces the coordinates in the field (`TransX(s, t)` is `s(x - t, y, z)`),
//! so the field is evaluated at the inverse-transformed point. Substitution is memoized
//! ([`Shape::remap`]), so shared parts of `s` stay shared.

use isoforge_field::Shape;

fn xyz() -> (Shape, Shape, Shape) {
    (Shape::x(), Shape::y(), Shape::z())
}

/// `TransX(s, t)`: x → x - t (moves `s` by `t` along x).
pub fn trans_x(s: &Shape, t: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&(x - t.into()), &y, &z)
}

/// `TransY(s, t)`: y → y - t.
pub fn trans_y(s: &Shape, t: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &(y - t.into()), &z)
}

/// `TransZ(s, t)`: z → z - t.
pub fn trans_z(s: &Shape, t: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &y, &(z - t.into()))
}

/// Moves `s` by a vector (x → x - v₀, y → y - v₁, z → z - v₂).
pub fn translate(s: &Shape, v: [f64; 3]) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&(x - v[0]), &(y - v[1]), &(z - v[2]))
}

/// `ScaleX(s, k)`: x → x / k (stretches `s` by `k` along x).
pub fn scale_x(s: &Shape, k: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&(x / k.into()), &y, &z)
}

/// `ScaleY(s, k)`: y → y / k.
pub fn scale_y(s: &Shape, k: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &(y / k.into()), &z)
}

/// `ScaleZ(s, k)`: z → z / k.
pub fn scale_z(s: &Shape, k: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &y, &(z / k.into()))
}

/// `ScaleXYZ(s, k)`: x, y, z → x / k, y / k, z / k.
pub fn scale_xyz(s: &Shape, k: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let k = k.into();
    s.remap(&(x / &k), &(y / &k), &(z / &k))
}

/// `ReflectXY(s)`: z → -z (mirror in the xy plane).
pub fn reflect_xy(s: &Shape) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &y, &-z)
}

/// `ReflectZX(s)`: y → -y (mirror in the zx plane).
pub fn reflect_zx(s: &Shape) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&x, &-y, &z)
}

/// `ReflectYZ(s)`: x → -x (mirror in the yz plane).
pub fn reflect_yz(s: &Shape) -> Shape {
    let (x, y, z) = xyz();
    s.remap(&-x, &y, &z)
}

/// `RotateRX(s, r)`: y → y·cos r − z·sin r, z → y·sin r + z·cos r (r in radians).
pub fn rotate_rx(s: &Shape, r: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let r = r.into();
    let (c, sn) = (r.cos(), r.sin());
    let y2 = &y * &c - &z * &sn;
    let z2 = &y * &sn + &z * &c;
    s.remap(&x, &y2, &z2)
}

/// `RotateRY(s, r)`: x → x·cos r + z·sin r, z → −x·sin r + z·cos r (r in radians).
pub fn rotate_ry(s: &Shape, r: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let r = r.into();
    let (c, sn) = (r.cos(), r.sin());
    let x2 = &x * &c + &z * &sn;
    let z2 = -(&x * &sn) + &z * &c;
    s.remap(&x2, &y, &z2)
}

/// `RotateRZ(s, r)`: x → x·cos r + y·sin r, y → −x·sin r + y·cos r (r in radians).
pub fn rotate_rz(s: &Shape, r: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let r = r.into();
    let (c, sn) = (r.cos(), r.sin());
    let x2 = &x * &c + &y * &sn;
    let y2 = -(&x * &sn) + &y * &c;
    s.remap(&x2, &y2, &z)
}

/// Degrees to radians, as a field (folds to a number for a number).
pub fn deg_to_rad(d: impl Into<Shape>) -> Shape {
    d.into() * (std::f64::consts::PI / 180.0)
}

/// `RotateX(s, d)`: [`rotate_rx`] by `d` degrees.
pub fn rotate_x(s: &Shape, d: impl Into<Shape>) -> Shape {
    rotate_rx(s, deg_to_rad(d))
}

/// `RotateY(s, d)`: [`rotate_ry`] by `d` degrees.
pub fn rotate_y(s: &Shape, d: impl Into<Shape>) -> Shape {
    rotate_ry(s, deg_to_rad(d))
}

/// `RotateZ(s, d)`: [`rotate_rz`] by `d` degrees.
pub fn rotate_z(s: &Shape, d: impl Into<Shape>) -> Shape {
    rotate_rz(s, deg_to_rad(d))
}
