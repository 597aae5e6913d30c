//! The quadratic error function of dual contouring (Ju, Losasso, Schaefer, Warren 2002):
//! the point that best fits the planes through a patch's edge crossings.
//!
//! A [`Qef`] holds the planes as sums (AᵀA, Aᵀb, bᵀb, the mass point), so the QEFs of
//! eight cells add up to their parent's, which is what merging octree cells needs. Sums are
//! kept relative to an origin near the planes (the block's corner), so that large
//! coordinates do not eat the precision of a small error.
//!
//! [`Qef::solve_in`] finds the minimizer inside a box. The free minimizer comes from a
//! truncated pseudo-inverse around the mass point, so a flat or curved patch (rank 1 or 2)
//! keeps its vertex near the middle of its crossings instead of sliding along the free
//! directions. When that point is outside the box, the minimum over the box lies on one of
//! its faces, edges or corners: each is solved with those coordinates held, and the best
//! feasible one wins. Clamping instead (moving the point into the box along the axes) takes
//! it off the planes: a cube's edge that clips a cell's corner had its vertex 0.1 of a cell
//! off the cube's faces that way.

use glam::{DMat3, DVec3};

/// Singular values below this fraction of the largest are dropped. 0.1 is the usual
/// choice (Ju et al.; fidget and libfive use similar cut-offs): it keeps true corners
/// (three well separated normals) and treats nearly parallel normals as one plane.
const SINGULAR_CUTOFF: f64 = 0.1;

/// A sum of plane constraints `n · x = n · p` (point `p`, unit normal `n`).
#[derive(Clone, Copy, Debug)]
pub struct Qef {
    /// Every sum below is over coordinates relative to this point.
    origin: DVec3,
    /// AᵀA = Σ n nᵀ.
    ata: DMat3,
    /// Aᵀb = Σ n d, with d = n · (p − origin).
    atb: DVec3,
    /// bᵀb = Σ d².
    btb: f64,
    /// Σ (p − origin).
    mass: DVec3,
    /// Planes added.
    count: u32,
}

impl Default for Qef {
    /// No planes, around the origin. (Not derived: glam's default matrix is the identity.)
    fn default() -> Self {
        Qef::new(DVec3::ZERO)
    }
}

impl Qef {
    /// No planes, sums taken around `origin`.
    pub fn new(origin: DVec3) -> Self {
        Qef {
            origin,
            ata: DMat3::ZERO,
            atb: DVec3::ZERO,
            btb: 0.0,
            mass: DVec3::ZERO,
            count: 0,
        }
    }

    /// Clears the planes and moves the origin.
    pub fn reset(&mut self, origin: DVec3) {
        *self = Qef::new(origin);
    }

    /// Adds the plane through `p` with unit normal `n`.
    pub fn add(&mut self, p: DVec3, n: DVec3) {
        let q = p - self.origin;
        let d = n.dot(q);
        // The outer product n nᵀ, column j being n · n[j].
        self.ata += DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        self.atb += n * d;
        self.btb += d * d;
        self.mass += q;
        self.count += 1;
    }

    /// Adds every plane of `other` (whatever its origin).
    pub fn merge(&mut self, other: &Qef) {
        let moved = other.moved_to(self.origin);
        self.ata += moved.ata;
        self.atb += moved.atb;
        self.btb += moved.btb;
        self.mass += moved.mass;
        self.count += moved.count;
    }

    /// The same planes with sums around `origin`: d changes by n · (old − new origin).
    fn moved_to(&self, origin: DVec3) -> Qef {
        let t = origin - self.origin;
        if t == DVec3::ZERO {
            return *self;
        }
        let ata_t = self.ata * t;
        Qef {
            origin,
            ata: self.ata,
            atb: self.atb - ata_t,
            btb: self.btb - 2.0 * t.dot(self.atb) + t.dot(ata_t),
            mass: self.mass - t * f64::from(self.count),
            count: self.count,
        }
    }

    /// How many planes were added.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// The mean of the crossings.
    pub fn mass_point(&self) -> DVec3 {
        self.origin + self.mass / f64::from(self.count.max(1))
    }

    /// Σ (n · x − d)² at `x`: the sum of squared distances from `x` to the planes.
    pub fn error(&self, x: DVec3) -> f64 {
        let q = x - self.origin;
        (q.dot(self.ata * q) - 2.0 * q.dot(self.atb) + self.btb).max(0.0)
    }

    /// The minimizer over all space (truncated, around the mass point); the mass point when
    /// nothing better is defined.
    #[cfg(test)]
    pub fn solve(&self) -> DVec3 {
        if self.count == 0 {
            return self.origin;
        }
        let m = self.mass / f64::from(self.count);
        self.origin + self.solve_fixed(m, [None; 3])
    }

    /// The minimizer over the box `[lo, hi]` (absolute coordinates; `lo <= hi`).
    pub fn solve_in(&self, lo: DVec3, hi: DVec3) -> DVec3 {
        self.solve_held(lo, hi).0
    }

    /// [`Qef::solve_in`], and, where the box held the point back, the free minimizer it
    /// lies outside (so the point is a compromise between planes that meet elsewhere).
    pub fn solve_held(&self, lo: DVec3, hi: DVec3) -> (DVec3, Option<DVec3>) {
        if self.count == 0 {
            return (((lo + hi) * 0.5).clamp(lo, hi), None);
        }
        let (lo, hi) = (lo - self.origin, hi - self.origin);
        let m = self.mass / f64::from(self.count);
        let free = self.solve_fixed(m, [None; 3]);
        let inside = |x: DVec3| x.cmpge(lo).all() && x.cmple(hi).all();
        if inside(free) {
            return (self.origin + free, None);
        }
        // The box's 26 faces, edges and corners: each axis held at lo, held at hi, or free.
        let mut best: Option<(f64, f64, DVec3)> = None;
        for code in 1..27u32 {
            let mut fixed = [None; 3];
            let mut k = code;
            for (a, f) in fixed.iter_mut().enumerate() {
                *f = match k % 3 {
                    1 => Some(lo[a]),
                    2 => Some(hi[a]),
                    _ => None,
                };
                k /= 3;
            }
            let x = self.solve_fixed(m, fixed);
            // Free coordinates may land a rounding step outside: hold them in.
            let x = x.clamp(lo, hi);
            let e = self.error(self.origin + x);
            let d = x.distance_squared(m);
            let better = match best {
                None => true,
                Some((be, bd, _)) => e < be * (1.0 - 1e-9) || (e <= be * (1.0 + 1e-9) && d < bd),
            };
            if better {
                best = Some((e, d, x));
            }
        }
        let x = match best {
            Some((_, _, x)) => x,
            None => free.clamp(lo, hi),
        };
        (self.origin + x, Some(self.origin + free))
    }

    /// The truncated minimizer with some coordinates held (relative coordinates), around
    /// the point `m` for the free ones.
    fn solve_fixed(&self, m: DVec3, fixed: [Option<f64>; 3]) -> DVec3 {
        let mut start = m;
        for (a, f) in fixed.iter().enumerate() {
            if let Some(v) = f {
                start[a] = *v;
            }
        }
        // Gradient of the error at `start`, halved: AᵀA start − Aᵀb; solve for the step
        // in the free coordinates only.
        let residual = self.atb - self.ata * start;
        let mut a = self.ata.to_cols_array_2d();
        let mut r = residual;
        for (i, f) in fixed.iter().enumerate() {
            if f.is_some() {
                r[i] = 0.0;
                a[i] = [0.0; 3];
                for row in a.iter_mut() {
                    row[i] = 0.0;
                }
            }
        }
        let (values, vectors) = eigen_sym(a);
        let max = values.iter().fold(0.0f64, |acc, &b| acc.max(b.abs()));
        if max <= 0.0 || !max.is_finite() {
            return start;
        }
        // AᵀA's eigenvalues are the squared singular values of A.
        let cut = max * SINGULAR_CUTOFF * SINGULAR_CUTOFF;
        let mut x = start;
        for k in 0..3 {
            if values[k].abs() < cut {
                continue;
            }
            let v = DVec3::new(vectors[0][k], vectors[1][k], vectors[2][k]);
            x += v * (v.dot(r) / values[k]);
        }
        if x.is_finite() { x } else { start }
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 matrix, by cyclic Jacobi
/// rotations: robust for the rank-deficient matrices QEFs give, and 3×3 converges in a
/// handful of sweeps.
#[allow(clippy::needless_range_loop)] // index form mirrors the matrix algebra
pub fn eigen_sym(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..24 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        // Off-diagonal mass below 1e-20 of the diagonal's (elements ~1e-10 relative) is
        // far finer than the 1e-2 eigenvalue cut-off needs; a tighter bound only added
        // sweeps (the solver was 13% of gyroid meshing time at 1e-30).
        let tiny = 1e-20 * diag.max(1e-300);
        if off <= tiny {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] * a[p][q] <= tiny * 1e-2 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // a ← Jᵀ a J with the rotation J in the (p, q) plane.
            for k in 0..3 {
                let akp = a[k][p];
                let akq = a[k][q];
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let apk = a[p][k];
                let aqk = a[q][k];
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in &mut v {
                let vp = row[p];
                let vq = row[q];
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(a: DVec3, b: [f64; 3]) -> bool {
        (a - DVec3::from(b)).abs().max_element() < 1e-9
    }

    fn add(q: &mut Qef, p: [f64; 3], n: [f64; 3]) {
        q.add(p.into(), DVec3::from(n).normalize());
    }

    const BIG: [f64; 3] = [1e9; 3];

    fn unbounded(q: &Qef) -> DVec3 {
        q.solve_in(-DVec3::from(BIG), DVec3::from(BIG))
    }

    #[test]
    fn corner_of_three_planes() {
        let mut q = Qef::default();
        add(&mut q, [0.3, 0.0, 0.0], [1.0, 0.0, 0.0]);
        add(&mut q, [0.0, 0.7, 0.0], [0.0, 1.0, 0.0]);
        add(&mut q, [0.0, 0.0, 0.2], [0.0, 0.0, 1.0]);
        assert!(near(q.solve(), [0.3, 0.7, 0.2]));
        assert!(near(unbounded(&q), [0.3, 0.7, 0.2]));
        assert!(q.error(DVec3::new(0.3, 0.7, 0.2)) < 1e-20);
    }

    #[test]
    fn flat_patch_stays_at_mass_point_in_plane() {
        let mut q = Qef::new(DVec3::new(5.0, 5.0, 5.0));
        for p in [
            [0.0, 0.0, 0.5],
            [1.0, 0.0, 0.5],
            [0.0, 1.0, 0.5],
            [1.0, 1.0, 0.5],
        ] {
            add(&mut q, p, [0.0, 0.0, 1.0]);
        }
        assert!(near(q.solve(), [0.5, 0.5, 0.5]));
    }

    #[test]
    fn nearly_parallel_normals_do_not_fly_off() {
        let mut q = Qef::default();
        add(&mut q, [0.0, 0.0, 0.5], [0.0, 0.0, 1.0]);
        let n = [1e-6, 0.0, (1.0f64 - 1e-12).sqrt()];
        add(&mut q, [1.0, 0.0, 0.5], n);
        let x = q.solve();
        assert!(x.abs().max_element() <= 1.0, "{x:?}");
    }

    #[test]
    fn merge_equals_adding_all_planes_whatever_the_origins() {
        let planes = [
            ([0.1, 0.2, 0.3], [1.0, 0.2, 0.0]),
            ([0.5, 0.1, 0.9], [0.0, 1.0, 0.3]),
            ([0.7, 0.6, 0.2], [0.2, 0.1, 1.0]),
            ([0.3, 0.8, 0.4], [1.0, 1.0, 0.0]),
        ];
        let mut all = Qef::new(DVec3::new(-3.0, 2.0, 7.0));
        let mut a = Qef::new(DVec3::new(0.0, 0.0, 0.0));
        let mut b = Qef::new(DVec3::new(100.0, -50.0, 3.0));
        for (i, (p, n)) in planes.iter().enumerate() {
            add(&mut all, *p, *n);
            add(if i % 2 == 0 { &mut a } else { &mut b }, *p, *n);
        }
        a.merge(&b);
        for x in [[0.0, 0.0, 0.0], [0.4, 0.4, 0.4], [1.0, -2.0, 3.0]] {
            let x = DVec3::from(x);
            assert!((a.error(x) - all.error(x)).abs() < 1e-9, "{x}");
        }
        assert!((a.mass_point() - all.mass_point()).length() < 1e-12);
        assert!((a.solve() - all.solve()).length() < 1e-9);
    }

    #[test]
    fn an_edge_clipping_the_box_corner_keeps_the_vertex_on_both_planes() {
        // Two planes meeting along a line that only clips the unit box near (0.9, 0.9, 0):
        // the free minimizer nearest the crossings' mass point lies below the box, and
        // clamping it would leave both planes; the box-constrained one stays on the line.
        let d = DVec3::ONE.normalize();
        let n1 = DVec3::new(1.0, -1.0, 0.0).normalize();
        let n2 = DVec3::new(1.0, 1.0, -2.0).normalize();
        let line = |t: f64| DVec3::new(0.9, 0.9, 0.0) + d * t;
        let mut q = Qef::default();
        for (t, s) in [(-0.2, 0.4), (0.0, 0.5), (0.05, 0.3)] {
            q.add(line(t) + n1.cross(d) * s, n1);
            q.add(line(t) - n2.cross(d) * s, n2);
        }
        let free = q.solve();
        assert!(
            free.min_element() < 0.0 || free.max_element() > 1.0,
            "{free}"
        );
        let x = q.solve_in(DVec3::ZERO, DVec3::ONE);
        assert!(
            x.cmpge(DVec3::ZERO).all() && x.cmple(DVec3::ONE).all(),
            "{x}"
        );
        assert!(q.error(x) < 1e-12, "{x}: error {}", q.error(x));
    }

    #[test]
    fn eigen_decomposition_reconstructs() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]];
        let (w, v) = eigen_sym(a);
        for i in 0..3 {
            for j in 0..3 {
                let r: f64 = (0..3).map(|k| v[i][k] * w[k] * v[j][k]).sum();
                assert!((r - a[i][j]).abs() < 1e-9);
            }
        }
    }
}
