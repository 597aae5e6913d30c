//! Each classic formula checked at sample points against the formula as docs/language.md
//! writes it, in plain f64.

use std::f64::consts::PI;

use isoforge_field::Shape;

use super::*;
use crate::reference::at;

const POINTS: [[f64; 3]; 7] = [
    [0.0, 0.0, 0.0],
    [0.3, -0.7, 1.1],
    [1.5, 0.25, -0.5],
    [-2.0, 1.0, 0.75],
    [0.1, 0.2, 0.3],
    [3.0, -3.5, 2.5],
    [-0.6, -0.4, -1.2],
];

fn check(name: &str, s: &Shape, want: impl Fn(f64, f64, f64) -> f64) {
    for p in POINTS {
        let (got, w) = (at(s, p), want(p[0], p[1], p[2]));
        let tol = 1e-9 * (1.0 + w.abs());
        assert!(
            (got - w).abs() <= tol,
            "{name} at {p:?}: got {got}, want {w}"
        );
    }
}

fn fmax(a: f64, b: f64) -> f64 {
    a.max(b)
}

#[test]
fn primitives_match_their_formulas() {
    check("Sphere", &sphere(1.5), |x, y, z| {
        x * x + y * y + z * z - 1.5 * 1.5
    });
    let h = 2.0;
    check("Cube", &cube(h), |x, y, z| {
        fmax(
            fmax((x / (h / 2.0)).abs(), (y / (h / 2.0)).abs()),
            (z / (h / 2.0)).abs(),
        ) - 1.0
    });
    let (a, b, c) = (1.0, 0.25, 3.0);
    check("Prism", &prism(a, b, c), |x, y, z| {
        fmax(
            fmax((x / (a / 2.0)).abs(), (y / (b / 2.0)).abs()),
            (z / (c / 2.0)).abs(),
        ) - 1.0
    });
    check("Torus", &torus(2.0, 0.5), |x, y, z| {
        (2.0 - (x * x + y * y).sqrt()).powi(2) + z * z - 0.25
    });
    let close_f = |s: f64, b: f64| (s / (b / 2.0)).abs() - 1.0;
    check("Cyl", &cyl(0.35, 0.5, 6.0), |x, y, z| {
        fmax(x * x / 0.35 + y * y / 0.5 - 1.0, close_f(z, 6.0))
    });
    check("Cone", &cone(1.0, 2.0, 9.0), |x, y, z| {
        fmax(
            9.0 * (x * x / 1.0 + y * y / 4.0).sqrt() - z,
            close_f(z, 9.0),
        )
    });
    check("Ellip", &ellip(1.0, 2.0, 3.0), |x, y, z| {
        x * x + y * y / 4.0 + z * z / 9.0 - 1.0
    });
    check("Para", &para(1.0, 2.0, 0.5), |x, y, z| {
        fmax(x * x + y * y / 4.0 - 0.5 * z, z) - 1.0
    });
    check("Close", &close(Shape::z(), 3.0), |_, _, z| close_f(z, 3.0));
    check("HSpace", &hspace(0.5), |_, _, z| z - 0.5);
    check("Tetrahedral", &tetrahedral(18.0, 18.0, 60.0), |x, y, z| {
        let r2 = x * x + y * y + z * z;
        r2 * r2 + 18.0 * x * y * z - 18.0 * r2 + 60.0
    });
    check("Sinus", &sinus(1.0, 5.0), |x, y, z| {
        (PI * (x * x + y * y - 1.0)).sin() / 2.0 + 5.0 * z
    });
    let (a, b, c) = (-0.5, 1.0, 4.0);
    check("Bug", &bug(a, b, c), |x, y, z| {
        ((x * (b * y).cos() - z * (b * y).sin()) + a).powi(2)
            + (y / c).powi(2)
            + (x * (b * y).sin() + z * (b * y).cos()).powi(2)
            - 1.0
    });
    check("Drope", &drope(4.0), |x, y, z| {
        z - 4.0 * x * (-x * x - y * y).exp()
    });
    let (a, b, c, d, e) = (1.0, 9.0 / 4.0, 1.0, 1.0, 9.0 / 80.0);
    check("Heart", &heart(a, b, c, d, e), |x, y, z| {
        (a * x * x + b * y * y + c * z * z - 1.0).powi(3)
            - d * x * x * z.powi(3)
            - e * y * y * z.powi(3)
    });
}

#[test]
fn parameters_may_be_fields() {
    // A sphere whose radius grows with z: radius 1 at z = 0, 2 at z = 1.
    let s = sphere(1.0 + Shape::z());
    assert_eq!(at(&s, [1.0, 0.0, 0.0]), 0.0);
    assert_eq!(at(&s, [0.0, 0.0, 1.0]), 1.0 - 4.0);
}

fn probe() -> Shape {
    // An asymmetric field, so every substitution shows.
    Shape::x() + 10.0 * Shape::y() + 100.0 * Shape::z()
}

#[test]
fn transforms_substitute_as_written() {
    let s = probe();
    let f = |x: f64, y: f64, z: f64| x + 10.0 * y + 100.0 * z;
    check("TransX", &trans_x(&s, 2.0), |x, y, z| f(x - 2.0, y, z));
    check("TransY", &trans_y(&s, 2.0), |x, y, z| f(x, y - 2.0, z));
    check("TransZ", &trans_z(&s, 2.0), |x, y, z| f(x, y, z - 2.0));
    check("ScaleX", &scale_x(&s, 4.0), |x, y, z| f(x / 4.0, y, z));
    check("ScaleY", &scale_y(&s, 4.0), |x, y, z| f(x, y / 4.0, z));
    check("ScaleZ", &scale_z(&s, 4.0), |x, y, z| f(x, y, z / 4.0));
    check("ScaleXYZ", &scale_xyz(&s, 0.25), |x, y, z| {
        f(x / 0.25, y / 0.25, z / 0.25)
    });
    check("ReflectXY", &reflect_xy(&s), |x, y, z| f(x, y, -z));
    check("ReflectZX", &reflect_zx(&s), |x, y, z| f(x, -y, z));
    check("ReflectYZ", &reflect_yz(&s), |x, y, z| f(-x, y, z));
    let r: f64 = 0.7;
    let (c, sn) = (r.cos(), r.sin());
    check("RotateRX", &rotate_rx(&s, r), |x, y, z| {
        f(x, y * c - z * sn, y * sn + z * c)
    });
    check("RotateRY", &rotate_ry(&s, r), |x, y, z| {
        f(x * c + z * sn, y, -x * sn + z * c)
    });
    check("RotateRZ", &rotate_rz(&s, r), |x, y, z| {
        f(x * c + y * sn, -x * sn + y * c, z)
    });
    let d: f64 = 40.0;
    let (c, sn) = (d.to_radians().cos(), d.to_radians().sin());
    check("RotateX", &rotate_x(&s, d), |x, y, z| {
        f(x, y * c - z * sn, y * sn + z * c)
    });
    check("RotateY", &rotate_y(&s, d), |x, y, z| {
        f(x * c + z * sn, y, -x * sn + z * c)
    });
    check("RotateZ", &rotate_z(&s, d), |x, y, z| {
        f(x * c + y * sn, -x * sn + y * c, z)
    });
}

#[test]
fn combinations_match_their_formulas() {
    let a = sphere(1.0);
    let b = Shape::x() - 0.5;
    let fa = |x: f64, y: f64, z: f64| x * x + y * y + z * z - 1.0;
    let fb = |x: f64, _: f64, _: f64| x - 0.5;
    check("Union", &union(&a, &b), |x, y, z| {
        fa(x, y, z).min(fb(x, y, z))
    });
    check("Intersect", &intersect(&a, &b), |x, y, z| {
        fa(x, y, z).max(fb(x, y, z))
    });
    check("Subtract", &subtract(&a, &b), |x, y, z| {
        fa(x, y, z).max(-fb(x, y, z))
    });
    check("Morph", &morph(&a, &b, 0.3), |x, y, z| {
        (fb(x, y, z) - fa(x, y, z)) * 0.3 + fa(x, y, z)
    });
    check("Blend", &blend(&a, &b, 0.5), |x, y, z| {
        fa(x, y, z) * fb(x, y, z) - 1.0
    });
    check("Combine", &combine(&a, &b, 2.0), |x, y, z| {
        2.0 * (fa(x, y, z) + fb(x, y, z))
    });
    check("Max", &max(&a, &b), |x, y, z| fa(x, y, z).max(fb(x, y, z)));
    check("Min", &min(&a, &b), |x, y, z| fa(x, y, z).min(fb(x, y, z)));
}

#[test]
fn rotations_move_shapes_the_expected_way() {
    // A ball at +x turned 90 degrees about z lands at +y (x -> x cos r + y sin r).
    let ball = trans_x(&sphere(0.5), 2.0);
    let turned = rotate_z(&ball, 90.0);
    assert!(at(&turned, [0.0, 2.0, 0.0]) < 0.0);
    assert!(at(&turned, [2.0, 0.0, 0.0]) > 0.0);
}

#[test]
fn union_all_is_balanced_and_complete() {
    let balls: Vec<Shape> = (0..100).map(|i| trans_x(&sphere(0.25), i as f64)).collect();
    let u = union_all(&balls).unwrap();
    for i in 0..100 {
        assert!(at(&u, [i as f64, 0.0, 0.0]) < 0.0);
    }
    assert!(at(&u, [0.5, 0.0, 0.0]) > 0.0);
    assert!(union_all(&[]).is_none());
    fn depth(s: &Shape) -> usize {
        match s.node() {
            isoforge_field::ShapeNode::Binary(isoforge_field::BinaryOp::Min, a, b) => {
                1 + depth(a).max(depth(b))
            }
            _ => 0,
        }
    }
    assert_eq!(depth(&u), 7);
}

mod laws {
    use super::*;
    use proptest::prelude::*;

    fn lumpy() -> Shape {
        // Not symmetric under any of the transforms, so an identity that fails shows.
        torus(2.0, 0.5) + 0.3 * Shape::x() - 0.2 * Shape::y() * Shape::z()
    }

    fn near(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        #[test]
        fn transforms_undo(
            p in prop::array::uniform3(-4.0f64..4.0),
            t in -3.0f64..3.0,
            k in 0.2f64..5.0,
            r in -7.0f64..7.0,
        ) {
            let s = lumpy();
            let v = at(&s, p);
            let undo: [(&str, Shape); 10] = [
                ("TransX", trans_x(&trans_x(&s, t), -t)),
                ("TransY", trans_y(&trans_y(&s, t), -t)),
                ("TransZ", trans_z(&trans_z(&s, t), -t)),
                ("ScaleX", scale_x(&scale_x(&s, k), 1.0 / k)),
                ("ScaleXYZ", scale_xyz(&scale_xyz(&s, k), 1.0 / k)),
                ("ReflectXY", reflect_xy(&reflect_xy(&s))),
                ("ReflectYZ", reflect_yz(&reflect_yz(&s))),
                ("RotateRX", rotate_rx(&rotate_rx(&s, r), -r)),
                ("RotateRY", rotate_ry(&rotate_ry(&s, r), -r)),
                ("RotateZ", rotate_z(&rotate_z(&s, r * 30.0), -r * 30.0)),
            ];
            for (name, u) in undo {
                prop_assert!(near(at(&u, p), v), "{name}: {} vs {v}", at(&u, p));
            }
        }

        #[test]
        fn rotations_keep_a_centred_sphere(
            p in prop::array::uniform3(-4.0f64..4.0),
            r in -7.0f64..7.0,
        ) {
            let s = sphere(2.0);
            let v = at(&s, p);
            for rotated in [rotate_rx(&s, r), rotate_ry(&s, r), rotate_rz(&s, r)] {
                prop_assert!(near(at(&rotated, p), v));
            }
        }

        #[test]
        fn booleans_are_min_and_max(
            p in prop::array::uniform3(-4.0f64..4.0),
            c in prop::array::uniform3(-1.0f64..1.0),
        ) {
            let a = sphere(2.0);
            let b = translate(&cube(2.0), c);
            let (va, vb) = (at(&a, p), at(&b, p));
            prop_assert_eq!(at(&union(&a, &b), p), va.min(vb));
            prop_assert_eq!(at(&union(&b, &a), p), va.min(vb));
            prop_assert_eq!(at(&intersect(&a, &b), p), va.max(vb));
            prop_assert_eq!(at(&subtract(&a, &b), p), va.max(-vb));
            // Inside the union iff inside either.
            prop_assert_eq!(at(&union(&a, &b), p) < 0.0, va < 0.0 || vb < 0.0);
        }
    }
}
