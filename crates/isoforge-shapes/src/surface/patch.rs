//! Tensor-product Bezier patches: evaluation with first and second derivatives (from
//! Bernstein polynomials), subdivision by de Casteljau, degree elevation, and the convex
//! hull property (the patch lies in its control points' box).

use glam::DVec3;

/// The most control points along one side of a patch: Bernstein evaluation keeps its
/// bases on the stack, and beyond this degree a Bezier patch is numerically meaningless.
pub const MAX_ORDER: usize = 64;

/// Stack buffers for patches up to degree 7 each way (the common bicubic ones).
const SMALL: usize = 8;

/// A patch of degree (m, n): `(m + 1) × (n + 1)` control points, row-major (row i is
/// the i-th in s), covering `s_range × t_range` of its surface's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    rows: usize,
    cols: usize,
    pts: Vec<DVec3>,
    /// Where the patch sits in the surface's (s, t) parameters.
    pub s_range: [f64; 2],
    /// As `s_range`, for t.
    pub t_range: [f64; 2],
}

/// A point of a patch and its derivatives in the patch's own (u, v) in [0, 1]².
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Jet {
    /// The point.
    pub p: DVec3,
    /// ∂/∂u.
    pub du: DVec3,
    /// ∂/∂v.
    pub dv: DVec3,
    /// ∂²/∂u².
    pub duu: DVec3,
    /// ∂²/∂u∂v.
    pub duv: DVec3,
    /// ∂²/∂v².
    pub dvv: DVec3,
}

/// The Bernstein bases of degree `n` at `u` with their first and second derivatives,
/// into the first `n + 1` entries of each slice (which hold at least that many).
fn bernstein<const N: usize>(n: usize, u: f64, b: &mut [f64], d1: &mut [f64], d2: &mut [f64]) {
    // Degree n − 2 in place, B(k, i) = (1 − u) B(k−1, i) + u B(k−1, i−1); then one more
    // step into `p1` (degree n − 1) and one into `b` (degree n), so nothing is copied.
    let mut p1 = [0.0f64; N];
    let mut p2 = [0.0f64; N];
    let step = |from: &[f64], to: &mut [f64], k: usize| {
        // `from` holds degree k − 1 (k entries); `to` gets degree k (k + 1 entries).
        to[0] = (1.0 - u) * from[0];
        for i in 1..k {
            to[i] = (1.0 - u) * from[i] + u * from[i - 1];
        }
        to[k] = u * from[k - 1];
    };
    match n {
        0 => b[0] = 1.0,
        1 => {
            p1[0] = 1.0;
            step(&p1, b, 1);
        }
        _ => {
            p2[0] = 1.0;
            for k in 1..=n - 2 {
                // In place, from the top down, so each entry reads the old one below it.
                p2[k] = u * p2[k - 1];
                for i in (1..k).rev() {
                    p2[i] = (1.0 - u) * p2[i] + u * p2[i - 1];
                }
                p2[0] *= 1.0 - u;
            }
            step(&p2, &mut p1, n - 1);
            step(&p1, b, n);
        }
    }
    let nf = n as f64;
    for i in 0..=n {
        d1[i] = if n >= 1 {
            let a = if i > 0 { p1[i - 1] } else { 0.0 };
            let c = if i < n { p1[i] } else { 0.0 };
            nf * (a - c)
        } else {
            0.0
        };
        d2[i] = if n >= 2 {
            let at = |k: isize| {
                if k >= 0 && (k as usize) <= n - 2 {
                    p2[k as usize]
                } else {
                    0.0
                }
            };
            let i = i as isize;
            nf * (nf - 1.0) * (at(i - 2) - 2.0 * at(i - 1) + at(i))
        } else {
            0.0
        };
    }
}

impl Patch {
    /// A patch from rows of control points (every row the same length, 2 to
    /// [`MAX_ORDER`] each way) covering `[0, 1]²`.
    pub fn new(rows: usize, cols: usize, pts: Vec<DVec3>) -> Patch {
        debug_assert_eq!(rows * cols, pts.len());
        Patch {
            rows,
            cols,
            pts,
            s_range: [0.0, 1.0],
            t_range: [0.0, 1.0],
        }
    }

    /// The same patch placed at `s_range × t_range` of its surface.
    pub fn placed(mut self, s_range: [f64; 2], t_range: [f64; 2]) -> Patch {
        self.s_range = s_range;
        self.t_range = t_range;
        self
    }

    /// Rows and columns of control points.
    pub fn size(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }

    /// Control point (i, j).
    pub fn at(&self, i: usize, j: usize) -> DVec3 {
        self.pts[i * self.cols + j]
    }

    /// The four corner points (a patch passes through them) with their (u, v).
    pub fn corners(&self) -> [(DVec3, glam::DVec2); 4] {
        let (m, n) = (self.rows - 1, self.cols - 1);
        [
            (self.at(0, 0), glam::DVec2::new(0.0, 0.0)),
            (self.at(0, n), glam::DVec2::new(0.0, 1.0)),
            (self.at(m, 0), glam::DVec2::new(1.0, 0.0)),
            (self.at(m, n), glam::DVec2::new(1.0, 1.0)),
        ]
    }

    /// The control points.
    pub fn points(&self) -> &[DVec3] {
        &self.pts
    }

    /// The point and derivatives at (u, v) in [0, 1]².
    pub fn jet(&self, u: f64, v: f64) -> Jet {
        // Most patches are bicubic: small stack buffers keep evaluation cheap.
        if self.rows <= SMALL && self.cols <= SMALL {
            self.jet_with::<SMALL>(u, v)
        } else {
            self.jet_with::<MAX_ORDER>(u, v)
        }
    }

    fn jet_with<const N: usize>(&self, u: f64, v: f64) -> Jet {
        let (m, n) = (self.rows - 1, self.cols - 1);
        let (mut bu, mut du, mut ddu) = ([0.0; N], [0.0; N], [0.0; N]);
        let (mut bv, mut dv, mut ddv) = ([0.0; N], [0.0; N], [0.0; N]);
        bernstein::<N>(m, u, &mut bu, &mut du, &mut ddu);
        bernstein::<N>(n, v, &mut bv, &mut dv, &mut ddv);
        let mut jet = Jet {
            p: DVec3::ZERO,
            du: DVec3::ZERO,
            dv: DVec3::ZERO,
            duu: DVec3::ZERO,
            duv: DVec3::ZERO,
            dvv: DVec3::ZERO,
        };
        for i in 0..=m {
            // Each row's blend in v, then weighted in u.
            let (mut row, mut row_v, mut row_vv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
            let base = i * self.cols;
            for j in 0..=n {
                let q = self.pts[base + j];
                row += q * bv[j];
                row_v += q * dv[j];
                row_vv += q * ddv[j];
            }
            jet.p += row * bu[i];
            jet.du += row * du[i];
            jet.dv += row_v * bu[i];
            jet.duu += row * ddu[i];
            jet.duv += row_v * du[i];
            jet.dvv += row_vv * bu[i];
        }
        jet
    }

    /// The point at (u, v) in [0, 1]².
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.jet(u, v).p
    }

    /// The surface's (s, t) at the patch's (u, v).
    pub fn global(&self, u: f64, v: f64) -> (f64, f64) {
        (
            self.s_range[0] + u * (self.s_range[1] - self.s_range[0]),
            self.t_range[0] + v * (self.t_range[1] - self.t_range[0]),
        )
    }

    /// The box of the control points, which holds the patch (convex hull property).
    pub fn hull_box(&self) -> crate::bvh::Box3 {
        crate::bvh::Box3::around(self.pts.iter().copied())
    }

    /// How far the control points stray from the bilinear patch of the four corners:
    /// zero for a flat, evenly spaced net.
    pub fn flatness(&self) -> f64 {
        let (m, n) = (self.rows - 1, self.cols - 1);
        let c = [self.at(0, 0), self.at(0, n), self.at(m, 0), self.at(m, n)];
        let mut worst = 0.0f64;
        for i in 0..=m {
            for j in 0..=n {
                let (u, v) = (i as f64 / m as f64, j as f64 / n as f64);
                let bilinear = c[0] * (1.0 - u) * (1.0 - v)
                    + c[1] * (1.0 - u) * v
                    + c[2] * u * (1.0 - v)
                    + c[3] * u * v;
                worst = worst.max(self.at(i, j).distance(bilinear));
            }
        }
        worst
    }

    /// The four quarters, split at u = v = ½ by de Casteljau, in order
    /// (low u, low v), (low u, high v), (high u, low v), (high u, high v).
    pub fn split(&self) -> [Patch; 4] {
        let (rows, cols) = (self.rows, self.cols);
        // Split every row in v.
        let mut left = vec![DVec3::ZERO; rows * cols];
        let mut right = vec![DVec3::ZERO; rows * cols];
        for i in 0..rows {
            let row: Vec<DVec3> = (0..cols).map(|j| self.at(i, j)).collect();
            let (l, r) = halve(&row);
            left[i * cols..(i + 1) * cols].copy_from_slice(&l);
            right[i * cols..(i + 1) * cols].copy_from_slice(&r);
        }
        // Then every column of each half in u.
        let split_u = |net: &[DVec3]| {
            let mut lo = vec![DVec3::ZERO; rows * cols];
            let mut hi = vec![DVec3::ZERO; rows * cols];
            for j in 0..cols {
                let col: Vec<DVec3> = (0..rows).map(|i| net[i * cols + j]).collect();
                let (a, b) = halve(&col);
                for i in 0..rows {
                    lo[i * cols + j] = a[i];
                    hi[i * cols + j] = b[i];
                }
            }
            (lo, hi)
        };
        let (ll, hl) = split_u(&left);
        let (lr, hr) = split_u(&right);
        let [s0, s1] = self.s_range;
        let [t0, t1] = self.t_range;
        let (sm, tm) = (0.5 * (s0 + s1), 0.5 * (t0 + t1));
        let make = |pts: Vec<DVec3>, s: [f64; 2], t: [f64; 2]| Patch {
            rows,
            cols,
            pts,
            s_range: s,
            t_range: t,
        };
        [
            make(ll, [s0, sm], [t0, tm]),
            make(lr, [s0, sm], [tm, t1]),
            make(hl, [sm, s1], [t0, tm]),
            make(hr, [sm, s1], [tm, t1]),
        ]
    }
}

/// A Bezier curve's control points split at ½ (de Casteljau).
fn halve(c: &[DVec3]) -> (Vec<DVec3>, Vec<DVec3>) {
    let n = c.len();
    let mut work = c.to_vec();
    let mut left = Vec::with_capacity(n);
    let mut right = Vec::with_capacity(n);
    left.push(work[0]);
    right.push(work[n - 1]);
    for k in 1..n {
        for i in 0..n - k {
            work[i] = (work[i] + work[i + 1]) * 0.5;
        }
        left.push(work[0]);
        right.push(work[n - 1 - k]);
    }
    right.reverse();
    (left, right)
}

/// A cubic Bezier segment's controls from a linear one's (degree elevation 1 → 3).
pub fn elevate_linear(a: DVec3, b: DVec3) -> [DVec3; 4] {
    [a, (a * 2.0 + b) / 3.0, (a + b * 2.0) / 3.0, b]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binom(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    /// Q(s, t) = Σ P_ij B_i(s) B_j(t), written out directly.
    fn direct(p: &Patch, u: f64, v: f64) -> DVec3 {
        let (m, n) = (p.rows - 1, p.cols - 1);
        let mut q = DVec3::ZERO;
        for i in 0..=m {
            for j in 0..=n {
                let bi = binom(m, i) * u.powi(i as i32) * (1.0 - u).powi((m - i) as i32);
                let bj = binom(n, j) * v.powi(j as i32) * (1.0 - v).powi((n - j) as i32);
                q += p.at(i, j) * bi * bj;
            }
        }
        q
    }

    fn wavy(rows: usize, cols: usize) -> Patch {
        let pts = (0..rows)
            .flat_map(|i| {
                (0..cols).map(move |j| {
                    DVec3::new(i as f64, j as f64, ((i * 3 + j * 5) % 7) as f64 * 0.3)
                })
            })
            .collect();
        Patch::new(rows, cols, pts)
    }

    #[test]
    fn evaluation_matches_the_bernstein_sum_and_its_derivatives() {
        for (r, c) in [(2, 2), (4, 4), (3, 6), (8, 5)] {
            let p = wavy(r, c);
            for k in 0..20 {
                let (u, v) = ((k as f64 * 0.173) % 1.0, (k as f64 * 0.391) % 1.0);
                let j = p.jet(u, v);
                assert!(j.p.distance(direct(&p, u, v)) < 1e-12);
                let h = 1e-5;
                let fd_u = (direct(&p, u + h, v) - direct(&p, u - h, v)) / (2.0 * h);
                let fd_v = (direct(&p, u, v + h) - direct(&p, u, v - h)) / (2.0 * h);
                assert!(j.du.distance(fd_u) < 1e-6, "{r}x{c} du");
                assert!(j.dv.distance(fd_v) < 1e-6, "{r}x{c} dv");
                let fd_uu = (p.jet(u + h, v).du - p.jet(u - h, v).du) / (2.0 * h);
                let fd_uv = (p.jet(u, v + h).du - p.jet(u, v - h).du) / (2.0 * h);
                let fd_vv = (p.jet(u, v + h).dv - p.jet(u, v - h).dv) / (2.0 * h);
                assert!(j.duu.distance(fd_uu) < 1e-5);
                assert!(j.duv.distance(fd_uv) < 1e-5);
                assert!(j.dvv.distance(fd_vv) < 1e-5);
            }
        }
    }

    #[test]
    fn quarters_reproduce_the_patch_and_stay_in_its_hull() {
        let p = wavy(4, 5);
        let q = p.split();
        for k in 0..30 {
            let (u, v) = ((k as f64 * 0.29) % 1.0, (k as f64 * 0.53) % 1.0);
            // Quarter (high u, low v) at (u, v) is the patch at (½ + u/2, v/2).
            let a = q[2].point(u, v);
            let b = p.point(0.5 + 0.5 * u, 0.5 * v);
            assert!(a.distance(b) < 1e-12);
            let bx = q[2].hull_box();
            assert!(a.cmpge(bx.min - 1e-12).all() && a.cmple(bx.max + 1e-12).all());
        }
        assert_eq!(q[3].s_range, [0.5, 1.0]);
        assert_eq!(q[1].t_range, [0.5, 1.0]);
    }
}
