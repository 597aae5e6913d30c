//! The transcendental enclosures at their hard spots.

use std::f64::consts::{FRAC_PI_2, PI};

use isoforge_field::Interval;
use isoforge_field::eval::enclose;

use crate::common::encloses;

fn iv(a: f64, b: f64) -> Interval {
    Interval::try_from((a, b)).unwrap()
}

/// Checks `f(iv)` encloses `g` at many points of `[a, b]` (endpoints included).
fn check(f: fn(Interval) -> (Interval, bool), g: fn(f64) -> f64, a: f64, b: f64) {
    let (e, nan) = f(iv(a, b));
    for k in 0..=1000 {
        let x = if k == 1000 {
            b
        } else {
            a + (b - a) * k as f64 / 1000.0
        };
        let v = g(x);
        if v.is_nan() {
            assert!(nan, "NaN at {x} not flagged for [{a}, {b}]");
        } else {
            assert!(encloses(e, v), "[{a}, {b}] -> {e:?} misses {v} at {x}");
        }
    }
}

#[test]
fn sin_cos_around_quarter_turns() {
    for k in -40..40 {
        let c = k as f64 * FRAC_PI_2;
        for w in [0.0, 1e-300, 1e-15, 1e-12, 1e-6, 0.1, 1.0, 3.0] {
            for (a, b) in [(c - w, c + w), (c, c + w), (c - w, c)] {
                check(enclose::sin, f64::sin, a, b);
                check(enclose::cos, f64::cos, a, b);
            }
        }
    }
    // Extremum included: the bound reaches exactly 1.
    assert_eq!(enclose::sin(iv(1.5, 1.6)).0.sup(), 1.0);
    assert_eq!(enclose::cos(iv(-0.1, 0.1)).0.sup(), 1.0);
    assert_eq!(enclose::cos(iv(3.0, 3.2)).0.inf(), -1.0);
    // Tight away from extrema.
    let (s, _) = enclose::sin(iv(0.1, 0.2));
    assert!(s.sup() < 0.2 && s.inf() > 0.09);
    // A wide or infinite argument.
    assert_eq!(enclose::sin(iv(0.0, 100.0)).0, iv(-1.0, 1.0));
    assert!(enclose::sin(iv(0.0, f64::INFINITY)).1, "sin(inf) is NaN");
    check(enclose::sin, f64::sin, 1e14, 1e14 + 1.0);
}

#[test]
fn tan_near_poles() {
    for k in -20..20 {
        let p = (2 * k + 1) as f64 * FRAC_PI_2;
        // Across the pole: everything.
        let (t, nan) = enclose::tan(iv(p - 1e-9, p + 1e-9));
        assert_eq!(t, Interval::ENTIRE);
        assert!(!nan);
        // Right up to it on either side.
        check(
            enclose::tan,
            f64::tan,
            p - 0.5,
            p.next_down().next_down().next_down(),
        );
        check(enclose::tan, f64::tan, p + 1e-6, p + 0.5);
    }
    check(enclose::tan, f64::tan, -1.0, 1.0);
    assert!(enclose::tan(iv(-1.0, 1.0)).0.sup() < 1.6);
}

#[test]
fn exp_overflow_and_ln_at_zero() {
    check(enclose::exp, f64::exp, 700.0, 720.0);
    assert_eq!(enclose::exp(iv(700.0, 720.0)).0.sup(), f64::INFINITY);
    check(enclose::exp, f64::exp, -800.0, -700.0);
    assert!(enclose::exp(iv(-800.0, -700.0)).0.inf() >= 0.0);
    check(enclose::exp, f64::exp, -1.0, 1.0);
    // ln: reaching 0 or below is flagged.
    assert!(enclose::ln(iv(0.0, 1.0)).1);
    assert!(enclose::ln(iv(-1.0, 1.0)).1);
    assert!(!enclose::ln(iv(1e-300, 1.0)).1);
    check(enclose::ln, f64::ln, 1e-300, 1e300);
    check(enclose::ln, f64::ln, 0.999, 1.001);
}

#[test]
fn inverse_trig_domains() {
    check(enclose::asin, f64::asin, -1.0, 1.0);
    check(enclose::acos, f64::acos, -1.0, 1.0);
    check(enclose::atan, f64::atan, -1e300, 1e300);
    assert!(enclose::asin(iv(0.5, 1.0 + 1e-15)).1);
    assert!(enclose::acos(iv(-1.5, 0.0)).1);
    assert!(enclose::asin(iv(-1.0, 1.0)).0.sup() <= FRAC_PI_2.next_up());
    assert!(enclose::acos(iv(-1.0, 1.0)).0.sup() <= PI.next_up());
}

#[test]
fn pow_with_negative_base_is_a_domain_error() {
    assert!(enclose::pow(iv(-1.0, 2.0), iv(0.5, 0.5)).1);
    // Non-negative bases: corners and the x = 1 / y = 0 lines.
    for (a, b) in [
        ((0.0, 2.0), (-1.0, 3.0)),
        ((0.5, 1.5), (-2.0, -1.0)),
        ((2.0, 3.0), (0.5, 2.5)),
    ] {
        let (e, nan) = enclose::pow(iv(a.0, a.1), iv(b.0, b.1));
        assert!(!nan);
        for i in 0..=20 {
            for j in 0..=20 {
                let x = a.0 + (a.1 - a.0) * i as f64 / 20.0;
                let y = b.0 + (b.1 - b.0) * j as f64 / 20.0;
                assert!(encloses(e, x.powf(y)), "{x}^{y} not in {e:?}");
                // -0 as base gives -inf for negative odd exponents.
                if x == 0.0 {
                    assert!(encloses(e, (-0.0f64).powf(y)));
                }
            }
        }
    }
    // powi: odd negative across 0 is everything; even stays non-negative.
    assert_eq!(enclose::powi(iv(-1.0, 1.0), -3).0, Interval::ENTIRE);
    assert!(enclose::powi(iv(-1.0, 2.0), 4).0.inf() >= 0.0);
    for n in [-5, -4, -1, 2, 3, 7, 8, 31] {
        for (a, b) in [
            (-2.0, -0.5),
            (-1.5, 2.0),
            (0.3, 1.7),
            (1e-100, 1e-90),
            (1e100, 1e102),
        ] {
            let (e, _) = enclose::powi(iv(a, b), n);
            for k in 0..=200 {
                let x = a + (b - a) * k as f64 / 200.0;
                assert!(encloses(e, x.powi(n)), "{x}^{n} not in {e:?}");
            }
        }
    }
}

#[test]
fn atan2_across_the_branch_cut() {
    // The box straddles the negative x axis: angles near +pi and -pi.
    let (e, _) = enclose::atan2(iv(-0.1, 0.1), iv(-2.0, -1.0));
    assert!(e.inf() <= -PI && e.sup() >= PI);
    assert!(encloses(e, (-0.0f64).atan2(-1.0)));
    assert!(encloses(e, (0.0f64).atan2(-1.0)));
    // y = 0 exactly with x < 0: a zero of either sign is possible.
    let (e, _) = enclose::atan2(iv(0.0, 1.0), iv(-2.0, -1.0));
    assert!(encloses(e, (-0.0f64).atan2(-1.5)));
    // Around the origin: everything.
    let (e, _) = enclose::atan2(iv(-1.0, 1.0), iv(-1.0, 1.0));
    assert!(e.inf() <= -PI && e.sup() >= PI);
    // Away from the cut: tight and enclosing.
    for (y, x) in [
        ((0.5, 1.0), (-1.0, 1.0)),
        ((-1.0, 1.0), (0.5, 2.0)),
        ((-2.0, -1.0), (-3.0, 3.0)),
    ] {
        let (e, nan) = enclose::atan2(iv(y.0, y.1), iv(x.0, x.1));
        assert!(!nan);
        assert!(e.wid() < 2.0 * PI);
        for i in 0..=30 {
            for j in 0..=30 {
                let yy = y.0 + (y.1 - y.0) * i as f64 / 30.0;
                let xx = x.0 + (x.1 - x.0) * j as f64 / 30.0;
                assert!(encloses(e, yy.atan2(xx)));
            }
        }
    }
}

#[test]
fn modulo_by_a_possible_zero_is_flagged() {
    assert!(enclose::modulo(iv(1.0, 2.0), iv(-1.0, 1.0)).1);
    let (e, nan) = enclose::modulo(iv(-5.0, 7.0), iv(1.5, 2.0));
    assert!(!nan);
    for i in 0..=100 {
        for j in 0..=10 {
            let a = -5.0 + 12.0 * i as f64 / 100.0;
            let b = 1.5 + 0.5 * j as f64 / 10.0;
            assert!(encloses(e, a - b * (a / b).floor()));
        }
    }
}
