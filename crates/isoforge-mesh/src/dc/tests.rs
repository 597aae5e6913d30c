//! Mesher tests on plain closures (no tape needed): every corner sign pattern of a cell and
//! of a pair of cells, across block boundaries, with and without NaN; shapes that break
//! meshers. Each mesh is checked by the crate's checker.

use isoforge_field::{Bounds, Grad, Interval, clip_grad, clip_interval, clip_value};

use super::sampler::Sampler;
use super::{MeshSettings, mesh_sampler_blocks, octree};
use crate::check::check;
use crate::mesh::Mesh;

type IntervalFn = Box<dyn Fn([Interval; 3]) -> Interval + Sync>;

/// A field from closures, clipped to the region by the same rules a tape is
/// (`isoforge_field::clip_*`); intervals are `ENTIRE` unless given, normals come from the
/// mesher's finite-difference fallback unless `nan_grad` is unset.
pub struct FnSampler<F: Fn([f64; 3]) -> f64 + Sync> {
    pub f: F,
    pub interval: Option<IntervalFn>,
    pub nan_grad: bool,
    /// The region; [`mesh_fn`] sets it from the settings.
    pub bounds: Bounds,
}

impl<F: Fn([f64; 3]) -> f64 + Sync> FnSampler<F> {
    pub fn new(f: F) -> Self {
        FnSampler {
            f,
            interval: None,
            nan_grad: true,
            bounds: Bounds::new([0.0; 3], [1.0; 3]).expect("unit box"),
        }
    }

    /// The unclipped gradient: NaN unless asked for, else central differences.
    fn raw_grad(&self, p: [f64; 3]) -> Grad {
        let v = (self.f)(p);
        if self.nan_grad {
            return Grad {
                v,
                d: [f64::NAN; 3],
            };
        }
        let h = 1e-6;
        let d = [0, 1, 2].map(|a| {
            let (mut q, mut r) = (p, p);
            q[a] += h;
            r[a] -= h;
            ((self.f)(q) - (self.f)(r)) / (2.0 * h)
        });
        Grad { v, d }
    }
}

/// Meshes a closure field over the settings' region.
fn mesh_fn<F: Fn([f64; 3]) -> f64 + Sync>(s: FnSampler<F>, settings: &MeshSettings) -> Mesh {
    mesh_fn_blocks(s, settings, octree::BLOCK_SHIFT)
}

/// Meshes a closure field with blocks of 2^`block_shift` cells.
fn mesh_fn_blocks<F: Fn([f64; 3]) -> f64 + Sync>(
    mut s: FnSampler<F>,
    settings: &MeshSettings,
    block_shift: u32,
) -> Mesh {
    s.bounds = settings.bounds;
    mesh_sampler_blocks(&s, settings, block_shift)
}

impl<F: Fn([f64; 3]) -> f64 + Sync> Sampler for FnSampler<F> {
    type Local = ();
    type Evals = ();
    fn evals(&self) {}
    fn root(&self) {}
    fn interval(&self, _: &mut (), _: &(), b: [Interval; 3]) -> Interval {
        let f = match &self.interval {
            Some(i) => i(b),
            None => Interval::ENTIRE,
        };
        clip_interval(&self.bounds, f, false, b)
    }
    fn narrow(&self, _: &mut (), _: &()) {}
    fn batch(&self, _: &mut (), _: &(), xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for i in 0..out.len() {
            let p = [xs[i], ys[i], zs[i]];
            out[i] = clip_value(&self.bounds, (self.f)(p), p);
        }
    }
    fn grad(&self, _: &mut (), _: &(), p: [f64; 3]) -> [f64; 4] {
        let g = clip_grad(&self.bounds, self.raw_grad(p), p);
        [g.v, g.d[0], g.d[1], g.d[2]]
    }
}

/// Checks the mesh with the crate's checker (closed, manifold, oriented; an empty mesh
/// passes, callers say when they expect one) and that vertex positions are distinct.
/// Returns the volume.
pub fn assert_closed_manifold(mesh: &Mesh, what: &str) -> f64 {
    if mesh.triangles.is_empty() {
        return 0.0;
    }
    let report = check(mesh);
    assert!(
        report.is_closed_manifold(),
        "{what}: {:?}",
        report.problems()
    );
    // STL has no shared vertices: readers weld by position, so positions must be distinct.
    let mut seen = std::collections::HashSet::new();
    for v in &mesh.vertices {
        assert!(
            seen.insert(v.map(f32::to_bits)),
            "{what}: two vertices at {v:?}"
        );
    }
    report.volume
}

fn settings(min: f64, max: f64, depth: u8) -> MeshSettings {
    MeshSettings::new(Bounds::new([min; 3], [max; 3]).unwrap(), depth)
}

/// Trilinear interpolation of values on the integer lattice 0..=16.
fn trilinear(values: &[f64], p: [f64; 3]) -> f64 {
    const S: usize = 17;
    let mut i = [0usize; 3];
    let mut t = [0.0; 3];
    for a in 0..3 {
        let c = p[a].clamp(0.0, 15.999_999);
        i[a] = c.floor() as usize;
        t[a] = c - i[a] as f64;
    }
    let at =
        |dx: usize, dy: usize, dz: usize| values[(i[0] + dx) + S * ((i[1] + dy) + S * (i[2] + dz))];
    let mut v = 0.0;
    for c in 0..8 {
        let (dx, dy, dz) = (c & 1, c >> 1 & 1, c >> 2 & 1);
        let w = (if dx == 1 { t[0] } else { 1.0 - t[0] })
            * (if dy == 1 { t[1] } else { 1.0 - t[1] })
            * (if dz == 1 { t[2] } else { 1.0 - t[2] });
        v += w * at(dx, dy, dz);
    }
    v
}

/// Meshes the lattice where the corners listed are given values and the rest are outside.
/// The region is [0, 16]³ at depth 4 (cells of 1, blocks of 8), so the cells at 7..9
/// straddle block boundaries on every axis.
fn mesh_lattice(corners: &[([usize; 3], f64)], nan_grad: bool) -> Mesh {
    let mut values = vec![1.0; 17 * 17 * 17];
    for &(g, v) in corners {
        values[g[0] + 17 * (g[1] + 17 * g[2])] = v;
    }
    let mut s = FnSampler::new(move |p| trilinear(&values, p));
    s.nan_grad = nan_grad;
    // Blocks of 8 cells, so that the cells at 7..9 straddle block boundaries.
    mesh_fn_blocks(s, &settings(0.0, 16.0, 4), 3)
}

fn corner_value(inside: bool, c: usize) -> f64 {
    // Varied magnitudes so crossings are not all at edge midpoints.
    if inside {
        -0.3 - 0.1 * c as f64
    } else {
        0.2 + 0.15 * c as f64
    }
}

/// Inside corners so deep that the middle of every ambiguous face is inside: every such
/// face is joined (`leaf::joined_faces`), where [`corner_value`] leaves most apart.
fn deep_corner_value(inside: bool, c: usize) -> f64 {
    if inside {
        -3.0 - 0.1 * c as f64
    } else {
        0.2 + 0.15 * c as f64
    }
}

#[test]
fn all_256_sign_patterns_of_a_cell_are_closed_manifold() {
    for value in [corner_value, deep_corner_value] {
        all_256_sign_patterns(value);
    }
}

fn all_256_sign_patterns(corner_value: fn(bool, usize) -> f64) {
    for pattern in 0..256usize {
        let corners: Vec<([usize; 3], f64)> = (0..8)
            .map(|c| {
                let g = [7 + (c & 1), 7 + (c >> 1 & 1), 7 + (c >> 2 & 1)];
                (g, corner_value(pattern >> c & 1 == 1, c))
            })
            .collect();
        let mesh = mesh_lattice(&corners, pattern % 2 == 0);
        let vol = assert_closed_manifold(&mesh, &format!("pattern {pattern}"));
        assert_eq!(mesh.triangles.is_empty(), pattern == 0, "pattern {pattern}");
        if pattern != 0 {
            assert!(vol > 0.0, "pattern {pattern}: volume {vol}");
        }
    }
}

#[test]
fn all_4096_sign_patterns_of_two_neighbouring_cells_are_closed_manifold() {
    for value in [corner_value, deep_corner_value] {
        all_4096_sign_patterns_of_two_cells(value);
    }
}

fn all_4096_sign_patterns_of_two_cells(corner_value: fn(bool, usize) -> f64) {
    // Cells [7,8] and [8,9] along x, on the boundary between two blocks; then the same
    // along y and z.
    for axis in 0..3 {
        for pattern in 0..4096usize {
            // Corner c of the 3x2x2 block of corners: along `axis` 0..=2, others 0..=1.
            let corners: Vec<([usize; 3], f64)> = (0..12)
                .map(|c| {
                    let (u, v, w) = (c % 3, (c / 3) % 2, c / 6);
                    let mut g = [7; 3];
                    g[axis] += u;
                    g[(axis + 1) % 3] += v;
                    g[(axis + 2) % 3] += w;
                    (g, corner_value(pattern >> c & 1 == 1, c % 8))
                })
                .collect();
            let mesh = mesh_lattice(&corners, true);
            let vol = assert_closed_manifold(&mesh, &format!("axis {axis} pattern {pattern}"));
            if pattern != 0 {
                assert!(vol > 0.0, "axis {axis} pattern {pattern}: volume {vol}");
            }
        }
    }
}

#[test]
fn nan_corners_count_as_outside() {
    // Three states per corner: inside, outside, NaN; 3^8 patterns on one cell.
    for code in 0..6561usize {
        let mut k = code;
        let corners: Vec<([usize; 3], f64)> = (0..8)
            .map(|c| {
                let state = k % 3;
                k /= 3;
                let g = [7 + (c & 1), 7 + (c >> 1 & 1), 7 + (c >> 2 & 1)];
                let v = match state {
                    0 => corner_value(true, c),
                    1 => corner_value(false, c),
                    _ => f64::NAN,
                };
                (g, v)
            })
            .collect();
        let mesh = mesh_lattice(&corners, false);
        assert_closed_manifold(&mesh, &format!("nan code {code}"));
        for v in &mesh.vertices {
            assert!(
                v.iter().all(|c| c.is_finite() && (6.0..=10.0).contains(c)),
                "{v:?}"
            );
        }
    }
}

fn sphere_interval(b: [Interval; 3]) -> Interval {
    b[0].sqr() + b[1].sqr() + b[2].sqr() - Interval::try_from((1.0, 1.0)).unwrap()
}

#[test]
fn sphere_volume_and_pruning() {
    for depth in [3u8, 4, 5, 6] {
        let mut s = FnSampler::new(|p: [f64; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.0);
        s.interval = Some(Box::new(sphere_interval));
        s.nan_grad = false;
        let mesh = mesh_fn(s, &settings(-1.5, 1.5, depth));
        let vol = assert_closed_manifold(&mesh, &format!("sphere depth {depth}"));
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        let tol = if depth >= 6 { 0.02 } else { 0.15 };
        assert!((vol - exact).abs() < tol * exact, "depth {depth}: {vol}");
        for v in &mesh.vertices {
            let r = v.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt();
            assert!(
                (r - 1.0).abs() < 3.0 / f64::from(1u32 << depth),
                "depth {depth}: r {r}"
            );
        }
    }
}

#[test]
fn model_larger_than_region_is_capped() {
    // A sphere of radius 2 in [-1, 1]³: the result is the cube, capped on all six sides.
    let mut s = FnSampler::new(|p: [f64; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 4.0);
    s.nan_grad = false;
    let mesh = mesh_fn(s, &settings(-1.0, 1.0, 5));
    let vol = assert_closed_manifold(&mesh, "capped");
    assert!((vol - 8.0).abs() < 0.01, "{vol}");
}

#[test]
fn thin_plate_and_touching_spheres() {
    // A plate 0.01 thick in cells of 0.1: no corner is inside, so nothing (but valid).
    let s = FnSampler::new(|p: [f64; 3]| p[2].abs() - 0.005 + 0.0 * p[0]);
    let mesh = mesh_fn(s, &settings(-1.0, 1.0, 4));
    assert_closed_manifold(&mesh, "thin plate");
    // A plate 0.15 thick with its faces between lattice planes, tilted.
    let s = FnSampler::new(|p: [f64; 3]| (p[2] + 0.3 * p[0]).abs() - 0.07);
    let mesh = mesh_fn(s, &settings(-1.0, 1.0, 5));
    let vol = assert_closed_manifold(&mesh, "tilted plate");
    assert!(vol > 0.0);
    // Two spheres touching at the origin (a lattice corner and a non-corner).
    for shift in [0.0, 0.013] {
        let s = FnSampler::new(move |p: [f64; 3]| {
            let a = (p[0] - 0.5 - shift).powi(2) + p[1].powi(2) + p[2].powi(2) - 0.25;
            let b = (p[0] + 0.5 - shift).powi(2) + p[1].powi(2) + p[2].powi(2) - 0.25;
            a.min(b)
        });
        let mesh = mesh_fn(s, &settings(-1.0, 1.0, 5));
        assert_closed_manifold(&mesh, "touching spheres");
    }
}

#[test]
fn nan_half_space_and_cone_through_axis() {
    // sqrt(x) − 0.5 is NaN for x < 0 (outside there): a slab 0 ≤ x < 0.25, capped.
    let s = FnSampler::new(|p: [f64; 3]| p[0].sqrt() - 0.5);
    let mesh = mesh_fn(s, &settings(-1.0, 1.0, 5));
    let vol = assert_closed_manifold(&mesh, "sqrt(x)");
    assert!((vol - 1.0).abs() < 0.15, "{vol}");
    // sqrt(x²+y²) − (1 − |z|)/2: a double cone, gradient undefined on the z axis.
    let s =
        FnSampler::new(|p: [f64; 3]| (p[0] * p[0] + p[1] * p[1]).sqrt() - (1.0 - p[2].abs()) / 2.0);
    let mut s2 = s;
    s2.nan_grad = false;
    let mesh = mesh_fn(s2, &settings(-1.0, 1.0, 5));
    assert_closed_manifold(&mesh, "double cone");
}

#[test]
fn gyroid_sphere_is_closed_manifold() {
    let gyroid = |p: [f64; 3]| {
        let (x, y, z) = (8.0 * p[0], 8.0 * p[1], 8.0 * p[2]);
        let g = x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos();
        (g.abs() - 0.3).max(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.0)
    };
    for (depth, lo, hi) in [(5u8, 0.2, 1.0), (7, 0.79, 0.84)] {
        let mut s = FnSampler::new(gyroid);
        s.nan_grad = false;
        let mesh = mesh_fn(s, &settings(-1.5, 1.5, depth));
        let vol = assert_closed_manifold(&mesh, &format!("gyroid depth {depth}"));
        // The sheet is about one cell thick at depth 5: a thinner volume is expected there;
        // the reference (finest meshes) is 0.817.
        assert!(vol > lo && vol < hi, "depth {depth}: {vol}");
    }
}

/// The sign-changing edges of the lattice of `settings` for a field (inside: negative).
fn crossing_edges(f: impl Fn([f64; 3]) -> f64, settings: &MeshSettings) -> usize {
    let n = 1usize << settings.depth;
    let cell = settings.cell();
    let lo = settings.bounds.min;
    let inside = |i: [usize; 3]| f([0, 1, 2].map(|a| lo[a] + cell * i[a] as f64)) < 0.0;
    let mut count = 0;
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                for a in 0..3 {
                    let mut q = [i, j, k];
                    q[a] += 1;
                    if q[a] <= n && inside([i, j, k]) != inside(q) {
                        count += 1;
                    }
                }
            }
        }
    }
    count
}

#[test]
fn tolerance_zero_is_the_uniform_mesh() {
    // Every leaf a finest cell: each crossing lattice edge gives one quad, two triangles
    // (the sphere meets no cell face in the ambiguous pattern at this depth), and every
    // triangle joins vertices of neighbouring cells.
    let sphere = |p: [f64; 3]| p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.0;
    let mut uniform = settings(-1.5, 1.5, 5);
    uniform.tolerance = Some(0.0);
    let edges = crossing_edges(sphere, &uniform);
    let mut s = FnSampler::new(sphere);
    s.nan_grad = false;
    let mesh = mesh_fn(s, &uniform);
    assert_closed_manifold(&mesh, "uniform sphere");
    assert_eq!(mesh.triangles.len(), 2 * edges);
    let longest = 2.0 * 3f64.sqrt() * uniform.cell();
    for t in &mesh.triangles {
        for e in 0..3 {
            let (p, q) = (
                mesh.vertices[t[e] as usize],
                mesh.vertices[t[(e + 1) % 3] as usize],
            );
            let d = (0..3)
                .map(|a| f64::from(p[a] - q[a]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d <= longest, "an edge of {d} in a uniform mesh");
        }
    }
    // The default tolerance merges: fewer triangles, every vertex still on the sphere
    // within the tolerance.
    let merged_settings = settings(-1.5, 1.5, 5);
    let mut s = FnSampler::new(sphere);
    s.nan_grad = false;
    let merged = mesh_fn(s, &merged_settings);
    assert_closed_manifold(&merged, "merged sphere");
    assert!(
        merged.triangles.len() * 2 < mesh.triangles.len(),
        "{} vs {}",
        merged.triangles.len(),
        mesh.triangles.len()
    );
    let tolerance = merged_settings.effective_tolerance();
    for v in &merged.vertices {
        let r = v.iter().map(|c| f64::from(*c).powi(2)).sum::<f64>().sqrt();
        assert!((r - 1.0).abs() <= tolerance, "r {r}, tolerance {tolerance}");
    }
}

#[test]
fn every_tolerance_keeps_shapes_closed() {
    // Large tolerances merge as far as the topology test allows: the test, not the
    // tolerance, is then all that keeps the mesh manifold.
    let gyroid = |p: [f64; 3]| {
        let (x, y, z) = (6.0 * p[0], 6.0 * p[1], 6.0 * p[2]);
        let g = x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos();
        (g.abs() - 0.4).max(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1.0)
    };
    for cells in [0.0, 0.05, 0.5, 2.0, 20.0, f64::INFINITY] {
        for block_shift in [2, 4] {
            let mut st = settings(-1.3, 1.2, 6);
            st.tolerance = Some(cells * st.cell());
            let mut s = FnSampler::new(gyroid);
            s.nan_grad = false;
            let mesh = mesh_fn_blocks(s, &st, block_shift);
            let vol = assert_closed_manifold(&mesh, &format!("tolerance {cells} cells"));
            assert!(
                vol > 0.5 && vol < 1.3,
                "tolerance {cells} cells: volume {vol}"
            );
        }
    }
}

#[test]
fn full_region_whose_last_lattice_plane_rounds_inside() {
    // The region is not a cube: along y the lattice's last plane (origin + 64 cells) lands
    // one rounding error inside the region's wall, so the interval calls the blocks under
    // it full while that plane, owned by no block, counts as outside. A model filling the
    // region once lost its cap there (edges without their four cells).
    let bounds = Bounds::new(
        [-0.8, -1.218_528_582_133_456_4, -0.8],
        [0.8, 1.058_524_001_171_898_4, 0.8],
    )
    .unwrap();
    for tolerance in [Some(0.0), None] {
        let mut st = MeshSettings::new(bounds, 6);
        st.tolerance = tolerance;
        let mut s = FnSampler::new(|_p: [f64; 3]| -1.0);
        s.interval = Some(Box::new(|_b| Interval::try_from((-1.0, -1.0)).unwrap()));
        let mesh = mesh_fn(s, &st);
        let vol = assert_closed_manifold(&mesh, "the region filled");
        assert!((vol - 1.6 * 1.6 * 2.277).abs() < 0.01, "{vol}");
    }
}
