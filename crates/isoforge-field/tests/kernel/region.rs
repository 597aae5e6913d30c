//! The region: the clipped field's laws (proptest) and the region search.

use isoforge_field::{
    BatchEval, Bounds, ClippedField, GradEval, IntervalEval, PointEval, RegionError,
    SEARCH_HALF_SIDE, Shape, Tape, ensure_not_empty, find_bounds, region_is_empty,
};
use proptest::prelude::*;

use crate::common::*;

/// A random region: per axis a lower end and a positive length.
fn any_region() -> impl Strategy<Value = Bounds> {
    let axis = (-3.0..3.0f64, 0.01..4.0f64);
    [axis.clone(), axis.clone(), axis].prop_map(|a| {
        Bounds::new(a.map(|(lo, _)| lo), a.map(|(lo, len)| lo + len)).expect("lo < lo + len")
    })
}

fn fractions() -> impl Strategy<Value = Vec<[f64; 3]>> {
    proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64], 8)
}

fn strictly_in(b: &Bounds, p: [f64; 3]) -> bool {
    (0..3).all(|i| b.min[i] < p[i] && p[i] < b.max[i])
}

proptest! {
    #![proptest_config(crate::common::cases(384))]

    /// Outside the box (and on its faces) the clipped field is positive, whatever the
    /// model; inside, it is negative exactly where the model is.
    #[test]
    fn outside_the_box_is_outside(
        s in any_shape(), r in any_region(), b in any_box(), f in fractions()
    ) {
        let field = ClippedField::new(&s, r);
        let tape = Tape::new(&s);
        let mut ev = PointEval::new();
        for p in samples(&b, &f) {
            let v = field.point(&mut ev, p);
            prop_assert!(!v.is_nan(), "F is never NaN");
            if !strictly_in(&r, p) {
                prop_assert!(v >= 0.0, "{:?} at {:?} out of {:?}: {}", s, p, r, v);
            } else {
                let raw = ev.eval(&tape, p);
                prop_assert_eq!(field.is_inside(&mut ev, p), raw < 0.0, "{:?} at {:?}", s, p);
            }
        }
    }

    /// The clipped interval over a box encloses every clipped point value in it; batch
    /// and gradient values equal point values bit for bit.
    #[test]
    fn clipped_interval_encloses_clipped_points(
        s in any_shape(), r in any_region(), b in any_box(), f in fractions()
    ) {
        let field = ClippedField::new(&s, r);
        let mut ie = IntervalEval::new();
        let mut pe = PointEval::new();
        let mut ge = GradEval::new();
        let i = field.interval(&mut ie, intervals(&b));
        let pts = samples(&b, &f);
        let xyz: [Vec<f64>; 3] = [0, 1, 2].map(|k| pts.iter().map(|p| p[k]).collect());
        let mut batch = vec![0.0; pts.len()];
        field.batch(&mut BatchEval::new(), &xyz[0], &xyz[1], &xyz[2], &mut batch);
        let narrow = field.narrow(&ie);
        for (k, p) in pts.iter().enumerate() {
            let v = field.point(&mut pe, *p);
            prop_assert!(encloses(i, v), "{:?} in {:?} over {:?}: {:?} misses {}", s, r, b, i, v);
            prop_assert!(same(batch[k], v), "batch {} vs point {}", batch[k], v);
            prop_assert!(same(field.grad(&mut ge, *p).v, v), "grad value vs point");
            // The narrowed field agrees in the box (where the model is defined).
            let w = narrow.point(&mut pe, *p);
            prop_assert!(same(v, w) || v == f64::INFINITY, "narrow {} vs {}", w, v);
        }
    }
}

/// NaN counts as outside, even where the box's distance would win a float `max`.
#[test]
fn nan_is_outside() {
    let r = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
    // sqrt(x) is NaN for x < 0.
    let field = ClippedField::new(&(Shape::x().sqrt() - 0.5), r);
    let mut pe = PointEval::new();
    assert_eq!(field.point(&mut pe, [-0.5, 0.0, 0.0]), f64::INFINITY);
    assert_eq!(field.point(&mut pe, [-5.0, 0.0, 0.0]), f64::INFINITY);
    assert!(field.is_inside(&mut pe, [0.1, 0.0, 0.0]));
    let g = field.grad(&mut GradEval::new(), [-0.5, 0.0, 0.0]);
    assert_eq!(g.v, f64::INFINITY);
    assert!(
        g.d.iter().all(|d| d.is_nan()),
        "no direction is known at NaN"
    );
    // Over a box where the model may be NaN, no point is proven inside.
    let mut ie = IntervalEval::new();
    let half = intervals(&[(-1.0, 0.5), (-0.5, 0.5), (-0.5, 0.5)]);
    assert_eq!(field.interval(&mut ie, half).sup(), f64::INFINITY);
}

/// Where the box's face is nearer than the model's surface, value and gradient are the
/// box's.
#[test]
fn the_box_caps_a_model_it_cuts() {
    let r = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
    let ball = Shape::x().square() + Shape::y().square() + Shape::z().square() - 4.0;
    let field = ClippedField::new(&ball, r);
    let g = field.grad(&mut GradEval::new(), [0.9, 0.0, 0.0]);
    assert!((g.v - -0.1).abs() < 1e-12, "{g:?}");
    assert_eq!(g.d, [1.0, 0.0, 0.0]);
    let g = field.grad(&mut GradEval::new(), [0.0, 0.0, -0.95]);
    assert_eq!(g.d, [0.0, 0.0, -1.0]);
    // A box wholly inside the ball and the region is proven full.
    let mut ie = IntervalEval::new();
    let inner = intervals(&[(-0.5, 0.5); 3]);
    assert!(field.interval(&mut ie, inner).sup() < 0.0);
    // One wholly outside the region is proven empty, though the ball fills it.
    let beyond = intervals(&[(1.0, 1.5), (-0.5, 0.5), (-0.5, 0.5)]);
    assert!(field.interval(&mut ie, beyond).inf() >= 0.0);
}

fn sphere(c: [f64; 3], r: f64) -> Shape {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    (x - c[0]).square() + (y - c[1]).square() + (z - c[2]).square() - r * r
}

proptest! {
    #![proptest_config(crate::common::cases(64))]

    /// Found bounds enclose a sphere, tightly.
    #[test]
    fn found_bounds_enclose_a_sphere(
        c in prop::array::uniform3(-50.0f64..50.0),
        r in 0.05f64..20.0,
    ) {
        let b = find_bounds(&sphere(c, r)).unwrap();
        for (i, ci) in c.iter().enumerate() {
            prop_assert!(b.min[i] <= ci - r && b.max[i] >= ci + r, "{b:?}");
            // Tight: padding is a few percent, plus what the cells add.
            prop_assert!(b.min[i] >= ci - 1.2 * r && b.max[i] <= ci + 1.2 * r, "{b:?}");
        }
    }
}

#[test]
fn an_empty_model_has_no_region() {
    // Positive everywhere.
    let empty = Shape::x().square() + Shape::y().square() + Shape::z().square() + 1.0;
    assert_eq!(
        find_bounds(&empty),
        Err(RegionError::Empty {
            half_side: SEARCH_HALF_SIDE
        })
    );
}

#[test]
fn an_unbounded_model_is_refused() {
    // Everything below z = 1.
    let half_space = Shape::z() - 1.0;
    assert_eq!(
        find_bounds(&half_space),
        Err(RegionError::Unbounded {
            half_side: SEARCH_HALF_SIDE
        })
    );
}

#[test]
fn an_empty_region_is_refused() {
    let far = sphere([10.0, 0.0, 0.0], 1.0);
    let region = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
    assert!(region_is_empty(&far, &region));
    assert_eq!(
        ensure_not_empty(&far, &region),
        Err(RegionError::EmptyRegion { region })
    );
    let near = sphere([0.9, 0.0, 0.0], 0.5);
    assert!(!region_is_empty(&near, &region));
    assert_eq!(ensure_not_empty(&near, &region), Ok(()));
}
