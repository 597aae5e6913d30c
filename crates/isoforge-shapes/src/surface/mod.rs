//! Free-form surfaces made printable: Bezier-Bernstein patches over a guiding net of any
//! size, uniform B-splines of degree 1 to 3 (with the boundary correction of clamped
//! indices as an option), and bilinearly blended Coons patches of four boundary curves,
//! each thickened into a solid of a given thickness centred on the surface.
//!
//! Every kind becomes a [`Surface`]: a set of Bezier patches over the parameter square
//! (a B-spline's spans converted exactly, a Coons patch's cells exactly as bicubics of its
//! sampled boundary curves). [`thick::ThickSurface`] is the field of the thickened solid:
//! a closest-point search (subdivision for a start, Newton to finish) over a hierarchy of
//! sub-patches, with interval bounds from their control nets' boxes.

pub mod patch;
pub mod thick;

use glam::DVec3;
use isoforge_field::Shape;

use patch::{MAX_ORDER, Patch, elevate_linear};
pub use thick::{Edges, ThickSurface};

/// Why a surface could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SurfaceError {
    /// The net is not a grid of the right size.
    #[error("{0}")]
    BadNet(String),
    /// A number out of range.
    #[error("{what} must be {range}, not {value}")]
    OutOfRange {
        /// What it was.
        what: &'static str,
        /// The range, in words.
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// A boundary curve gave a point that is not finite.
    #[error("the curve {curve} gives a point that is not finite at {at}")]
    NotFinite {
        /// Which curve (c0, c1, d0, d1).
        curve: &'static str,
        /// The parameter.
        at: f64,
    },
}

/// A surface over (s, t) in [0, 1]², as Bezier patches.
#[derive(Clone, Debug)]
pub struct Surface {
    patches: Vec<Patch>,
}

impl Surface {
    /// The patches.
    pub fn patches(&self) -> &[Patch] {
        &self.patches
    }

    /// The point Q(s, t).
    pub fn point(&self, s: f64, t: f64) -> DVec3 {
        let (s, t) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let patch = self
            .patches
            .iter()
            .find(|p| {
                p.s_range[0] <= s && s <= p.s_range[1] && p.t_range[0] <= t && t <= p.t_range[1]
            })
            .unwrap_or(&self.patches[0]);
        let u = (s - patch.s_range[0]) / (patch.s_range[1] - patch.s_range[0]);
        let v = (t - patch.t_range[0]) / (patch.t_range[1] - patch.t_range[0]);
        patch.point(u, v)
    }

    /// The solid of thickness `thickness` centred on the surface.
    pub fn thicken(&self, thickness: f64, edges: Edges) -> Result<Shape, SurfaceError> {
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(SurfaceError::OutOfRange {
                what: "the thickness",
                range: "a positive number",
                value: thickness,
            });
        }
        Ok(Shape::custom(std::sync::Arc::new(ThickSurface::new(
            self, thickness, edges,
        ))))
    }
}

fn check_net(net: &[Vec<[f64; 3]>], min: usize) -> Result<(usize, usize), SurfaceError> {
    let rows = net.len();
    let cols = net.first().map_or(0, Vec::len);
    if rows < min || cols < min {
        return Err(SurfaceError::BadNet(format!(
            "the net is {rows} x {cols}; it needs at least {min} x {min} points"
        )));
    }
    for (i, row) in net.iter().enumerate() {
        if row.len() != cols {
            return Err(SurfaceError::BadNet(format!(
                "row {i} of the net has {} points, row 0 has {cols}; every row needs the same count",
                row.len()
            )));
        }
        for (j, p) in row.iter().enumerate() {
            if !p.iter().all(|c| c.is_finite()) {
                return Err(SurfaceError::BadNet(format!(
                    "point [{i}][{j}] of the net is not finite"
                )));
            }
        }
    }
    Ok((rows, cols))
}

/// `bezier_surface(net)`: Q(s, t) = Σ P_ij B_i(s) B_j(t), the Bernstein polynomials of
/// degree rows − 1 in s and cols − 1 in t.
pub fn bezier(net: &[Vec<[f64; 3]>]) -> Result<Surface, SurfaceError> {
    let (rows, cols) = check_net(net, 2)?;
    if rows > MAX_ORDER || cols > MAX_ORDER {
        return Err(SurfaceError::BadNet(format!(
            "the net is {rows} x {cols}; a Bezier patch takes at most {MAX_ORDER} points each way (use bspline_surface for larger nets)"
        )));
    }
    let pts = net.iter().flatten().map(|&p| DVec3::from(p)).collect();
    Ok(Surface {
        patches: vec![Patch::new(rows, cols, pts)],
    })
}

/// The Bezier controls of one uniform B-spline span of degree `d` from its `d + 1`
/// B-spline control points.
fn span_to_bezier(d: usize, p: &[DVec3]) -> Vec<DVec3> {
    match d {
        1 => vec![p[0], p[1]],
        2 => vec![(p[0] + p[1]) * 0.5, p[1], (p[1] + p[2]) * 0.5],
        _ => vec![
            (p[0] + p[1] * 4.0 + p[2]) / 6.0,
            (p[1] * 2.0 + p[2]) / 3.0,
            (p[1] + p[2] * 2.0) / 3.0,
            (p[1] + p[2] * 4.0 + p[3]) / 6.0,
        ],
    }
}

/// `bspline_surface(net, degree, #{clamped})`: the uniform B-spline surface of degree 1
/// to 3 over the net. Unclamped, it spans the net's inner part (n − degree spans a
/// side); clamped, the edge control points are repeated degree − 1 more times (the
/// lecture's indices clamped at the edges), so the surface reaches the net's corners and
/// edges.
pub fn bspline(net: &[Vec<[f64; 3]>], degree: i64, clamped: bool) -> Result<Surface, SurfaceError> {
    if !(1..=3).contains(&degree) {
        return Err(SurfaceError::OutOfRange {
            what: "the degree",
            range: "1, 2 or 3",
            value: degree as f64,
        });
    }
    let d = degree as usize;
    let (rows, cols) = check_net(net, d + 1)?;
    let pad = if clamped { d.saturating_sub(1) } else { 0 };
    let index = |k: usize, n: usize| k.saturating_sub(pad).min(n - 1);
    let (nr, nc) = (rows + 2 * pad, cols + 2 * pad);
    let at = |i: usize, j: usize| DVec3::from(net[index(i, rows)][index(j, cols)]);
    let (spans_s, spans_t) = (nr - d, nc - d);
    let mut patches = Vec::with_capacity(spans_s * spans_t);
    for a in 0..spans_s {
        for b in 0..spans_t {
            // Convert the (d+1)² local points: rows first, then columns.
            let mut rowwise = Vec::with_capacity((d + 1) * (d + 1));
            for i in 0..=d {
                let row: Vec<DVec3> = (0..=d).map(|j| at(a + i, b + j)).collect();
                rowwise.push(span_to_bezier(d, &row));
            }
            let mut pts = vec![DVec3::ZERO; (d + 1) * (d + 1)];
            for j in 0..=d {
                let col: Vec<DVec3> = (0..=d).map(|i| rowwise[i][j]).collect();
                for (i, q) in span_to_bezier(d, &col).into_iter().enumerate() {
                    pts[i * (d + 1) + j] = q;
                }
            }
            let s = [a as f64 / spans_s as f64, (a + 1) as f64 / spans_s as f64];
            let t = [b as f64 / spans_t as f64, (b + 1) as f64 / spans_t as f64];
            patches.push(Patch::new(d + 1, d + 1, pts).placed(s, t));
        }
    }
    Ok(Surface { patches })
}

/// Cells each boundary curve of a Coons patch is sampled into: the curves become cubic
/// Hermite pieces, and at 32 the lecture's `½ sin 2πs` is matched to 2e-6 (the
/// cubic's error, h⁴/384 times the fourth derivative), far below any printable detail.
pub const COONS_CELLS: usize = 32;

/// A boundary curve sampled for a Coons patch: points and derivatives at the cell ends.
struct Sampled {
    p: Vec<DVec3>,
    d: Vec<DVec3>,
}

fn sample(
    name: &'static str,
    f: &dyn Fn(f64) -> [f64; 3],
    n: usize,
) -> Result<Sampled, SurfaceError> {
    let at = |s: f64| {
        let p = DVec3::from(f(s));
        if p.is_finite() {
            Ok(p)
        } else {
            Err(SurfaceError::NotFinite { curve: name, at: s })
        }
    };
    let h = 1e-4 / n as f64;
    let mut p = Vec::with_capacity(n + 1);
    let mut d = Vec::with_capacity(n + 1);
    for i in 0..=n {
        let s = i as f64 / n as f64;
        p.push(at(s)?);
        // Central differences, one-sided at the ends (the curve may not exist past them).
        let (a, b) = ((s - h).max(0.0), (s + h).min(1.0));
        d.push((at(b)? - at(a)?) / (b - a));
    }
    Ok(Sampled { p, d })
}

impl Sampled {
    /// The cubic Bezier controls of cell `i`.
    fn cell(&self, i: usize, n: usize) -> [DVec3; 4] {
        let step = 1.0 / n as f64;
        [
            self.p[i],
            self.p[i] + self.d[i] * (step / 3.0),
            self.p[i + 1] - self.d[i + 1] * (step / 3.0),
            self.p[i + 1],
        ]
    }
}

/// The four boundary curves of a Coons patch: `c0(s) = P(s, 0)`, `c1(s) = P(s, 1)`,
/// `d0(t) = P(0, t)`, `d1(t) = P(1, t)`.
pub struct CoonsCurves<'a> {
    /// P(s, 0).
    pub c0: &'a dyn Fn(f64) -> [f64; 3],
    /// P(s, 1).
    pub c1: &'a dyn Fn(f64) -> [f64; 3],
    /// P(0, t).
    pub d0: &'a dyn Fn(f64) -> [f64; 3],
    /// P(1, t).
    pub d1: &'a dyn Fn(f64) -> [f64; 3],
}

/// `coons_patch(c0, c1, d0, d1)`: the bilinearly blended Coons patch
/// `(1−t)c0(s) + t c1(s) + (1−s)d0(t) + s d1(t) − [(1−s)(1−t)P00 + s(1−t)P10 + (1−s)t P01 + s t P11]`
/// with the corners taken from c0 and c1.
pub fn coons(curves: &CoonsCurves) -> Result<Surface, SurfaceError> {
    let n = COONS_CELLS;
    let c0 = sample("c0", curves.c0, n)?;
    let c1 = sample("c1", curves.c1, n)?;
    let d0 = sample("d0", curves.d0, n)?;
    let d1 = sample("d1", curves.d1, n)?;
    let (p00, p10) = (c0.p[0], c0.p[n]);
    let (p01, p11) = (c1.p[0], c1.p[n]);
    let bilinear = |s: f64, t: f64| {
        p00 * (1.0 - s) * (1.0 - t) + p10 * s * (1.0 - t) + p01 * (1.0 - s) * t + p11 * s * t
    };
    let mut patches = Vec::with_capacity(n * n);
    for a in 0..n {
        let (s0, s1) = (a as f64 / n as f64, (a + 1) as f64 / n as f64);
        let (c0a, c1a) = (c0.cell(a, n), c1.cell(a, n));
        for b in 0..n {
            let (t0, t1) = (b as f64 / n as f64, (b + 1) as f64 / n as f64);
            let (d0b, d1b) = (d0.cell(b, n), d1.cell(b, n));
            // Each term as a bicubic Bezier net on this cell, rows in s, columns in t.
            let mut pts = vec![DVec3::ZERO; 16];
            for i in 0..4 {
                // The linear blends in t and in s, raised to degree 3.
                let along_t = elevate_linear(
                    c0a[i] * (1.0 - t0) + c1a[i] * t0,
                    c0a[i] * (1.0 - t1) + c1a[i] * t1,
                );
                for j in 0..4 {
                    let along_s = elevate_linear(
                        d0b[j] * (1.0 - s0) + d1b[j] * s0,
                        d0b[j] * (1.0 - s1) + d1b[j] * s1,
                    );
                    // The bilinear corner term is bilinear in (s, t), so its Bezier
                    // controls are its values at the elevated grid's parameters.
                    let (si, tj) = (
                        s0 + (s1 - s0) * i as f64 / 3.0,
                        t0 + (t1 - t0) * j as f64 / 3.0,
                    );
                    pts[i * 4 + j] = along_t[j] + along_s[i] - bilinear(si, tj);
                }
            }
            patches.push(Patch::new(4, 4, pts).placed([s0, s1], [t0, t1]));
        }
    }
    Ok(Surface { patches })
}

#[cfg(test)]
mod tests;
