//! The modern library against written-out distances, and its enclosures against points.

use isoforge_field::{GradEval, Interval, IntervalEval, PointEval, Shape, Tape};
use proptest::prelude::*;

use super::*;

fn at(s: &Shape, p: [f64; 3]) -> f64 {
    PointEval::new().eval(&Tape::new(s), p)
}

fn near(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + b.abs())
}

/// The exact distance to an axis-aligned box of half-sides `h` centred at `c`, by the
/// nearest point (clamping), independent of the formula under test.
fn box_distance(p: [f64; 3], h: [f64; 3]) -> f64 {
    let q: Vec<f64> = (0..3).map(|i| p[i].abs() - h[i]).collect();
    if q.iter().all(|&v| v <= 0.0) {
        q.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
    } else {
        q.iter().map(|v| v.max(0.0).powi(2)).sum::<f64>().sqrt()
    }
}

fn points() -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    for i in 0..7 {
        for j in 0..7 {
            for k in 0..7 {
                out.push([
                    i as f64 * 1.7 - 5.1,
                    j as f64 * 1.3 - 3.9,
                    k as f64 * 2.1 - 6.3,
                ]);
            }
        }
    }
    out
}

#[test]
fn primitives_are_exact_distances() {
    let s = sphere(2.0).unwrap();
    let b = box3([2.0, 4.0, 6.0]).unwrap();
    let c = cylinder(1.5, 4.0).unwrap();
    let t = torus(3.0, 1.0).unwrap();
    let cap = capsule([0.0, 0.0, -1.0], [0.0, 0.0, 2.0], 0.5).unwrap();
    let h = half_space([0.0, 3.0, 4.0], 1.0).unwrap();
    for p in points() {
        let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!(near(at(&s, p), len - 2.0), "sphere at {p:?}");
        assert!(
            near(at(&b, p), box_distance(p, [1.0, 2.0, 3.0])),
            "box at {p:?}"
        );
        let (dr, dz) = (rho - 1.5, p[2].abs() - 2.0);
        let cyl = if dr <= 0.0 && dz <= 0.0 {
            dr.max(dz)
        } else {
            (dr.max(0.0).powi(2) + dz.max(0.0).powi(2)).sqrt()
        };
        assert!(near(at(&c, p), cyl), "cylinder at {p:?}");
        assert!(near(
            at(&t, p),
            ((rho - 3.0).powi(2) + p[2] * p[2]).sqrt() - 1.0
        ));
        let zc = p[2].clamp(-1.0, 2.0);
        let capd = (p[0] * p[0] + p[1] * p[1] + (p[2] - zc).powi(2)).sqrt() - 0.5;
        assert!(near(at(&cap, p), capd), "capsule at {p:?}");
        assert!(near(at(&h, p), 0.6 * p[1] + 0.8 * p[2] - 1.0));
    }
}

/// The exact distance to the cone with base radius r on z = 0 and apex at height h: the
/// distance in the meridian plane to the whole (mirrored) triangle, edge by edge.
fn cone_distance(p: [f64; 3], r: f64, h: f64) -> f64 {
    let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
    let z = p[2];
    let inside = z >= 0.0 && rho <= r * (1.0 - z / h);
    let seg = |a: [f64; 2], b: [f64; 2]| {
        let (du, dv) = (b[0] - a[0], b[1] - a[1]);
        let t = (((rho - a[0]) * du + (z - a[1]) * dv) / (du * du + dv * dv)).clamp(0.0, 1.0);
        ((rho - a[0] - t * du).powi(2) + (z - a[1] - t * dv).powi(2)).sqrt()
    };
    let d = seg([-r, 0.0], [r, 0.0])
        .min(seg([r, 0.0], [0.0, h]))
        .min(seg([0.0, h], [-r, 0.0]));
    if inside { -d } else { d }
}

#[test]
fn the_cone_is_an_exact_distance() {
    let c = cone(2.0, 5.0).unwrap();
    for p in points() {
        let want = cone_distance(p, 2.0, 5.0);
        assert!(
            (at(&c, p) - want).abs() < 1e-8,
            "cone at {p:?}: {} vs {want}",
            at(&c, p)
        );
    }
    assert!(at(&c, [0.0, 0.0, 1.0]) < 0.0, "on the axis, inside");
    assert!(
        at(&c, [0.0, 0.0, 0.0]).abs() < 1e-12,
        "the base centre is on the surface"
    );
}

#[test]
fn ellipsoid_surface_is_exact_and_its_centre_inside() {
    let e = ellipsoid([1.0, 2.0, 3.0]).unwrap();
    for p in [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, -3.0]] {
        assert!(at(&e, p).abs() < 1e-12);
    }
    let t: f64 = 0.7;
    assert!(at(&e, [t.cos(), 2.0 * t.sin(), 0.0]).abs() < 1e-12);
    assert!(at(&e, [0.0; 3]) < 0.0);
    assert!(at(&e, [0.0, 0.0, 3.1]) > 0.0);
    // A sphere is its own distance.
    let s = ellipsoid([2.0; 3]).unwrap();
    assert!(near(at(&s, [3.0, 0.0, 0.0]), 1.0));
}

#[test]
fn gradients_are_defined_inside_and_on_axes() {
    let mut ge = GradEval::new();
    for s in [
        box3([2.0, 2.0, 2.0]).unwrap(),
        cylinder(1.0, 2.0).unwrap(),
        cone(1.0, 2.0).unwrap(),
        torus(2.0, 0.5).unwrap(),
    ] {
        for p in [[0.0, 0.0, 0.5], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]] {
            let g = ge.eval(&Tape::new(&s), p);
            assert!(g.d.iter().all(|d| d.is_finite()), "{s:?} at {p:?}: {g:?}");
        }
    }
}

#[test]
fn transforms_move_the_solid_the_right_way() {
    let b = box3([2.0, 1.0, 1.0]).unwrap(); // long in x
    let moved = move_by(&b, [10.0, 0.0, 0.0]).unwrap();
    assert!(at(&moved, [10.9, 0.0, 0.0]) < 0.0);
    let turned = rotate_z(&b, 90.0).unwrap(); // now long in y
    assert!(at(&turned, [0.0, 0.9, 0.0]) < 0.0);
    assert!(at(&turned, [0.9, 0.0, 0.0]) > 0.0);
    let tilted = rotate_y(&b, 90.0).unwrap(); // +x onto -z: long in z
    assert!(at(&tilted, [0.0, 0.0, -0.9]) < 0.0);
    let about = rotate(&b, [0.0, 0.0, 2.0], 90.0).unwrap();
    for p in points() {
        assert!(near(at(&about, p), at(&turned, p)));
    }
    // rotate_x: +y onto +z.
    let ylong = box3([1.0, 2.0, 1.0]).unwrap();
    assert!(at(&rotate_x(&ylong, 90.0).unwrap(), [0.0, 0.0, 0.9]) < 0.0);
    // Uniform scaling keeps the distance exact.
    let big = scale_uniform(&sphere(1.0).unwrap(), 3.0).unwrap();
    assert!(near(at(&big, [5.0, 0.0, 0.0]), 2.0));
    let m = mirror_x(&moved);
    assert!(at(&m, [-10.9, 0.0, 0.0]) < 0.0);
    // A twist of 90°/mm turns the slice at z = 1 by a quarter turn.
    let bar = box3([4.0, 0.5, 10.0]).unwrap();
    let tw = twist(&bar, 90.0).unwrap();
    assert!(at(&tw, [1.5, 0.0, 0.0]) < 0.0);
    assert!(at(&tw, [0.0, 1.5, 1.0]) < 0.0);
    assert!(at(&tw, [1.5, 0.0, 1.0]) > 0.0);
    // It has a region of its own, within the cylinder that holds the bar's turns.
    let region = isoforge_field::find_bounds(&tw).expect("a twisted bar is bounded");
    let reach = (2.0f64.hypot(0.25) + 0.5) * 1.2;
    assert!(
        (0..2).all(|a| region.min[a] > -reach && region.max[a] < reach),
        "{region:?}"
    );
    assert!(region.min[2] > -6.0 && region.max[2] < 6.0, "{region:?}");
}

#[test]
fn booleans_and_blends() {
    let a = sphere(1.0).unwrap();
    let b = move_by(&a, [1.5, 0.0, 0.0]).unwrap();
    let u = union(&a, &b);
    let su = smooth_union(&a, &b, 0.5).unwrap();
    // Between the balls the smooth union reaches further out.
    let p = [0.75, 0.7, 0.0];
    assert!(at(&u, p) > 0.0 && at(&su, p) < at(&u, p));
    // Far from the crease nothing changes.
    assert_eq!(at(&su, [-0.5, 0.0, 0.0]), at(&u, [-0.5, 0.0, 0.0]));
    let d = difference(&a, &b);
    assert!(at(&d, [-0.5, 0.0, 0.0]) < 0.0 && at(&d, [0.6, 0.0, 0.0]) > 0.0);
    let all = union_all(&[a.clone(), b.clone(), move_by(&a, [0.0, 3.0, 0.0]).unwrap()]).unwrap();
    assert!(at(&all, [0.0, 3.0, 0.0]) < 0.0);
    let cut = difference_all(&[a.clone(), b.clone()]).unwrap();
    assert_eq!(at(&cut, [0.6, 0.0, 0.0]), at(&d, [0.6, 0.0, 0.0]));
    assert!(smooth_union(&a, &b, 0.0).is_err());
}

#[test]
fn first_order_distance_of_a_scaled_field() {
    // 3·(|p| − 2) has slope 3: its estimate is the distance again.
    let s = (sphere(2.0).unwrap()) * 3.0;
    let v = first_order_distance(&s);
    for p in [[5.0f64, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 2.0, 2.0]] {
        let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(near(at(&v, p), len - 2.0), "{p:?}");
    }
    // The classic sphere x²+y²+z²−4: (r² − 4) / 2r, zero on the sphere.
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let classic = x.square() + y.square() + z.square() - 4.0;
    let v = first_order_distance(&classic);
    assert!(near(at(&v, [3.0, 0.0, 0.0]), 5.0 / 6.0));
    assert!(at(&v, [2.0, 0.0, 0.0]).abs() < 1e-15);
    // At the centre the slope vanishes: deep inside.
    assert_eq!(at(&v, [0.0; 3]), -distance_limit());
    let sh = shell(&classic, 0.5).unwrap();
    assert!(at(&sh, [1.9, 0.0, 0.0]) < 0.0, "in the wall");
    assert!(at(&sh, [1.0, 0.0, 0.0]) > 0.0, "in the hollow");
    assert!(at(&sh, [2.1, 0.0, 0.0]) > 0.0, "outside");
}

fn distance_limit() -> f64 {
    1e12
}

fn heart() -> Shape {
    crate::classic::heart(1.0, 2.25, 1.0, 1.0, 0.1125)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// The estimate's gradient (from ∇f and one difference of it along the gradient's
    /// direction) is the derivative of its values: central differences of them agree,
    /// for a field far from a distance (the classic heart) and its offset.
    #[test]
    fn first_order_distance_gradient_is_the_values_derivative(
        p in [-1.5..1.5f64, -1.5..1.5f64, -1.5..1.5f64],
    ) {
        for s in [first_order_distance(&heart()), offset(&heart(), 0.2).unwrap()] {
            let tape = Tape::new(&s);
            let g = GradEval::new().eval(&tape, p);
            let mut pe = PointEval::new();
            let v = pe.eval(&tape, p);
            prop_assert_eq!(g.v, v);
            // Deep inside the slope all but vanishes and the estimate saturates.
            prop_assume!(v.abs() < 10.0);
            let h = 1e-5;
            for k in 0..3 {
                let (mut a, mut b) = (p, p);
                a[k] += h;
                b[k] -= h;
                let fd = (pe.eval(&tape, a) - pe.eval(&tape, b)) / (2.0 * h);
                prop_assert!(
                    (g.d[k] - fd).abs() <= 1e-4 * (1.0 + fd.abs()),
                    "d{} {} against {} at {:?}", k, g.d[k], fd, p
                );
            }
        }
    }

    /// The estimate's enclosure over a box holds every point value in it, for a field
    /// that is far from a distance (the classic heart) and its offsets and shells.
    #[test]
    fn first_order_distance_encloses_points(
        lo in [-1.5..1.5f64, -1.5..1.5f64, -1.5..1.5f64],
        size in 0.001..1.0f64,
        f in proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64], 6),
    ) {
        for s in [first_order_distance(&heart()), offset(&heart(), 0.2).unwrap(), shell(&heart(), 0.1).unwrap()] {
            let tape = Tape::new(&s);
            let b = [0, 1, 2].map(|i| Interval::try_from((lo[i], lo[i] + size)).unwrap());
            let i = IntervalEval::new().eval(&tape, b);
            let mut pe = PointEval::new();
            for q in &f {
                let p = [0, 1, 2].map(|k| lo[k] + q[k] * size);
                let v = pe.eval(&tape, p);
                prop_assert!(!v.is_nan());
                prop_assert!(i.inf() <= v && v <= i.sup(), "{:?} at {:?} outside {:?}", v, p, i);
            }
        }
    }
}

/// Two hearts far apart: the estimate of their union, narrowed to a box around one,
/// leaves the other out and gives the same values and gradients there; over a box that
/// holds both nothing narrows.
#[test]
fn narrowing_the_first_order_distance_leaves_out_the_far_part() {
    use isoforge_field::CustomField;
    let two = union(&heart(), &move_by(&heart(), [6.0, 0.0, 0.0]).unwrap());
    let whole = FirstOrderDistance::new(&two);
    let iv = |lo: f64, hi: f64| Interval::try_from((lo, hi)).unwrap();
    assert!(
        whole
            .narrow([iv(-2.0, 8.0), iv(-2.0, 2.0), iv(-2.0, 2.0)])
            .is_none()
    );
    let near = whole
        .narrow([iv(-1.5, 1.5), iv(-1.5, 1.5), iv(-1.5, 1.5)])
        .expect("the far heart is left out");
    for i in 0..=6 {
        for j in 0..=6 {
            let p = [-1.5 + 0.5 * i as f64, -1.5 + 0.5 * j as f64, 0.3];
            assert_eq!(near.value(p), whole.value(p), "at {p:?}");
            assert_eq!(near.gradient(p), whole.gradient(p), "at {p:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// A tape narrowed to a box (min/max choices and the custom nodes' own tapes) gives
    /// the whole tape's values and gradients at every point of the box, bit for bit.
    #[test]
    fn a_narrowed_offset_is_the_whole_one_in_its_box(
        c in [-3.0..9.0f64, -3.0..3.0f64, -3.0..3.0f64],
        w in 0.05..3.0f64,
        t in [0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64],
    ) {
        let two = union(&heart(), &move_by(&heart(), [6.0, 0.0, 0.0]).unwrap());
        let ball = move_by(&sphere(1.0).unwrap(), [3.0, 3.0, 0.0]).unwrap();
        let s = union(&offset(&two, 0.2).unwrap(), &ball);
        let tape = Tape::new(&s);
        let b = [0, 1, 2].map(|k| Interval::try_from((c[k] - w, c[k] + w)).unwrap());
        let mut ie = IntervalEval::new();
        ie.eval(&tape, b);
        let short = tape.narrow(&ie);
        let p = [0, 1, 2].map(|k| c[k] + (2.0 * t[k] - 1.0) * w);
        let mut pe = PointEval::new();
        prop_assert_eq!(pe.eval(&short, p), pe.eval(&tape, p));
        let mut ge = GradEval::new();
        let (a, z) = (ge.eval(&short, p), ge.eval(&tape, p));
        prop_assert_eq!((a.v, a.d), (z.v, z.d));
    }
}
