//! Surfaces against their defining formulas, and their thickened fields.

use std::f64::consts::{PI, TAU};

use glam::DVec3;
use isoforge_field::CustomField;

use super::*;
use crate::reference::at;

/// A 4×4 net like the lecture's (its first row is the lecture's; see
/// `fixtures/sweeps/lecture_bezier.rhai`).
fn lecture_net() -> Vec<Vec<[f64; 3]>> {
    vec![
        vec![
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
            [0.0, 2.0, 1.0],
            [0.0, 3.0, 1.0],
        ],
        vec![
            [1.0, 0.0, 1.0],
            [1.0, 1.0, 2.0],
            [1.0, 2.0, 2.0],
            [1.0, 3.0, 1.0],
        ],
        vec![
            [2.0, 0.0, 1.0],
            [2.0, 1.0, 2.0],
            [2.0, 2.0, 3.0],
            [2.0, 3.0, 2.0],
        ],
        vec![
            [3.0, 0.0, 0.0],
            [3.0, 1.0, 1.0],
            [3.0, 2.0, 1.0],
            [3.0, 3.0, 2.0],
        ],
    ]
}

fn bernstein(n: usize, i: usize, u: f64) -> f64 {
    let binom = (0..i).fold(1.0, |acc, k| acc * (n - k) as f64 / (k + 1) as f64);
    binom * u.powi(i as i32) * (1.0 - u).powi((n - i) as i32)
}

#[test]
fn bezier_surface_is_the_bernstein_sum() {
    let net = lecture_net();
    let s = bezier(&net).unwrap();
    for k in 0..50 {
        let (u, v) = ((k as f64 * 0.137) % 1.0, (k as f64 * 0.611) % 1.0);
        let mut q = DVec3::ZERO;
        for (i, row) in net.iter().enumerate() {
            for (j, p) in row.iter().enumerate() {
                q += DVec3::from(*p) * bernstein(3, i, u) * bernstein(3, j, v);
            }
        }
        assert!(s.point(u, v).distance(q) < 1e-12);
    }
    assert!(
        bezier(&[vec![[0.0; 3]; 2]]).is_err(),
        "one row is not a net"
    );
    assert!(bezier(&[vec![[0.0; 3]; 2], vec![[0.0; 3]; 3]]).is_err());
}

#[test]
fn bsplines_reach_their_corners_only_when_clamped() {
    // The lecture's 8×8 net, indices 1 to 8.
    let net: Vec<Vec<[f64; 3]>> = (1..=8)
        .map(|i| {
            (1..=8)
                .map(|j| {
                    let (i, j) = (i as f64, j as f64);
                    [
                        i,
                        j,
                        (10.0 - (i - 3.0).powi(2)) * (j - 2.0) * (j - 4.0) * (j - 6.0) / 200.0,
                    ]
                })
                .collect()
        })
        .collect();
    for d in 1..=3 {
        let clamped = bspline(&net, d, true).unwrap();
        let corner = DVec3::from(net[0][0]);
        assert!(
            clamped.point(0.0, 0.0).distance(corner) < 1e-12,
            "degree {d}"
        );
        assert!(clamped.point(1.0, 1.0).distance(DVec3::from(net[7][7])) < 1e-12);
        let free = bspline(&net, d, false).unwrap();
        if d > 1 {
            assert!(free.point(0.0, 0.0).distance(corner) > 0.1, "degree {d}");
        }
    }
    // Degree 1 is the bilinear interpolation of the net.
    let lin = bspline(&net, 1, false).unwrap();
    let mid = (DVec3::from(net[2][3]) + DVec3::from(net[3][3])) * 0.5;
    assert!(lin.point(2.5 / 7.0, 3.0 / 7.0).distance(mid) < 1e-12);
    // Uniform quadratic spans join smoothly: the derivative agrees across a join.
    let q = bspline(&net, 2, false).unwrap();
    let h = 1e-6;
    let join = 1.0 / 6.0;
    let left = (q.point(join, 0.4) - q.point(join - h, 0.4)) / h;
    let right = (q.point(join + h, 0.4) - q.point(join, 0.4)) / h;
    assert!(left.distance(right) < 1e-3 * left.length());
    assert!(bspline(&net, 4, false).is_err());
    assert!(bspline(&net[..2], 3, false).is_err());
}

#[test]
fn coons_patch_keeps_its_boundary_curves() {
    let c0 = |s: f64| [s, 0.0, 0.5 * (TAU * s).sin()];
    let c1 = |s: f64| [s, 1.0, 0.5 * (PI * s).sin()];
    let d0 = |t: f64| [0.0, t, 0.0];
    let d1 = |t: f64| [1.0, t, 0.0];
    let s = coons(&CoonsCurves {
        c0: &c0,
        c1: &c1,
        d0: &d0,
        d1: &d1,
    })
    .unwrap();
    for k in 0..=40 {
        let u = k as f64 / 40.0;
        assert!(s.point(u, 0.0).distance(DVec3::from(c0(u))) < 1e-5);
        assert!(s.point(u, 1.0).distance(DVec3::from(c1(u))) < 1e-5);
        assert!(s.point(0.0, u).distance(DVec3::from(d0(u))) < 1e-5);
        assert!(s.point(1.0, u).distance(DVec3::from(d1(u))) < 1e-5);
        // Inside, the blend: x = s, y = t, z = (1−t)·c0z + t·c1z.
        let t = (k as f64 * 0.37) % 1.0;
        let z = (1.0 - t) * 0.5 * (TAU * u).sin() + t * 0.5 * (PI * u).sin();
        assert!(s.point(u, t).distance(DVec3::new(u, t, z)) < 1e-5);
    }
}

#[test]
fn thickened_fields_measure_distance_to_the_surface() {
    let s = bezier(&lecture_net()).unwrap();
    let round = s.thicken(0.4, Edges::Round).unwrap();
    let flat = s.thicken(0.4, Edges::Flat).unwrap();
    for k in 0..30 {
        let (u, v) = (
            0.1 + (k as f64 * 0.137) % 0.8,
            0.1 + (k as f64 * 0.611) % 0.8,
        );
        let h = 1e-6;
        let q = s.point(u, v);
        let n = (s.point(u + h, v) - s.point(u - h, v))
            .cross(s.point(u, v + h) - s.point(u, v - h))
            .normalize();
        for w in [-0.15, 0.0, 0.1] {
            let p = q + n * w;
            let d = at(&round, p.to_array());
            assert!(
                (d - (w.abs() - 0.2)).abs() < 1e-6,
                "round at ({u}, {v}, {w}): {d}"
            );
            let f = at(&flat, p.to_array());
            assert!(f < 0.0, "flat at ({u}, {v}, {w}): {f}");
        }
        let outside = q + n * 0.3;
        assert!(at(&flat, outside.to_array()) > 0.0);
    }
    // Past an edge the round slab goes on a little and the flat one does not.
    let edge = s.point(0.5, 0.0);
    let out = s.point(0.5, 0.0) - (s.point(0.5, 1e-6) - edge).normalize() * 0.1;
    assert!(at(&round, out.to_array()) < 0.0);
    assert!(at(&flat, out.to_array()) > 0.0);
    assert!(s.thicken(0.0, Edges::Round).is_err());
}

#[test]
fn thick_intervals_enclose_values() {
    let s = bezier(&lecture_net()).unwrap();
    for edges in [Edges::Round, Edges::Flat] {
        let f = ThickSurface::new(&s, 0.3, edges);
        for k in 0..60 {
            let c = DVec3::new(
                (k as f64 * 0.37) % 4.0 - 0.5,
                (k as f64 * 0.73) % 4.0 - 0.5,
                (k as f64 * 0.19) % 3.0 - 0.5,
            );
            let r = 0.05 + (k % 5) as f64 * 0.2;
            let iv = |a: f64, b: f64| isoforge_field::Interval::try_from((a, b)).unwrap();
            let e = f.interval([
                iv(c.x - r, c.x + r),
                iv(c.y - r, c.y + r),
                iv(c.z - r, c.z + r),
            ]);
            for a in [-1.0, 0.0, 1.0] {
                for b in [-1.0, 0.0, 1.0] {
                    for d in [-1.0, 0.0, 1.0] {
                        let p = c + DVec3::new(a, b, d) * r;
                        let v = f.value(p.to_array());
                        assert!(e.inf() <= v && v <= e.sup(), "{edges:?}: {v} not in {e:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn batched_values_match_single_points() {
    let s = bezier(&lecture_net()).unwrap();
    for edges in [Edges::Round, Edges::Flat] {
        let f = ThickSurface::new(&s, 0.3, edges);
        // Rows of neighbours like the mesher's blocks, plus a far jump inside one group.
        let n = 70;
        let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n {
            let far = if k == 40 { 5.0 } else { 0.0 };
            xs.push(-0.5 + k as f64 * 0.06 + far);
            ys.push(1.3 + (k % 7) as f64 * 0.01);
            zs.push(0.2 - (k % 3) as f64 * 0.05);
        }
        let mut out = vec![0.0; n];
        f.values(&xs, &ys, &zs, &mut out);
        for k in 0..n {
            let one = f.value([xs[k], ys[k], zs[k]]);
            assert!(
                (out[k] - one).abs() < 1e-7,
                "{edges:?} point {k}: {} vs {one}",
                out[k]
            );
        }
    }
}

/// The mesher samples a block's 17³ corners in one batch call, x fastest, and the batch
/// carries each point's foot over to the next as a warm start. Along the border those
/// warm starts must land on the same feet as a fresh search: they once stopped a hair
/// short of the border (s = 1 − 10⁻⁷, or 5·10⁻⁴ of a piece after a jump to a new row),
/// read that as barely inside, and left loose slivers beyond the s = 0 and s = 1 borders
/// of `fixtures/sweeps/lecture_bezier.rhai` at depths 8 and 9.
#[test]
fn batched_blocks_along_the_border_match_single_points() {
    let s = bezier(&lecture_net()).unwrap();
    let f = ThickSurface::new(&s, 0.3, Edges::Flat);
    // The fixture's region, [-0.5, 3.5]² × [-0.5, 2.5], as the mesher's grid.
    let origin = DVec3::splat(-0.5);
    let (mut points, mut worst) = (0, 0.0f64);
    for depth in [8, 9] {
        let cell = 4.0 / f64::from(1u32 << depth);
        let block = 16.0 * cell;
        // Every block within half the thickness of the border.
        let mut blocks = std::collections::BTreeSet::new();
        for k in 0..=200 {
            let u = f64::from(k) / 200.0;
            for (a, b) in [(u, 0.0), (u, 1.0), (0.0, u), (1.0, u)] {
                let q = s.point(a, b);
                for o in 0..9 {
                    // The point and the corners of a cube around it.
                    let off = if o == 8 {
                        DVec3::ZERO
                    } else {
                        DVec3::new(
                            f64::from(o & 1) * 2.0 - 1.0,
                            f64::from(o >> 1 & 1) * 2.0 - 1.0,
                            f64::from(o >> 2) * 2.0 - 1.0,
                        ) * 0.15
                    };
                    let c = ((q + off - origin) / block).floor();
                    blocks.insert([c.x as i64, c.y as i64, c.z as i64]);
                }
            }
        }
        for b in blocks {
            let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
            for k in 0..17 {
                for j in 0..17 {
                    for i in 0..17 {
                        xs.push(origin.x + (b[0] * 16 + i) as f64 * cell);
                        ys.push(origin.y + (b[1] * 16 + j) as f64 * cell);
                        zs.push(origin.z + (b[2] * 16 + k) as f64 * cell);
                    }
                }
            }
            let mut out = vec![0.0; xs.len()];
            f.values(&xs, &ys, &zs, &mut out);
            for q in 0..out.len() {
                let one = f.value([xs[q], ys[q], zs[q]]);
                worst = worst.max((out[q] - one).abs());
                assert!(
                    (out[q] - one).abs() < 1e-6,
                    "depth {depth}, block {b:?}, ({}, {}, {}): batch {} vs single {one}",
                    xs[q],
                    ys[q],
                    zs[q],
                    out[q]
                );
                points += 1;
            }
        }
    }
    println!("{points} points, batch and single apart by at most {worst:.1e}");
}
