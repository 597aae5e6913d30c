//! Tubes against distances worked out by hand, and their enclosures.

use std::f64::consts::TAU;

use isoforge_field::{IntervalEval, PointEval};
use proptest::prelude::*;

use super::*;

fn s() -> Shape {
    Shape::x()
}

fn circle(radius: f64) -> [Shape; 3] {
    [s().cos() * radius, s().sin() * radius, Shape::constant(0.0)]
}

fn at(f: &Shape, p: [f64; 3]) -> f64 {
    PointEval::new().eval(&Tape::new(f), p)
}

#[test]
fn a_circle_with_a_constant_radius_is_a_torus() {
    let (tube, exact) = curve_tube(circle(10.0), &Shape::constant(2.0), 0.0, TAU).unwrap();
    assert!(exact);
    for p in [
        [13.0f64, 0.0, 0.0],
        [0.0, -7.0, 1.0],
        [5.0, 5.0, 3.0],
        [9.0, 1.0, -0.5],
        [0.5, 0.0, 0.0],
    ] {
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
        let want = ((rho - 10.0).powi(2) + p[2] * p[2]).sqrt() - 2.0;
        // Gauss-Newton creeps near the circle's centre (where every point is nearly
        // nearest): there the tolerance is looser, far from the surface.
        let tolerance = if rho < 2.0 { 1e-6 } else { 1e-9 };
        let got = at(&tube, p);
        assert!((got - want).abs() < tolerance, "{p:?}: {got} vs {want}");
    }
}

#[test]
fn an_open_line_is_a_capped_cylinder() {
    let line = [s(), Shape::constant(0.0), Shape::constant(0.0)];
    let (tube, _) = curve_tube(line, &Shape::constant(1.0), 0.0, 10.0).unwrap();
    for (p, want) in [
        ([5.0, 3.0, 0.0], 2.0),
        ([5.0, 0.5, 0.0], -0.5),
        ([-2.0, 0.0, 0.0], 2.0),
        ([12.0, 0.0, 0.5], 2.0),
        ([-3.0, 4.0, 0.0], 18f64.sqrt()),
        ([0.2, 0.0, 0.0], -0.2),
    ] {
        let got = at(&tube, p);
        assert!((got - want).abs() < 1e-9, "{p:?}: {got} vs {want}");
    }
}

/// The trefoil knot: a closed curve that is never planar, with torsion.
fn trefoil() -> [Shape; 3] {
    [
        s().sin() + (s() * 2.0).sin() * 2.0,
        s().cos() - (s() * 2.0).cos() * 2.0,
        -(s() * 3.0).sin(),
    ]
}

#[test]
fn theta_joins_up_round_a_closed_curve() {
    // A radius that depends on θ: a flattened tube. Round a closed curve its frame must
    // meet itself, so the field is continuous across the parameter's seam.
    let radius = Shape::constant(0.4) + Shape::y().cos() * 0.15;
    let tube = TubeField::new(trefoil(), &radius, 0.0, TAU).unwrap();
    assert!(tube.is_closed());
    let mut pe = PointEval::new();
    let mut c = |s: f64| tube.curve.point(&mut pe, s);
    // Points a fixed offset from the curve on either side of the seam.
    let (_, d1) = tube.curve.with_derivative(1e-4);
    let (t, r, _) = tube.frame(d1, 0, 1e-4);
    for k in 0..8 {
        let a = k as f64 * TAU / 8.0;
        let off = (r * a.cos() + t.cross(r) * a.sin()) * 0.3;
        let before = tube.value(((c(TAU - 1e-4)) + off).to_array());
        let after = tube.value(((c(1e-4)) + off).to_array());
        assert!(
            (before - after).abs() < 1e-3,
            "angle {a}: {before} vs {after}"
        );
    }
}

fn boxed(lo: [f64; 3], size: f64) -> [Interval; 3] {
    [0, 1, 2].map(|i| Interval::try_from((lo[i], lo[i] + size)).expect("box"))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    /// Enclosures hold every point value, for an open helix with a radius varying in s
    /// and θ and for the closed knot.
    #[test]
    fn tube_enclosures_hold_point_values(
        lo in [-4.0..4.0f64, -4.0..4.0f64, -2.0..2.0f64],
        size in 0.01..3.0f64,
        f in proptest::collection::vec([0.0..=1.0f64, 0.0..=1.0f64, 0.0..=1.0f64], 6),
    ) {
        let helix = [s().cos() * 2.0, s().sin() * 2.0, s() * 0.3];
        let wobble = Shape::constant(0.5) + (s() * 3.0).sin() * 0.2 + Shape::y().sin() * 0.1;
        let (open, _) = curve_tube(helix, &wobble, -3.0, 6.0).unwrap();
        let (knot, _) = curve_tube(trefoil(), &(Shape::constant(0.5) + (s() * 3.0).cos() * 0.2), 0.0, TAU).unwrap();
        for shape in [open, knot] {
            let tape = Tape::new(&shape);
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
