//! The classic primitives, with the formulas of the 2010 function-based modeler.
//!
//! Every parameter is `impl Into<Shape>`: a number (`sphere(2.0)`) or a field, so a radius
//! may vary over space (`sphere(1.0 + 0.1 * Shape::z())`). Constants fold as the graph is
//! built, so numeric parameters cost nothing at evaluation time.

use isoforge_field::Shape;

use super::combine::intersect;

fn xyz() -> (Shape, Shape, Shape) {
    (Shape::x(), Shape::y(), Shape::z())
}

/// `Sphere(a)`: `x^2+y^2+z^2-a^2`, a ball of radius `a` at the origin.
pub fn sphere(a: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    x.square() + y.square() + z.square() - a.into().square()
}

/// `Cube(h)`: `Max(Max(abs(x/(h/2)), abs(y/(h/2))), abs(z/(h/2))) - 1`, a cube of side `h`.
pub fn cube(h: impl Into<Shape>) -> Shape {
    let h = h.into();
    prism(h.clone(), h.clone(), h)
}

/// `Prism(a, b, c)`: `Max(Max(abs(x/(a/2)), abs(y/(b/2))), abs(z/(c/2))) - 1`, a box of
/// sides `a`, `b`, `c` centred at the origin.
pub fn prism(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let ax = (x / (a.into() / 2.0)).abs();
    let ay = (y / (b.into() / 2.0)).abs();
    let az = (z / (c.into() / 2.0)).abs();
    ax.max(&ay).max(&az) - 1.0
}

/// `Torus(a, b)`: `(a - sqrt(x^2+y^2))^2 + z^2 - b^2`, ring radius `a`, tube radius `b`,
/// around the z axis.
pub fn torus(a: impl Into<Shape>, b: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let rho = (x.square() + y.square()).sqrt();
    (a.into() - rho).square() + z.square() - b.into().square()
}

/// `Cyl(a, b, c)` (alias `Cyyl`): `Intersect(x^2/a + y^2/b - 1, Close(z, c))`, an elliptic
/// cylinder along z of height `c` centred at the origin. Note `a` and `b` divide the squares
/// directly: the semi-axes are `sqrt(a)` and `sqrt(b)`, as in the 2010 modeler.
pub fn cyl(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let side = x.square() / a.into() + y.square() / b.into() - 1.0;
    intersect(&side, &close(z, c))
}

/// `Cone(a, b, c)`: `Intersect(c*sqrt(x^2/a^2 + y^2/b^2) - z, Close(z, c))`.
pub fn cone(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let c = c.into();
    let r = (x.square() / a.into().square() + y.square() / b.into().square()).sqrt();
    intersect(&(&c * r - &z), &close(z, c))
}

/// `Ellip(a, b, c)`: `x^2/a^2 + y^2/b^2 + z^2/c^2 - 1`, an ellipsoid with semi-axes a, b, c.
pub fn ellip(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    x.square() / a.into().square() + y.square() / b.into().square() + z.square() / c.into().square()
        - 1.0
}

/// `Para(a, b, c)`: `Max(x^2/a^2 + y^2/b^2 - c*z, z) - 1`, a paraboloid cut at z = 1.
pub fn para(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let bowl = x.square() / a.into().square() + y.square() / b.into().square() - c.into() * &z;
    bowl.max(&z) - 1.0
}

/// `Close(s, b)`: `abs(s/(b/2)) - 1`, the slab where `|s| < b/2` (s is often `z`).
pub fn close(s: impl Into<Shape>, b: impl Into<Shape>) -> Shape {
    (s.into() / (b.into() / 2.0)).abs() - 1.0
}

/// `HSpace(h)`: `z - h`, everything below the plane z = h.
pub fn hspace(h: impl Into<Shape>) -> Shape {
    Shape::z() - h.into()
}

/// `Tetrahedral(a, b, c)`: `(x^2+y^2+z^2)^2 + a*x*y*z - b*(x^2+y^2+z^2) + c`.
pub fn tetrahedral(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let r2 = x.square() + y.square() + z.square();
    r2.square() + a.into() * x * y * z - b.into() * r2 + c.into()
}

/// `Sinus(r, h)`: `sin(PI*(x^2+y^2-r^2))/2 + h*z`, concentric ripples.
pub fn sinus(r: impl Into<Shape>, h: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let phase = std::f64::consts::PI * (x.square() + y.square() - r.into().square());
    phase.sin() / 2.0 + h.into() * z
}

/// `Bug(a, b, c)`:
/// `((x*cos(b*y) - z*sin(b*y)) + a)^2 + (y/c)^2 + (x*sin(b*y) + z*cos(b*y))^2 - 1`,
/// a torus-like body twisted about y.
pub fn bug(a: impl Into<Shape>, b: impl Into<Shape>, c: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let by = b.into() * &y;
    let (cos, sin) = (by.cos(), by.sin());
    let u = &x * &cos - &z * &sin + a.into();
    let w = &x * &sin + &z * &cos;
    u.square() + (y / c.into()).square() + w.square() - 1.0
}

/// `Drope(h)`: `z - h*x*exp(-x^2-y^2)`, the region under a drop-shaped bump.
pub fn drope(h: impl Into<Shape>) -> Shape {
    let (x, y, z) = xyz();
    let bump = (-x.square() - y.square()).exp();
    z - h.into() * x * bump
}

/// `Heart(a, b, c, d, e)`: `(a*x^2 + b*y^2 + c*z^2 - 1)^3 - d*x^2*z^3 - e*y^2*z^3`
/// (Taubin's heart surface).
pub fn heart(
    a: impl Into<Shape>,
    b: impl Into<Shape>,
    c: impl Into<Shape>,
    d: impl Into<Shape>,
    e: impl Into<Shape>,
) -> Shape {
    let (x, y, z) = xyz();
    let (x2, y2) = (x.square(), y.square());
    let z3 = z.powi(3);
    let body = (a.into() * &x2 + b.into() * &y2 + c.into() * z.square() - 1.0).powi(3);
    body - d.into() * x2 * &z3 - e.into() * y2 * z3
}
