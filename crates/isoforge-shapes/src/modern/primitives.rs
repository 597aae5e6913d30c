//! Exact signed-distance primitives, written as kernel expressions (so they run at kernel
//! speed and their tapes simplify per octree cell).
//!
//! Lengths are taken as `max(0, sqrt(..))` with the constant on the left: the value is the
//! same, but where the length is 0 (inside a box, on a cylinder's axis) the gradient
//! evaluator takes the constant's slope 0 instead of `0 * inf = NaN`, so normals and the
//! first-order distance of `offset` stay defined there.

use glam::DVec3;
use isoforge_field::Shape;

use super::{ModernError, finite, finite3, positive};

fn xyz() -> (Shape, Shape, Shape) {
    (Shape::x(), Shape::y(), Shape::z())
}

/// `sqrt(a² + b²)`, with slope 0 where it is 0 (see the module doc).
pub fn length2(a: &Shape, b: &Shape) -> Shape {
    Shape::constant(0.0).max(&(a.square() + b.square()).sqrt())
}

/// `sqrt(a² + b² + c²)`, with slope 0 where it is 0.
pub fn length3(a: &Shape, b: &Shape, c: &Shape) -> Shape {
    Shape::constant(0.0).max(&(a.square() + b.square() + c.square()).sqrt())
}

/// `sphere(r)`: the ball of radius `r` at the origin, `|p| - r`.
pub fn sphere(r: f64) -> Result<Shape, ModernError> {
    let r = positive("the radius", r)?;
    let (x, y, z) = xyz();
    Ok(length3(&x, &y, &z) - r)
}

/// `box([sx, sy, sz])`: the box of those sides centred at the origin. With
/// `q = |p| - size/2`: `|max(q, 0)| + min(max(qx, qy, qz), 0)`.
pub fn box3(size: [f64; 3]) -> Result<Shape, ModernError> {
    for s in size {
        positive("each side of the box", s)?;
    }
    let (x, y, z) = xyz();
    let q = [x, y, z]
        .iter()
        .zip(size)
        .map(|(c, s)| c.abs() - s / 2.0)
        .collect::<Vec<_>>();
    let zero = Shape::constant(0.0);
    let outside = length3(&q[0].max(&zero), &q[1].max(&zero), &q[2].max(&zero));
    let inside = q[0].max(&q[1]).max(&q[2]).min(&zero);
    Ok(outside + inside)
}

/// The exact distance of a 2D "rectangle" profile `(d0, d1)` (each a signed distance to
/// one pair of parallel sides): `|max(d, 0)| + min(max(d0, d1), 0)`.
fn rectangle(d0: &Shape, d1: &Shape) -> Shape {
    let zero = Shape::constant(0.0);
    length2(&d0.max(&zero), &d1.max(&zero)) + d0.max(d1).min(&zero)
}

/// `cylinder(r, h)`: radius `r`, height `h`, axis z, centred at the origin.
pub fn cylinder(r: f64, h: f64) -> Result<Shape, ModernError> {
    let r = positive("the radius", r)?;
    let h = positive("the height", h)?;
    let (x, y, z) = xyz();
    Ok(rectangle(&(length2(&x, &y) - r), &(z.abs() - h / 2.0)))
}

/// `torus(R, r)`: the ring of radius `R` about the z axis, tube radius `r`.
pub fn torus(big: f64, small: f64) -> Result<Shape, ModernError> {
    let big = positive("the ring radius R", big)?;
    let small = positive("the tube radius r", small)?;
    let (x, y, z) = xyz();
    Ok(length2(&(length2(&x, &y) - big), &z) - small)
}

/// `capsule(p0, p1, r)`: all points within `r` of the segment p0–p1.
pub fn capsule(p0: [f64; 3], p1: [f64; 3], r: f64) -> Result<Shape, ModernError> {
    let r = positive("the radius", r)?;
    let (a, b) = (
        DVec3::from(finite3("p0", p0)?),
        DVec3::from(finite3("p1", p1)?),
    );
    let ba = b - a;
    let (x, y, z) = xyz();
    let pa = [x - a.x, y - a.y, z - a.z];
    let len2 = ba.length_squared();
    if len2 == 0.0 {
        return Ok(length3(&pa[0], &pa[1], &pa[2]) - r);
    }
    let t = (&pa[0] * ba.x + &pa[1] * ba.y + &pa[2] * ba.z) / len2;
    let t = Shape::constant(0.0).max(&Shape::constant(1.0).min(&t));
    let d = [&pa[0] - &t * ba.x, &pa[1] - &t * ba.y, &pa[2] - &t * ba.z];
    Ok(length3(&d[0], &d[1], &d[2]) - r)
}

/// `half_space(normal, offset)`: the points with `n·p < offset`, `n` the unit normal.
pub fn half_space(normal: [f64; 3], offset: f64) -> Result<Shape, ModernError> {
    let n = DVec3::from(finite3("the normal", normal)?);
    let offset = finite("the offset", offset)?;
    let len = n.length();
    if len == 0.0 {
        return Err(ModernError::ZeroVector { what: "the normal" });
    }
    let n = n / len;
    let (x, y, z) = xyz();
    Ok(x * n.x + y * n.y + z * n.z - offset)
}

/// The sign of `h` as a field: -1 or 1 beyond 1e-9 mm of zero, linear within. Times a
/// distance `d` with `|h| <= d` this is exact wherever `|h| >= 1e-9`, and off by less
/// than 1e-9 mm elsewhere.
fn sign_of(h: &Shape) -> Shape {
    const BAND: f64 = 1e-9;
    Shape::constant(-1.0).max(&Shape::constant(1.0).min(&(h / BAND)))
}

/// The unsigned distance from `(u, v)` to the segment a–b in that plane.
fn segment_distance(u: &Shape, v: &Shape, a: [f64; 2], b: [f64; 2]) -> Shape {
    let (du, dv) = (b[0] - a[0], b[1] - a[1]);
    let pu = u - a[0];
    let pv = v - a[1];
    let t = (&pu * du + &pv * dv) / (du * du + dv * dv);
    let t = Shape::constant(0.0).max(&Shape::constant(1.0).min(&t));
    length2(&(pu - &t * du), &(pv - &t * dv))
}

/// `cone(r, h)`: base of radius `r` on z = 0, apex at height `h` on the z axis.
///
/// In the half-plane (ρ, z) the cone is the triangle (0, 0), (r, 0), (0, h). Outside a
/// convex polygon the distance is the distance to the nearest edge; inside it is minus
/// the distance to the nearest edge line, which is the largest of the edge lines' signed
/// distances H. Both have the magnitude D of the nearest-edge distance, so the field is
/// sign(H)·D (the axis side need not be an edge: the mirrored triangle is never nearer).
pub fn cone(r: f64, h: f64) -> Result<Shape, ModernError> {
    let r = positive("the base radius", r)?;
    let h = positive("the height", h)?;
    let (x, y, z) = xyz();
    let rho = length2(&x, &y);
    let slant = (h * h + r * r).sqrt();
    // Outward signed distances to the base line (z = 0) and the slanted side's line.
    let base_line = -&z;
    let side_line = (h * (&rho - r) + r * &z) / slant;
    let lines = base_line.max(&side_line);
    let nearest = segment_distance(&rho, &z, [0.0, 0.0], [r, 0.0]).min(&segment_distance(
        &rho,
        &z,
        [r, 0.0],
        [0.0, h],
    ));
    Ok(sign_of(&lines) * nearest)
}

/// `ellipsoid([a, b, c])`: semi-axes a, b, c along x, y, z.
///
/// No closed form of its distance exists. The field is `(k0 - 1)·k0 / k1` with
/// `k0 = |p / r|`, `k1 = |p / r²|` (Quilez's bound): zero exactly on the ellipsoid, the
/// distance itself for a sphere, and within a few percent of it near the surface of
/// others. `k0 / k1` always lies between the smallest and largest semi-axis; clamping it
/// there keeps the centre (where both are 0) inside instead of 0 / 0.
pub fn ellipsoid(radii: [f64; 3]) -> Result<Shape, ModernError> {
    for r in radii {
        positive("each semi-axis", r)?;
    }
    let (x, y, z) = xyz();
    let k0 = length3(&(&x / radii[0]), &(&y / radii[1]), &(&z / radii[2]));
    let k1 = length3(
        &(&x / (radii[0] * radii[0])),
        &(&y / (radii[1] * radii[1])),
        &(&z / (radii[2] * radii[2])),
    );
    let (lo, hi) = (
        radii[0].min(radii[1]).min(radii[2]),
        radii[0].max(radii[1]).max(radii[2]),
    );
    let k1 = Shape::constant(f64::MIN_POSITIVE).max(&k1);
    let ratio = Shape::constant(lo).max(&Shape::constant(hi).min(&(&k0 / k1)));
    Ok((k0 - 1.0) * ratio)
}

/// `gyroid(period, thickness)`: the sheet of that wall thickness around the gyroid
/// surface `g = sin(kx)cos(ky) + sin(ky)cos(kz) + sin(kz)cos(kx)`, `k = 2π / period`.
/// It fills space: intersect it with a body.
///
/// The field is the first-order distance to the surface, `|g| / |∇g|`, minus half the
/// thickness (∇g written out, so no derivative is taken at run time).
pub fn gyroid(period: f64, thickness: f64) -> Result<Shape, ModernError> {
    let period = positive("the period", period)?;
    let thickness = positive("the thickness", thickness)?;
    let k = std::f64::consts::TAU / period;
    let (x, y, z) = xyz();
    let (kx, ky, kz) = (x * k, y * k, z * k);
    let (sx, cx) = (kx.sin(), kx.cos());
    let (sy, cy) = (ky.sin(), ky.cos());
    let (sz, cz) = (kz.sin(), kz.cos());
    let g = &sx * &cy + &sy * &cz + &sz * &cx;
    let gx = (&cx * &cy - &sz * &sx) * k;
    let gy = (&cy * &cz - &sx * &sy) * k;
    let gz = (&cz * &cx - &sy * &sz) * k;
    // |∇g| vanishes only at isolated points off the surface; the floor keeps it finite.
    let slope = Shape::constant(1e-9 * k).max(&(gx.square() + gy.square() + gz.square()).sqrt());
    Ok(g.abs() / slope - thickness / 2.0)
}
