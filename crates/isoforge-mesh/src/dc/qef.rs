//! The quadratic error function of dual contouring (Ju, Losasso, Schaefer, Warren 2002):
//! the point that best fits the planes through a patch's edge crossings, found by a
//! truncated pseudo-inverse around the crossings' mass point, so that a flat or curved
//! patch (rank 1 or 2) keeps its vertex near the middle of its crossings instead of
//! sliding along the free directions.

/// Singular values below this fraction of the largest are dropped. 0.1 is the usual
/// choice (Ju et al.; fidget and libfive use similar cut-offs): it keeps true corners
/// (three well separated normals) and treats nearly parallel normals as one plane.
const SINGULAR_CUTOFF: f64 = 0.1;

/// Accumulates plane constraints (point, unit normal).
#[derive(Clone, Debug, Default)]
pub struct Qef {
    ata: [[f64; 3]; 3],
    sum_p: [f64; 3],
    count: usize,
    planes: Vec<([f64; 3], [f64; 3])>,
}

impl Qef {
    /// Clears for reuse (keeps its buffer).
    pub fn clear(&mut self) {
        self.ata = [[0.0; 3]; 3];
        self.sum_p = [0.0; 3];
        self.count = 0;
        self.planes.clear();
    }

    /// Adds the plane through `p` with unit normal `n`.
    pub fn add(&mut self, p: [f64; 3], n: [f64; 3]) {
        for i in 0..3 {
            for j in 0..3 {
                self.ata[i][j] += n[i] * n[j];
            }
            self.sum_p[i] += p[i];
        }
        self.count += 1;
        self.planes.push((p, n));
    }

    /// The minimizer, or the mass point when nothing better is defined.
    pub fn solve(&self) -> [f64; 3] {
        if self.count == 0 {
            return [0.0; 3];
        }
        let m = self.sum_p.map(|s| s / self.count as f64);
        // Aᵀb around the mass point: Σ n (n · (p − m)).
        let mut atb = [0.0; 3];
        for (p, n) in &self.planes {
            let d = (0..3).map(|i| n[i] * (p[i] - m[i])).sum::<f64>();
            for i in 0..3 {
                atb[i] += n[i] * d;
            }
        }
        let (values, vectors) = eigen_sym(self.ata);
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
            let v = [vectors[0][k], vectors[1][k], vectors[2][k]];
            let proj = (0..3).map(|i| v[i] * atb[i]).sum::<f64>() / values[k];
            for i in 0..3 {
                x[i] += v[i] * proj;
            }
        }
        if x.iter().all(|c| c.is_finite()) {
            x
        } else {
            m
        }
    }
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 matrix, by cyclic Jacobi
/// rotations: robust for the rank-deficient matrices QEFs give, and 3×3 converges in a
/// handful of sweeps.
pub fn eigen_sym(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..24 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-30 * diag.max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
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

    fn near(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9)
    }

    #[test]
    fn corner_of_three_planes() {
        let mut q = Qef::default();
        q.add([0.3, 0.0, 0.0], [1.0, 0.0, 0.0]);
        q.add([0.0, 0.7, 0.0], [0.0, 1.0, 0.0]);
        q.add([0.0, 0.0, 0.2], [0.0, 0.0, 1.0]);
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
            q.add(p, [0.0, 0.0, 1.0]);
        }
        assert!(near(q.solve(), [0.5, 0.5, 0.5]));
    }

    #[test]
    fn nearly_parallel_normals_do_not_fly_off() {
        let mut q = Qef::default();
        q.add([0.0, 0.0, 0.5], [0.0, 0.0, 1.0]);
        let n = [1e-6, 0.0, (1.0f64 - 1e-12).sqrt()];
        q.add([1.0, 0.0, 0.5], n);
        let x = q.solve();
        assert!(x.iter().all(|c| c.abs() <= 1.0), "{x:?}");
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
