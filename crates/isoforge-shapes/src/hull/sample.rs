//! A field that is not a known convex body enters a hull by samples of its surface.

use std::sync::Arc;

use glam::DVec3;
use isoforge_field::{BatchEval, Bounds, PointEval, Shape, Tape, find_bounds};

use super::HullError;
use super::convex::{Body, Convex};
use super::polytope::sphere_directions;

/// Grid cells along a sampled part's longest side. The hull of the surface points found
/// is within one cell of the part's true hull; 64 keeps sampling a part (65³ values and
/// the crossings' bisection) near 50 ms in a release build.
pub const SAMPLES: usize = 64;

/// Bisection steps per crossing: 2⁻²⁰ of a cell, far below the grid's own error.
const BISECTIONS: usize = 20;

/// The points where `shape`'s surface crosses a grid over its region, reduced to the
/// farthest ones in many directions, as a convex body. `index` names the part in errors.
pub fn sampled_part(shape: &Shape, index: usize) -> Result<Convex, HullError> {
    let found = find_bounds(shape).map_err(|e| HullError::Unbounded {
        index,
        why: e.to_string(),
    })?;
    // One cell of margin, so the surface never touches the grid's faces.
    let cell = found.longest_side() / (SAMPLES - 2) as f64;
    let region = Bounds::new(found.min.map(|v| v - cell), found.max.map(|v| v + cell))
        .ok_or(HullError::NothingInside { index })?;
    let points = surface_points(shape, &region, cell);
    if points.is_empty() {
        return Err(HullError::NothingInside { index });
    }
    Ok(Convex::new(Body::Points(Arc::from(extremes(&points)))))
}

/// Directions in which the sampled points' farthest ones are kept: level 3 of the
/// icosphere, 642 directions 0.14 rad apart. A point farthest in none of them lies within
/// about 0.3% of the part's size of the kept points' hull (the sagitta of that spacing), and
/// GJK then asks for at most 642 points' support instead of thousands.
const EXTREME_LEVEL: u32 = 3;

/// The points farthest along each direction of [`EXTREME_LEVEL`], without repeats.
fn extremes(points: &[DVec3]) -> Vec<DVec3> {
    let mut keep: Vec<usize> = sphere_directions(EXTREME_LEVEL)
        .iter()
        .filter_map(|&n| {
            (0..points.len()).max_by(|&a, &b| points[a].dot(n).total_cmp(&points[b].dot(n)))
        })
        .collect();
    keep.sort_unstable();
    keep.dedup();
    keep.into_iter().map(|i| points[i]).collect()
}

/// Surface crossings on the edges of a grid of `cell`-sized cells over `region`.
fn surface_points(shape: &Shape, region: &Bounds, cell: f64) -> Vec<DVec3> {
    let tape = Tape::new(shape);
    let size = region.size();
    let n = [0, 1, 2].map(|i| ((size[i] / cell).ceil() as usize).max(1) + 1);
    let at = |i: usize, j: usize, k: usize| {
        DVec3::new(
            region.min[0] + i as f64 * cell,
            region.min[1] + j as f64 * cell,
            region.min[2] + k as f64 * cell,
        )
    };
    let count = n[0] * n[1] * n[2];
    let (mut xs, mut ys, mut zs) = (
        Vec::with_capacity(count),
        Vec::with_capacity(count),
        Vec::with_capacity(count),
    );
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = at(i, j, k);
                xs.push(p.x);
                ys.push(p.y);
                zs.push(p.z);
            }
        }
    }
    let mut values = vec![0.0; count];
    BatchEval::new().eval(&tape, &xs, &ys, &zs, &mut values);
    let inside = |v: f64| v < 0.0;
    let index = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    let mut pe = PointEval::new();
    let mut out = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let a = index(i, j, k);
                for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                    let (i2, j2, k2) = (i + di, j + dj, k + dk);
                    if i2 >= n[0] || j2 >= n[1] || k2 >= n[2] {
                        continue;
                    }
                    let b = index(i2, j2, k2);
                    if inside(values[a]) == inside(values[b]) {
                        continue;
                    }
                    // Bisect, keeping the inside end: the point found lies in the solid.
                    let (mut p_in, mut p_out) = (at(i, j, k), at(i2, j2, k2));
                    if !inside(values[a]) {
                        std::mem::swap(&mut p_in, &mut p_out);
                    }
                    for _ in 0..BISECTIONS {
                        let m = (p_in + p_out) * 0.5;
                        if inside(pe.eval(&tape, m.to_array())) {
                            p_in = m;
                        } else {
                            p_out = m;
                        }
                    }
                    out.push(p_in);
                }
            }
        }
    }
    out
}
