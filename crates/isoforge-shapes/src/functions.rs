//! Functy's function classes, done exactly: the solid under a height field z = h(x, y)
//! and the solid inside a radius function r(θ, φ) about a centre. (Tubes along curves
//! are in `tube.rs`.) The functions are fields already (the script turned its closures
//! into expressions), so these are a few kernel operations around them.

use isoforge_field::Shape;

use crate::modern::{ModernError, finite, finite3, first_order_distance, length2, length3};

/// The slab between a field's surface and its first-order level −t (inward).
fn slab(f: &Shape, thickness: f64) -> Shape {
    let d = first_order_distance(f);
    d.max(&(-&d - thickness))
}

/// `cartesian(|x, y| h, thickness)`: the solid under the surface z = h(x, y).
///
/// Thickness 0 fills down to the region's floor (the field is `z − h`, and the region
/// caps it). A positive thickness is a slab hanging under the surface, measured along the
/// surface normal: between the surface and its first-order offset `(z − h) / √(1 + |∇h|²)
/// = −t`, which for a plane is exact.
pub fn cartesian(h: &Shape, thickness: f64) -> Result<Shape, ModernError> {
    let thickness = finite("the thickness", thickness)?;
    if thickness < 0.0 {
        return Err(ModernError::NotPositive {
            what: "the thickness (0 fills to the region's floor)",
            value: thickness,
        });
    }
    let f = Shape::z() - h;
    Ok(if thickness == 0.0 {
        f
    } else {
        slab(&f, thickness)
    })
}

/// The angles a radius function of `spherical` is given, about `centre`:
/// θ = atan2(y, x) (−π..π) and φ, the elevation (−π/2..π/2).
pub fn spherical_angles(centre: [f64; 3]) -> Result<(Shape, Shape), ModernError> {
    let c = finite3("the centre", centre)?;
    let (x, y, z) = (Shape::x() - c[0], Shape::y() - c[1], Shape::z() - c[2]);
    let theta = y.atan2(&x);
    let phi = z.atan2(&length2(&x, &y));
    Ok((theta, phi))
}

/// `spherical(|theta, phi| r, centre)`: inside where the distance from the centre is
/// below `r` (a field of the angles of [`spherical_angles`]); with a thickness, only a
/// wall that thick under that surface.
pub fn spherical(r: &Shape, centre: [f64; 3], thickness: f64) -> Result<Shape, ModernError> {
    let c = finite3("the centre", centre)?;
    let thickness = finite("the thickness", thickness)?;
    if thickness < 0.0 {
        return Err(ModernError::NotPositive {
            what: "the thickness",
            value: thickness,
        });
    }
    let rho = length3(
        &(Shape::x() - c[0]),
        &(Shape::y() - c[1]),
        &(Shape::z() - c[2]),
    );
    let f = rho - r;
    Ok(if thickness == 0.0 {
        f
    } else {
        slab(&f, thickness)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use isoforge_field::{PointEval, Tape};

    fn at(s: &Shape, p: [f64; 3]) -> f64 {
        PointEval::new().eval(&Tape::new(s), p)
    }

    #[test]
    fn a_flat_height_field_with_thickness_is_a_slab() {
        let s = cartesian(&Shape::constant(0.0), 2.0).unwrap();
        assert!(at(&s, [5.0, -3.0, -1.0]) < 0.0);
        assert!(at(&s, [5.0, -3.0, 0.5]) > 0.0);
        assert!(at(&s, [5.0, -3.0, -2.5]) > 0.0);
        assert!((at(&s, [0.0, 0.0, -1.5]) + 0.5).abs() < 1e-12);
        // Thickness 0 fills downwards.
        let fill = cartesian(&(Shape::x() * 0.5), 0.0).unwrap();
        assert!(at(&fill, [2.0, 0.0, -100.0]) < 0.0);
        assert!(at(&fill, [2.0, 0.0, 1.1]) > 0.0);
        assert!(cartesian(&Shape::constant(0.0), -1.0).is_err());
    }

    #[test]
    fn a_constant_radius_is_a_sphere_and_angles_are_functys() {
        let s = spherical(&Shape::constant(5.0), [1.0, 0.0, 0.0], 0.0).unwrap();
        assert!((at(&s, [7.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!(at(&s, [1.0, 4.9, 0.0]) < 0.0);
        let (theta, phi) = spherical_angles([0.0; 3]).unwrap();
        assert!((at(&theta, [0.0, 1.0, 0.0]) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((at(&phi, [0.0, 0.0, 2.0]) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((at(&phi, [1.0, 1.0, 0.0])).abs() < 1e-12);
        // A shell of thickness 1 hollows the ball.
        let sh = spherical(&Shape::constant(5.0), [0.0; 3], 1.0).unwrap();
        assert!(at(&sh, [4.5, 0.0, 0.0]) < 0.0);
        assert!(at(&sh, [3.5, 0.0, 0.0]) > 0.0);
    }
}
