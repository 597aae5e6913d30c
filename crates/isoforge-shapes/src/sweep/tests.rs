//! Sweeps checked point by point against the geometry they should make. (Volumes, which
//! need the mesher, are in `tests/sweep_volumes.rs`.)

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::*;
use crate::profile::{circle, polygon, rect};
use crate::reference::at;

fn inside(s: &Shape, p: [f64; 3]) -> bool {
    at(s, p) < 0.0
}

#[test]
fn a_twisted_square_is_a_turned_square_at_each_height() {
    let sq = rect([2.0, 2.0], 0.0).unwrap();
    let opts = LinearSweep {
        twist: 90.0,
        ..LinearSweep::new(10.0)
    };
    let s = linear_sweep(&sq, &opts).unwrap();
    // At half height the square is turned 45 degrees clockwise: its corner is on the axes.
    let corner = 2f64.sqrt();
    assert!(inside(&s, [corner - 0.01, 0.0, 5.0]));
    assert!(!inside(&s, [0.9, 0.9, 5.0]), "the unturned corner is gone");
    // At the top, turned 90 degrees: a square again, on the same footprint.
    assert!(inside(&s, [0.99, 0.99, 9.99]));
    // Clockwise: a point just past the bottom's (1, 0.5) edge point, turned clockwise a
    // little with height, is inside; turned counter-clockwise, outside.
    let a = -(10.0f64).to_radians();
    let p = DVec3::new(1.0, 0.5, 0.0);
    let cw = DVec3::new(
        p.x * a.cos() - p.y * a.sin(),
        p.x * a.sin() + p.y * a.cos(),
        10.0 / 9.0,
    );
    assert!(at(&s, [cw.x * 0.99, cw.y * 0.99, cw.z]) < 0.0);
    assert!(!inside(&s, [0.0, 0.0, -0.1]));
    assert!(!inside(&s, [0.0, 0.0, 10.1]));
    // The field is the profile's distance where there is no twist.
    let plain = linear_sweep(&sq, &LinearSweep::new(10.0)).unwrap();
    assert!((at(&plain, [2.0, 0.0, 5.0]) - 1.0).abs() < 1e-12);
}

#[test]
fn scale_shift_and_centre() {
    let c = circle(2.0).unwrap();
    let opts = LinearSweep {
        scale: [0.5, 0.5],
        shift: [3.0, 0.0],
        center: true,
        ..LinearSweep::new(4.0)
    };
    let s = linear_sweep(&c, &opts).unwrap();
    // Bottom at z = -2: radius 2 about the origin. Top at z = 2: radius 1 about (3, 0).
    assert!(inside(&s, [1.9, 0.0, -1.99]));
    assert!(!inside(&s, [1.9, 0.0, 1.99]));
    assert!(inside(&s, [3.9, 0.0, 1.99]));
    assert!(!inside(&s, [3.0, 1.1, 1.99]));
    // Halfway: radius 1.5 about (1.5, 0).
    assert!((at(&s, [3.0, 0.0, 0.0])).abs() < 1e-9);
    assert!(
        LinearSweep {
            scale: [-1.0, 1.0],
            ..LinearSweep::new(1.0)
        }
        .check()
        .is_err()
    );
}

#[test]
fn revolve_makes_rings_and_wedges() {
    let r = rect([2.0, 4.0], 0.0)
        .unwrap()
        .translate([4.0, 0.0])
        .unwrap();
    let ring = revolve(&r, 360.0).unwrap();
    for a in [0.0, 1.0, 2.5, 4.0] {
        assert!(inside(&ring, [4.0 * f64::cos(a), 4.0 * f64::sin(a), 1.9]));
    }
    assert!(!inside(&ring, [0.0, 0.0, 0.0]));
    assert!(!inside(&ring, [5.1, 0.0, 0.0]));
    let quarter = revolve(&r, 90.0).unwrap();
    assert!(inside(&quarter, [0.1, 4.0, 0.0]));
    assert!(inside(&quarter, [4.0, 0.1, 0.0]));
    assert!(!inside(&quarter, [-4.0, 0.1, 0.0]));
    assert!(!inside(&quarter, [4.0, -0.1, 0.0]));
    let most = revolve(&r, 270.0).unwrap();
    assert!(inside(&most, [-4.0, -0.1, 0.0]));
    assert!(!inside(&most, [0.1, -4.0, 0.0]));
    let crossing = rect([2.0, 2.0], 0.0).unwrap();
    assert!(matches!(
        revolve(&crossing, 360.0),
        Err(SweepError::CrossesAxis { .. })
    ));
    assert!(revolve(&r, 0.0).is_err() && revolve(&r, 400.0).is_err());
}

#[test]
fn a_spiral_follows_its_helix() {
    let prof = rect([1.0, 0.5], 0.0).unwrap();
    let opts = SpiralSweep {
        height: 6.0,
        radius: 5.0,
        turns: 3.0,
        taper: 0.0,
        internal: false,
    };
    let s = spiral_sweep(&prof, &opts).unwrap();
    // The profile's origin is at radius 5, angle θ, height −3 + θ/(2π) (pitch 2).
    for i in 0..40 {
        let theta = 0.05 + i as f64 * (3.0 * TAU - 0.1) / 39.0;
        let z = -3.0 + theta / TAU * 2.0;
        let p = [5.0 * theta.cos(), 5.0 * theta.sin(), z];
        assert!(
            at(&s, p) < -0.2,
            "on the helix at θ = {theta}: {}",
            at(&s, p)
        );
        // A pitch above and below, between turns, is outside... half a pitch is.
        assert!(!inside(&s, [p[0], p[1], z + 1.0]));
    }
    // Right-handed: counter-clockwise as it rises.
    let theta: f64 = 1.0;
    let z_ccw = -3.0 + theta / TAU * 2.0;
    assert!(inside(&s, [5.0 * theta.cos(), 5.0 * theta.sin(), z_ccw]));
    assert!(!inside(
        &s,
        [5.0 * theta.cos(), -(5.0 * theta.sin()), z_ccw]
    ));
    // The ends are cut at angles 0 and 3 turns.
    assert!(!inside(
        &s,
        [5.0 * (-0.05f64).cos(), 5.0 * (-0.05f64).sin(), -3.0]
    ));
}

#[test]
fn a_tapered_thread_shrinks_at_its_ends() {
    let prof = rect([1.0, 0.5], 0.0)
        .unwrap()
        .translate([0.5, 0.0])
        .unwrap();
    let opts = SpiralSweep {
        height: 4.0,
        radius: 5.0,
        turns: 2.0,
        taper: -5.0,
        internal: false,
    };
    let s = spiral_sweep(&prof, &opts).unwrap();
    // Mid-thread the full depth (x up to 1) is there; a hair after the start only the
    // root is.
    let at_angle = |theta: f64, x: f64| {
        let z = -2.0 + theta / TAU * 2.0;
        [(5.0 + x) * theta.cos(), (5.0 + x) * theta.sin(), z]
    };
    assert!(inside(&s, at_angle(2.0 * PI, 0.9)));
    assert!(!inside(&s, at_angle(0.02, 0.9)));
    assert!(inside(&s, at_angle(0.02, 0.02)));
}

#[test]
fn skin_of_two_equal_circles_is_a_cylinder() {
    let c = circle(3.0).unwrap();
    let s = skin(&[c.clone(), c], &[0.0, 5.0], &SkinOptions::default()).unwrap();
    // The nearest faces: the caps from the centre, the side from near the wall.
    assert!((at(&s, [0.0, 0.0, 2.5]) + 2.5).abs() < 1e-9);
    assert!((at(&s, [2.0, 0.0, 2.5]) + 1.0).abs() < 1e-3);
    assert!((at(&s, [4.0, 0.0, 1.0]) - 1.0).abs() < 1e-3);
    assert!(!inside(&s, [0.0, 0.0, 5.1]));
}

#[test]
fn skin_square_to_circle_by_every_method() {
    let sq = rect([4.0, 4.0], 0.0).unwrap();
    let c = circle(1.0).unwrap();
    for method in [
        SkinMethod::Direct,
        SkinMethod::Reindex,
        SkinMethod::Distance,
        SkinMethod::FastDistance,
        SkinMethod::Tangent,
    ] {
        let opts = SkinOptions {
            method,
            ..SkinOptions::default()
        };
        let s = skin(&[sq.clone(), c.clone()], &[0.0, 4.0], &opts).unwrap();
        assert!(
            inside(&s, [1.9, 1.9, 0.01]),
            "{method:?}: the square's corner"
        );
        assert!(inside(&s, [0.0, 0.95, 3.99]), "{method:?}: the circle");
        assert!(!inside(&s, [0.9, 0.9, 3.99]), "{method:?}");
        assert!(inside(&s, [0.0, 0.0, 2.0]));
    }
    let three = polygon(&[vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]]).unwrap();
    assert!(skin(&[three], &[0.0], &SkinOptions::default()).is_err());
}

#[test]
fn path_sweep_along_a_circle_is_a_torus() {
    let c = circle(1.0).unwrap();
    let path: Vec<DVec3> = (0..256)
        .map(|i| {
            let a = i as f64 * TAU / 256.0;
            DVec3::new(5.0 * a.cos(), 5.0 * a.sin(), 0.0)
        })
        .collect();
    let opts = PathSweep {
        closed: true,
        ..PathSweep::default()
    };
    let s = path_sweep(&c, &path, &opts).unwrap();
    for i in 0..50 {
        let a = i as f64 * 0.37;
        let d = at(&s, [5.0 * a.cos(), 5.0 * a.sin(), 0.0]);
        assert!((d + 1.0).abs() < 1e-3, "tube centre {d}");
        let d = at(&s, [6.5 * a.cos(), 6.5 * a.sin(), 0.0]);
        assert!((d - 0.5).abs() < 1e-3, "outside the tube {d}");
    }
    assert!(!inside(&s, [0.0, 0.0, 0.0]));
}

#[test]
fn an_open_path_is_capped_flat() {
    let sq = rect([2.0, 2.0], 0.0).unwrap();
    let path = [DVec3::ZERO, DVec3::new(0.0, 0.0, 10.0)];
    let s = path_sweep(&sq, &path, &PathSweep::default()).unwrap();
    assert!(inside(&s, [0.9, 0.9, 0.1]));
    assert!(inside(&s, [0.9, 0.9, 9.9]));
    assert!(!inside(&s, [0.0, 0.0, -0.1]));
    assert!(!inside(&s, [0.0, 0.0, 10.1]));
    assert!(
        (at(&s, [0.0, 0.0, -0.5]) - 0.5).abs() < 1e-9,
        "the cap is a distance"
    );
    assert!(at(&s, [0.0, 0.0, -50.0]) > 0.0);
}

#[test]
fn a_closure_path_is_sampled_finely() {
    let pts = path::sample_curve(&|s| [(TAU * s).cos(), (TAU * s).sin(), 0.0], true).unwrap();
    assert!(pts.len() >= 64);
    assert!(
        pts[0].distance(*pts.last().unwrap()) > 1e-6,
        "the repeated end is dropped"
    );
    let bad = path::sample_curve(&|s| [1.0 / (s - 0.5), 0.0, 0.0], false);
    assert!(bad.is_err());
}
