//! Shapes with known sections and volumes, shared by the slicer's tests.
#![allow(dead_code)]

use isoforge_field::{Bounds, Shape};

/// A solid with an exact cross-section distance and volume.
pub struct Known {
    pub shape: Shape,
    pub bounds: Bounds,
    pub volume: f64,
    /// Signed distance in the plane z (≤ 0 inside the section), model coordinates.
    pub section: Box<dyn Fn(f64, f64, f64) -> f64 + Sync>,
    /// Exact section area at z.
    pub area: Box<dyn Fn(f64) -> f64 + Sync>,
}

fn xyz() -> (Shape, Shape, Shape) {
    (Shape::x(), Shape::y(), Shape::z())
}

pub fn sphere(r: f64) -> Known {
    let (x, y, z) = xyz();
    let m = r + 1.0;
    Known {
        shape: (x.square() + y.square() + z.square()).sqrt() - r,
        bounds: Bounds::new([-m; 3], [m; 3]).unwrap(),
        volume: 4.0 / 3.0 * std::f64::consts::PI * r.powi(3),
        section: Box::new(move |x, y, z| {
            let s = (r * r - z * z).max(0.0).sqrt();
            x.hypot(y) - s
        }),
        area: Box::new(move |z| std::f64::consts::PI * (r * r - z * z).max(0.0)),
    }
}

pub fn cube(a: f64) -> Known {
    let (x, y, z) = xyz();
    let h = a / 2.0;
    let m = h + 1.0;
    Known {
        shape: x.abs().max(&y.abs()).max(&z.abs()) - h,
        bounds: Bounds::new([-m; 3], [m; 3]).unwrap(),
        volume: a.powi(3),
        section: Box::new(move |x, y, _| x.abs().max(y.abs()) - h),
        area: Box::new(move |z| if z.abs() <= h { a * a } else { 0.0 }),
    }
}

pub fn torus(big: f64, small: f64) -> Known {
    let (x, y, z) = xyz();
    let m = big + small + 1.0;
    Known {
        shape: ((x.square() + y.square()).sqrt() - big)
            .square()
            .add_z(&z)
            .sqrt()
            - small,
        bounds: Bounds::new([-m, -m, -small - 1.0], [m, m, small + 1.0]).unwrap(),
        volume: 2.0 * std::f64::consts::PI.powi(2) * big * small * small,
        section: Box::new(move |x, y, z| {
            let s = (small * small - z * z).max(0.0).sqrt();
            (x.hypot(y) - big).abs() - s
        }),
        area: Box::new(move |z| {
            let s = (small * small - z * z).max(0.0).sqrt();
            std::f64::consts::PI * ((big + s).powi(2) - (big - s).powi(2))
        }),
    }
}

trait AddZ {
    fn add_z(&self, z: &Shape) -> Shape;
}
impl AddZ for Shape {
    fn add_z(&self, z: &Shape) -> Shape {
        self + z.square()
    }
}
