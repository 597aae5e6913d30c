//! The quadratic error function of dual contouring (Ju, Losasso, Schaefer, Warren 2002):
//! the point that best fits the planes through a patch's edge crossings, found by a
//! truncated pseudo-inverse around the crossings' mass point, so that a flat or curved
//! patch (rank 1 or 2) keeps its vertex near the middle of its crossings instead of
//! sliding along the free directions.

use glam::{DMat3, DVec3};

/// Singular values below this fraction of the largest are dropped. 0.1 is the usual
/// choice (Ju et al.; fidget and libfive use similar cut-offs): it keeps true corners
/// (three well separated normals) and treats nearly parallel normals as one plane.
const SINGULAR_CUTOFF: f64 = 0.1;

/// Accumulates plane constraints (point, unit normal).
#[derive(Clone, Debug)]
pub struct Qef {
    /// AᵀA = Σ n nᵀ.
    ata: DMat3,
    sum_p: DVec3,
    count: usize,
    planes: Vec<(DVec3, DVec3)>,
}

impl Default for Qef {
    /// No planes. (Not derived: glam's default matrix is the identity, not zero.)
    fn default() -> Self {
        Qef {
            ata: DMat3::ZERO,
            sum_p: DVec3::ZERO,
            count: 0,
            planes: Vec::new(),
        }
    }
}

impl Qef {
    /// Clears for reuse (keeps its buffer).
    pub fn clear(&mut self) {
        self.ata = DMat3::ZERO;
        self.sum_p = DVec3::ZERO;
        self.count = 0;
        self.planes.clear();
    }

    /// Adds the plane through `p` with unit normal `n`.
    pub fn add(&mut self, p: DVec3, n: DVec3) {
        // The outer product n nᵀ, column j being n · n[j].
        self.ata += DMat3::from_cols(n * n.x, n * n.y, n * n.z);
        self.sum_p += p;
        self.count += 1;
        self.planes.push((p, n));
    }

    /// The mean of the crossings.
    pub fn mass_point(&self) -> DVec3 {
        self.sum_p / self.count.max(1) as f64
    }

    /// The minimizer, or the mass point when nothing better is defined.
    pub fn solve(&self) -> DVec3 {
        if self.count == 0 {
            return DVec3::ZERO;
        }
        let m = self.sum_p / self.count as f64;
        // Aᵀb around the mass point: Σ n (n · (p − m)).
        let mut atb = DVec3::ZERO;
        for (p, n) in &self.planes {
            atb += *n * n.dot(*p - m);
        }
        // AᵀA is symmetric: its columns are its rows.
        let (values, vectors) = eigen_sym(self.ata.to_cols_array_2d());
        let max = values.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        if max <= 0.0 || !max.is_finite() {
            return m;
        }
        // AᵀA's eigenvalues are the squared singular values of A.
        let cut = max * SINGULAR_CUTOFF * SINGULAR_CUTOFF;
        let mut x = m;
        for k in 0..3 {
            if values[k].abs() < cut {
                continue;
            }
            let v = DVec3::new(vectors[0][k], vectors[1][k], vectors[2][k]);
            x += v * (v.dot(atb) / values[k]);
        }
        if x.is_finite() { x } else { m }
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
        q.add(p.into(), n.into());
    }

    #[test]
    fn corner_of_three_planes() {
        let mut q = Qef::default();
        add(&mut q, [0.3, 0.0, 0.0], [1.0, 0.0, 0.0]);
        add(&mut q, [0.0, 0.7, 0.0], [0.0, 1.0, 0.0]);
        add(&mut q, [0.0, 0.0, 0.2], [0.0, 0.0, 1.0]);
        assert!(near(q.solve(), [0.3, 0.7, 0.2]));
    }

    #[test]
    fn flat_patch_stays_at_mass_point_in_plane() {
        let mut q = Qef::default();
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
