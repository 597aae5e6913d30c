//! Hull fields against distances worked out independently, and their enclosures.

use glam::DVec3;
use isoforge_field::{Interval, IntervalEval, PointEval, Shape, Tape};
use proptest::prelude::*;

use super::*;

fn field(parts: Vec<Convex>) -> Shape {
    hull(parts.into_iter().map(HullPart::Convex).collect())
        .expect("builds")
        .0
}

fn at(s: &Shape, p: DVec3) -> f64 {
    PointEval::new().eval(&Tape::new(s), p.to_array())
}

/// The distance from p to triangle a, b, c by brute force over a fine barycentric grid,
/// refined: slow and simple, unlike the code under test.
fn triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    let n = 200;
    for i in 0..=n {
        for j in 0..=(n - i) {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            let q = a + (b - a) * u + (c - a) * v;
            best = best.min((p - q).length());
        }
    }
    best
}

#[test]
fn four_balls_make_a_rounded_tetrahedron() {
    let centres = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(100.0, 100.0, 0.0),
        DVec3::new(0.0, 100.0, 100.0),
        DVec3::new(100.0, 0.0, 100.0),
    ];
    let s = field(centres.iter().map(|&c| Convex::ball(c, 4.0)).collect());
    let faces = [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)];
    let centre = DVec3::splat(50.0);
    // Outside the tetrahedron the hull's distance is the tetrahedron's minus 4.
    for p in [
        DVec3::new(-10.0, -10.0, -10.0),
        DVec3::new(50.0, 50.0, -20.0),
        DVec3::new(120.0, 120.0, 10.0),
        DVec3::new(0.0, 50.0, 60.0) + DVec3::new(-1.0, 0.0, 1.0) * 10.0,
    ] {
        let tetra = faces
            .iter()
            .map(|&(i, j, k)| triangle_distance(p, centres[i], centres[j], centres[k]))
            .fold(f64::INFINITY, f64::min);
        let got = at(&s, p);
        assert!(
            (got - (tetra - 4.0)).abs() < 0.02,
            "{p}: {got} vs {}",
            tetra - 4.0
        );
    }
    // Deep inside: minus the distance to the nearest face plane, minus 4 (exact near
    // flat faces).
    let v = at(&s, centre);
    let face_dist = 100.0 / 3f64.sqrt() / 2.0; // centre to a face plane of this tetrahedron
    assert!((v + face_dist + 4.0).abs() < 1e-6, "{v}");
}

#[test]
fn hull_of_two_boxes_is_an_exact_distance() {
    // Two unit cubes side by side with a gap: their hull is the 3 x 1 x 1 box.
    let s = field(vec![
        Convex::new(Body::Box(DVec3::splat(0.5))),
        Convex::new(Body::Box(DVec3::splat(0.5))).moved(DVec3::new(2.0, 0.0, 0.0)),
    ]);
    for (p, want) in [
        ([1.0, 0.0, 0.0], -0.5),
        ([1.0, 0.2, 0.1], -0.3),
        ([1.0, 2.5, 0.0], 2.0),
        ([4.5, 0.0, 0.0], 2.0),
        ([3.5, 1.5, 0.0], 2f64.sqrt()),
        ([-0.3, 0.0, 0.0], -0.2),
    ] {
        let got = at(&s, DVec3::from(p));
        assert!((got - want).abs() < 1e-9, "{p:?}: {got} vs {want}");
    }
}

#[test]
fn on_a_facet_the_gradient_is_its_normal() {
    // A cube and a cube turned and moved away: the hull's facets between them are
    // slanted. A line through each side of the bridge, bisected to the last bit (the
    // mesher interpolates crossings on a plane about as finely).
    let turn = glam::DMat3::from_euler(glam::EulerRot::XYZ, 0.5, 0.3, 0.2);
    let s = field(vec![
        Convex::new(Body::Box(DVec3::splat(5.0))).moved(DVec3::splat(20.0)),
        Convex::new(Body::Box(DVec3::splat(3.0)))
            .turned(turn)
            .moved(DVec3::new(40.0, 27.0, 24.0)),
    ]);
    let tape = Tape::new(&s);
    let mut ev = isoforge_field::GradEval::new();
    let mut grad = |p: DVec3| {
        let g = ev.eval(&tape, p.to_array());
        (g.v, DVec3::from(g.d))
    };
    let mut checked = 0;
    for k in 0..40 {
        let a = f64::from(k) * std::f64::consts::TAU / 40.0;
        let inside = DVec3::new(30.0, 23.5, 22.0);
        let mut outside = inside + DVec3::new(0.0, a.cos(), a.sin()) * 20.0;
        let mut inside = inside;
        assert!(grad(inside).0 < 0.0 && grad(outside).0 > 0.0);
        for _ in 0..80 {
            let mid = (inside + outside) * 0.5;
            if grad(mid).0 < 0.0 {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        // Off the facet's middle, by the normals on both sides a little way off.
        let (_, below) = grad(inside - (outside - inside).normalize() * 1e-3);
        let (_, above) = grad(outside + (outside - inside).normalize() * 1e-3);
        if (below - above).length() > 1e-12 {
            continue; // an edge of the hull: no one normal
        }
        for p in [inside, outside] {
            let (v, n) = grad(p);
            assert!(v.abs() < 1e-9, "at {p}: {v}");
            // The fault was the direction from the point to its nearest point, rounding
            // error on the surface.
            assert!((n - below).length() < 1e-9, "at {p}: {n} vs {below}");
        }
        checked += 1;
    }
    assert!(checked >= 20, "{checked} lines met a facet's middle");
}

#[test]
fn hull_of_a_box_and_a_ball_contains_both_and_no_more() {
    let b = Convex::new(Body::Box(DVec3::splat(1.0)));
    let ball = Convex::ball(DVec3::new(5.0, 0.0, 0.0), 1.0);
    let s = field(vec![b, ball]);
    assert!(at(&s, DVec3::new(3.0, 0.0, 0.0)) < 0.0, "between them");
    assert!(at(&s, DVec3::new(5.9, 0.0, 0.0)) < 0.0);
    assert!(at(&s, DVec3::new(6.1, 0.0, 0.0)) > 0.0);
    assert!((at(&s, DVec3::new(-3.0, 0.0, 0.0)) - 2.0).abs() < 1e-8);
}

#[test]
fn a_sampled_field_is_hulled_within_a_cell() {
    // A classic sphere (not a known body) of radius 2 at the origin, and a known ball.
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let classic = x.square() + y.square() + z.square() - 4.0;
    let (s, _) = hull(vec![
        HullPart::Field(classic),
        HullPart::Convex(Convex::ball(DVec3::new(10.0, 0.0, 0.0), 2.0)),
    ])
    .expect("builds");
    let cell = 4.0 / (SAMPLES - 2) as f64;
    // The capsule's side is 2 from the axis.
    for p in [
        DVec3::new(5.0, 3.0, 0.0),
        DVec3::new(-3.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.5),
    ] {
        let want = if p.x < 0.0 {
            p.length() - 2.0
        } else {
            (p.y * p.y + p.z * p.z).sqrt() - 2.0
        };
        let got = at(&s, p);
        assert!((got - want).abs() <= cell, "{p}: {got} vs {want}");
    }
    // An unbounded part is an error that names it.
    let err = hull(vec![HullPart::Field(Shape::z())])
        .map(|_| ())
        .unwrap_err();
    assert!(
        matches!(err, HullError::Unbounded { index: 1, .. }),
        "{err:?}"
    );
}

#[test]
fn a_sampled_hull_is_the_exact_distance_to_its_points_hull() {
    // A torus is no known body: its hull is a polytope of about 1,300 facets, read group
    // by group (planes.rs). Every value must be what all facets give, read one by one.
    let (x, y, z) = (Shape::x() - 1.0, Shape::y() + 2.0, Shape::z() - 0.5);
    let ring = (x.square() + y.square()).sqrt() - 3.0;
    let torus = (ring.square() + z.square()).sqrt() - 1.0;
    let body = sampled_part(&torus, 1).expect("sampled");
    let (s, _) = hull(vec![HullPart::Convex(body.clone())]).expect("builds");
    let points = body.polytope_points().expect("a polytope");
    let tris = polytope::hull_triangles(&points).expect("spans a volume");
    assert!(tris.len() > 500, "{} facets", tris.len());
    let brute = |p: DVec3| {
        let plane = tris
            .iter()
            .map(|(f, _)| f.normal.dot(p) - f.offset)
            .fold(f64::NEG_INFINITY, f64::max);
        if plane <= 0.0 {
            return plane;
        }
        tris.iter()
            .map(|(_, [a, b, c])| (p - gjk::closest_on_triangle(p, *a, *b, *c)).length())
            .fold(f64::INFINITY, f64::min)
    };
    let mut checked = 0;
    for i in 0..=16 {
        for j in 0..=16 {
            for k in 0..=8 {
                let p = DVec3::new(
                    -5.0 + 0.7 * i as f64,
                    -7.9 + 0.7 * j as f64,
                    -2.3 + 0.6 * k as f64,
                );
                let (got, want) = (at(&s, p), brute(p));
                assert!((got - want).abs() < 1e-9, "{p}: {got} against {want}");
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 17 * 17 * 9);
}

fn boxed(lo: [f64; 3], size: f64) -> [Interval; 3] {
    [0, 1, 2].map(|i| Interval::try_from((lo[i], lo[i] + size)).expect("box"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Enclosures hold every point value of their box.
    #[test]
    fn hull_enclosures_hold_point_values(
        lo in [-8.0..8.0f64, -8.0..8.0f64, -8.0..8.0f64],
        size in 0.01..6.0f64,
        f in proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64], 8),
    ) {
        let curved = field(vec![
            Convex::new(Body::Cylinder { r: 1.0, half: 2.0 }),
            Convex::ball(DVec3::new(4.0, 1.0, 0.0), 1.5),
            Convex::new(Body::Box(DVec3::new(0.5, 0.5, 0.5))).moved(DVec3::new(0.0, -3.0, 1.0)),
        ]);
        // Equal balls: a polytope core grown by 1.5 (the exact mode).
        let balls = field(
            [[0.0, 0.0, 0.0], [5.0, 1.0, 0.0], [1.0, 4.0, 2.0], [2.0, 1.0, -3.0]]
                .iter()
                .map(|c| Convex::ball(DVec3::from(*c), 1.5))
                .collect(),
        );
        // Two boxes: a polytope core grown by nothing.
        let boxes = field(vec![
            Convex::new(Body::Box(DVec3::new(1.0, 2.0, 0.5))),
            Convex::new(Body::Box(DVec3::splat(0.5))).moved(DVec3::new(4.0, 3.0, 1.0)),
        ]);
        for s in [curved, balls, boxes] {
            let tape = Tape::new(&s);
            let i = IntervalEval::new().eval(&tape, boxed(lo, size));
            let mut pe = PointEval::new();
            for q in &f {
                let p = [0, 1, 2].map(|k| lo[k] + q[k] * size);
                let v = pe.eval(&tape, p);
                prop_assert!(i.inf() <= v && v <= i.sup(), "{} at {:?} outside {:?}", v, p, i);
            }
        }
    }
}
