//! How far a mesh is from the surface it stands for, measured by the field itself.
//!
//! Each triangle is sampled at its corners, the middles of its edges and its centroid (the
//! points of a degree-3 quadrature rule, whose weights give the mean). At each point the
//! distance to the surface is found along the field's gradient: the first-order estimate
//! |F| / |∇F| says how far to look, a sign change of F on that line is bracketed and
//! bisected, and the distance to it is the answer. A point whose line finds no sign change
//! close by (just outside a convex edge, where the nearest surface is not along the
//! gradient) keeps the first-order estimate.
//!
//! It also counts the triangles that face against the field's gradient at their centroid:
//! folds, which neither the distance nor a check of the mesh alone reveals.
//!
//! Given a width ([`deviation_where_wide`]), the points beyond a tolerance are told apart
//! by how wide the model is where they miss (`narrow.rs`): a lattice of cells cannot follow
//! a solid or a gap narrower than two of its cells, so a mesh's promise holds where the
//! model is wider than that.
//!
//! [`DeviationSink`] (`stream.rs`) measures a mesh the same way as it passes on its way to
//! a file, a chunk of triangles at a time. A long tape is run narrowed to the small cube
//! around each group of points (`distances_grouped`), as the mesher runs it per block.
//!
//! ```
//! use isoforge_field::{Bounds, ClippedField, Shape};
//! use isoforge_mesh::{deviation, mesh_shape, MeshSettings};
//! let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
//! let ball = x.square() + y.square() + z.square() - 1.0;
//! let region = Bounds::new([-1.5; 3], [1.5; 3]).unwrap();
//! let mesh = mesh_shape(&ball, &MeshSettings::new(region, 5));
//! let d = deviation(&mesh, &ClippedField::new(&ball, region));
//! assert!(d.max < 0.05 && d.mean <= d.max);
//! ```

use glam::DVec3;
use isoforge_field::{BatchEval, ClippedField, GradEval, Interval, IntervalEval};
use rayon::prelude::*;

use crate::mesh::Mesh;

mod narrow;
mod stream;

pub use stream::DeviationSink;

/// Points per batch: large enough for the batch evaluator to pay off.
const CHUNK: usize = 4096;
/// Bisection rounds on a bracket along the gradient line: 2^-24 of a bracket a few
/// first-order distances long (a cell at most), far below f32's resolution of a vertex's
/// coordinates. Each round is a field evaluation per point, the bulk of the measure's
/// cost: 40 rounds took about a quarter more time (spiky_ball at depth 8) for digits no
/// f32 mesh has.
const BISECTIONS: usize = 24;
/// Bisection rounds on a bracket found searching around a point (`refine_largest`).
const AROUND_BISECTIONS: usize = 20;
/// How far along the gradient line to look for the surface, in multiples of the
/// first-order estimate (a smooth field's surface is found well within 2).
const SEARCH: [f64; 3] = [1.25, 2.0, 4.0];

/// The distance between a mesh and a model's surface.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Deviation {
    /// The largest distance of a sample point from the surface.
    pub max: f64,
    /// The mean distance, weighted by area.
    pub mean: f64,
    /// Where the largest distance is.
    pub at: [f64; 3],
    /// Points sampled.
    pub samples: usize,
    /// Of those, points whose distance is the first-order estimate (no sign change found
    /// on the gradient line nearby).
    pub estimated: usize,
    /// With a tolerance (`deviation_beyond`): the share of the mesh's area farther from
    /// the surface than it (by the quadrature weights of its sample points), 0 to 1.
    pub area_beyond: f64,
    /// With a tolerance: the sample points farther than it.
    pub points_beyond: usize,
    /// With a tolerance: whether every point counted beyond it was searched around (see
    /// `refine_largest`); if not, the counts beyond are upper bounds.
    pub beyond_exact: bool,
    /// Triangles whose normal is more than 90° from the field's gradient at their centroid:
    /// folds, where the mesh doubles back on itself (a closed, manifold mesh can still
    /// have them, and checkers that look at the mesh alone do not see them).
    pub facing_against: usize,
    /// Their share of the mesh's area, 0 to 1.
    pub area_facing_against: f64,
    /// With a width ([`deviation_where_wide`]): the points beyond the tolerance where the
    /// model (the solid, or the gap outside it) is narrower than the width (`narrow.rs`
    /// says how that is measured).
    pub points_beyond_narrow: usize,
    /// Their share of the mesh's area, 0 to 1 (a part of `area_beyond`).
    pub area_beyond_narrow: f64,
    /// The largest distance of a point not counted narrow: the largest distance where
    /// the model is at least the width wide (with no width asked for, `max`).
    pub max_wide: f64,
    /// Where that is.
    pub max_wide_at: [f64; 3],
}

impl Deviation {
    /// Whether the mesh keeps within `tolerance` of the surface everywhere sampled.
    pub fn holds(&self, tolerance: f64) -> bool {
        self.max <= tolerance
    }

    /// Whether it keeps within `tolerance` wherever the model is at least the width asked
    /// of [`deviation_where_wide`] wide.
    pub fn holds_where_wide(&self, tolerance: f64) -> bool {
        self.max_wide <= tolerance
    }
}

/// The distance from the mesh to the field's surface (see the module doc).
pub fn deviation(mesh: &Mesh, field: &ClippedField) -> Deviation {
    deviation_beyond(mesh, field, f64::INFINITY)
}

/// As [`deviation`], and how much of the mesh is farther than `tolerance` from the surface
/// (`area_beyond`, `points_beyond`): every sample point whose first distance is over it is
/// searched around, so those it counts are truly over (up to a limit of points searched;
/// `beyond_exact` says whether it was reached).
pub fn deviation_beyond(mesh: &Mesh, field: &ClippedField, tolerance: f64) -> Deviation {
    deviation_where_wide(mesh, field, tolerance, 0.0)
}

/// As [`deviation_beyond`], and of the points beyond `tolerance`, those where the model is
/// narrower than `width` counted apart (`points_beyond_narrow`, `area_beyond_narrow`,
/// `max_wide`; `narrow.rs` says how the width is measured). A width of 0 counts none.
pub fn deviation_where_wide(
    mesh: &Mesh,
    field: &ClippedField,
    tolerance: f64,
    width: f64,
) -> Deviation {
    if !mesh.has_valid_indices() || mesh.triangles.is_empty() {
        return Deviation {
            beyond_exact: true,
            ..Deviation::default()
        };
    }
    let points: Vec<[f64; 3]> = mesh
        .triangles
        .par_iter()
        .flat_map_iter(|&t| sample_points(mesh.corners(t)))
        .collect();
    let mut found = distances_nearby(field, &points);
    let beyond_exact = refine_largest(field, &points, &mut found, tolerance);
    let narrow = narrow::beyond_and_narrow(field, &points, &found, tolerance, width);
    let mut out = Deviation {
        beyond_exact,
        ..Deviation::default()
    };
    let mut sums = Sums::default();
    for (ti, &t) in mesh.triangles.iter().enumerate() {
        let first = SAMPLES * ti;
        sums.add(
            &mut out,
            tolerance,
            mesh.corners(t),
            &points[first..first + SAMPLES],
            &found[first..first + SAMPLES],
            |k| narrow.get(first + k) == Some(&true),
        );
    }
    sums.finish(&mut out);
    let against: Vec<f64> = mesh
        .triangles
        .par_iter()
        .map_init(GradEval::new, |grad, &t| {
            let [a, b, c] = mesh.corners(t);
            let n = (b - a).cross(c - a);
            let g = field.grad(grad, ((a + b + c) / 3.0).to_array());
            if n.dot(DVec3::from(g.d)) < 0.0 {
                n.length()
            } else {
                -1.0
            }
        })
        .filter(|&twice| twice >= 0.0)
        .collect();
    out.facing_against = against.len();
    out.area_facing_against = if sums.area > 0.0 {
        against.iter().fold(0.0, |s, x| s + x) / sums.area
    } else {
        0.0
    };
    out
}

/// The farthest of `points` from the surface, and its distance, measured as
/// [`deviation`] measures a mesh's sample points: along the gradient line, and the largest
/// searched around for a nearer surface until the largest left is one searched (so a few
/// points are searched, not every one over a tolerance). Only a distance to a point of the
/// surface found counts: a point whose gradient line and search around found none keeps
/// just the first-order estimate |F| / |∇F|, which where the field is no distance (an
/// `offset` of a gyroid, a smooth blend) can read millimetres where the surface is a sheet
/// too thin for the search's steps to see; such points are left out. `None` when no point
/// is left (or after [`FARTHEST_ROUNDS`] such points in a row).
pub fn farthest(field: &ClippedField, points: &[[f64; 3]]) -> Option<(f64, [f64; 3])> {
    let mut found = distances_nearby(field, points);
    for _ in 0..FARTHEST_ROUNDS {
        refine_largest(field, points, &mut found, f64::INFINITY);
        let (i, top) = found
            .iter()
            .enumerate()
            .filter(|(_, f)| f.d.is_finite() && f.d > 0.0)
            .max_by(|a, b| a.1.d.total_cmp(&b.1.d))?;
        if !top.estimated {
            return Some((top.d, points[i]));
        }
        found[i].d = 0.0;
    }
    None
}

/// The points of `points` farther than `tolerance` from the surface, with their distances,
/// measured as [`deviation_beyond`] measures a mesh's sample points: along the gradient
/// line, and each one over the tolerance searched around for a nearer surface (up to a
/// limit of points searched). A point with nothing better than the first-order estimate
/// counts with it, as it counts in [`Deviation::max`].
pub fn beyond(field: &ClippedField, points: &[[f64; 3]], tolerance: f64) -> Vec<([f64; 3], f64)> {
    let mut found = distances_nearby(field, points);
    refine_largest(field, points, &mut found, tolerance);
    points
        .iter()
        .zip(found)
        .filter(|(_, f)| f.d > tolerance)
        .map(|(p, f)| (*p, f.d))
        .collect()
}

/// Points whose distance is only an estimate left out of [`farthest`] at most, one a round.
const FARTHEST_ROUNDS: usize = 16;

/// Sample points per triangle.
const SAMPLES: usize = 7;
/// The degree-3 rule on a triangle, in the order of [`sample_points`]: corners 3/60, edge
/// middles 8/60, centroid 27/60.
const WEIGHTS: [f64; SAMPLES] = [
    3.0 / 60.0,
    3.0 / 60.0,
    3.0 / 60.0,
    8.0 / 60.0,
    8.0 / 60.0,
    8.0 / 60.0,
    27.0 / 60.0,
];

/// A triangle's sample points: its corners, the middles of its edges, its centroid.
fn sample_points([a, b, c]: [DVec3; 3]) -> [[f64; 3]; SAMPLES] {
    [
        a,
        b,
        c,
        (a + b) * 0.5,
        (b + c) * 0.5,
        (c + a) * 0.5,
        (a + b + c) / 3.0,
    ]
    .map(|p| p.to_array())
}

/// The area-weighted sums behind a [`Deviation`]'s mean and shares, triangle by triangle.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    /// Twice the area, times the weighted mean distance, summed.
    weighted: f64,
    /// Twice the area.
    area: f64,
    /// Twice the area beyond the tolerance (by the weights of the points beyond).
    beyond: f64,
    /// Of that, where the model is narrow.
    beyond_narrow: f64,
}

impl Sums {
    /// Counts one triangle (`corners`) whose sample points and their distances are
    /// `points` and `found`; `narrow(k)` says whether point k is beyond and narrow.
    fn add(
        &mut self,
        out: &mut Deviation,
        tolerance: f64,
        [a, b, c]: [DVec3; 3],
        points: &[[f64; 3]],
        found: &[Found],
        narrow: impl Fn(usize) -> bool,
    ) {
        let twice = (b - a).cross(c - a).length();
        let mut sum = 0.0;
        for (k, &weight) in WEIGHTS.iter().enumerate() {
            let Found { d, estimated, .. } = found[k];
            out.samples += 1;
            out.estimated += usize::from(estimated);
            sum += weight * d;
            if d > tolerance {
                out.points_beyond += 1;
                self.beyond += weight * twice;
            }
            if d > out.max {
                out.max = d;
                out.at = points[k];
            }
            if narrow(k) {
                out.points_beyond_narrow += 1;
                self.beyond_narrow += weight * twice;
            } else if d > out.max_wide {
                out.max_wide = d;
                out.max_wide_at = points[k];
            }
        }
        self.weighted += sum * twice;
        self.area += twice;
    }

    /// Puts the mean and the shares into `out`.
    fn finish(&self, out: &mut Deviation) {
        let share = |x: f64| if self.area > 0.0 { x / self.area } else { 0.0 };
        out.mean = share(self.weighted);
        out.area_beyond = share(self.beyond);
        out.area_beyond_narrow = share(self.beyond_narrow);
    }
}

/// A sample point's distance to the surface.
#[derive(Clone, Copy, Debug, Default)]
struct Found {
    /// The distance.
    d: f64,
    /// Whether it is the first-order estimate (no sign change found nearby).
    estimated: bool,
    /// The unit direction in which the surface was found that near (zero if none).
    toward: DVec3,
}

/// Points evaluated together, coordinate by coordinate, the buffers kept between calls.
#[derive(Default)]
struct Batch {
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    values: Vec<f64>,
    eval: Option<BatchEval>,
}

impl Batch {
    /// The field at each of `points`, in order.
    fn eval(&mut self, field: &ClippedField, points: impl IntoIterator<Item = DVec3>) -> &[f64] {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        for q in points {
            self.xs.push(q.x);
            self.ys.push(q.y);
            self.zs.push(q.z);
        }
        self.values.clear();
        self.values.resize(self.xs.len(), 0.0);
        let eval = self.eval.get_or_insert_with(BatchEval::new);
        field.batch(eval, &self.xs, &self.ys, &self.zs, &mut self.values);
        &self.values
    }
}

/// Directions searched around the points with the largest distances.
const DIRECTIONS: usize = 96;
/// Steps along each direction, out to the distance known so far.
const STEPS: usize = 12;
/// At most this many points are searched around (the search is about a thousand
/// evaluations a point).
const REFINE_LIMIT: usize = 50_000;

/// Tightens the largest distances. The gradient line is not the shortest way to the
/// surface near a crease (two surfaces meeting at an angle): a point just inside a sharp
/// edge looks along one surface's gradient and misses the other surface beside it. Every
/// distance found is an upper bound (a point of the surface that far away was found), so
/// the points are taken largest first and searched around in many directions for a nearer
/// sign change; once the largest distance left is one already searched, it is the
/// maximum. Points over `floor` are all searched (so that a count of points beyond a
/// tolerance counts none the search would have brought under it); returns false if the
/// limit on points searched ended that first.
fn refine_largest(
    field: &ClippedField,
    points: &[[f64; 3]],
    found: &mut [Found],
    floor: f64,
) -> bool {
    use std::cmp::Ordering;
    use std::collections::BinaryHeap;
    #[derive(PartialEq)]
    struct Item(f64, usize, bool);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Item {
        fn cmp(&self, other: &Self) -> Ordering {
            self.0.total_cmp(&other.0)
        }
    }
    // Directions spread evenly over the sphere (a Fibonacci lattice).
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let dirs: Vec<DVec3> = (0..DIRECTIONS)
        .map(|i| {
            let z = 1.0 - (2 * i + 1) as f64 / DIRECTIONS as f64;
            let r = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            DVec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect();
    let mut heap: BinaryHeap<Item> = found
        .iter()
        .enumerate()
        .filter(|(_, f)| f.d > 0.0 && f.d.is_finite())
        .map(|(i, f)| Item(f.d, i, false))
        .collect();
    let mut batch = Batch::default();
    let mut searched = 0;
    while let Some(Item(d, i, done)) = heap.pop() {
        if done {
            if d <= floor {
                break;
            }
            continue;
        }
        if searched == REFINE_LIMIT {
            return d <= floor;
        }
        searched += 1;
        let p = DVec3::from(points[i]);
        let inside = batch.eval(field, [p])[0] < 0.0;
        let f = batch.eval(
            field,
            dirs.iter()
                .flat_map(|&u| (1..=STEPS).map(move |k| p + u * (d * k as f64 / STEPS as f64))),
        );
        // Per direction, the first step past a sign change: a bracket to bisect.
        let mut brackets: Vec<(DVec3, f64, f64)> = Vec::new();
        for (j, &u) in dirs.iter().enumerate() {
            if let Some(k) = (0..STEPS).find(|&k| (f[j * STEPS + k] < 0.0) != inside) {
                let step = d / STEPS as f64;
                brackets.push((u, step * k as f64, step * (k + 1) as f64));
            }
        }
        for _ in 0..AROUND_BISECTIONS {
            let mids = brackets
                .iter()
                .map(|&(u, lo, hi)| p + u * (0.5 * (lo + hi)));
            let f = batch.eval(field, mids);
            for (b, &v) in brackets.iter_mut().zip(f.iter()) {
                let mid = 0.5 * (b.1 + b.2);
                if (v < 0.0) != inside {
                    b.2 = mid;
                } else {
                    b.1 = mid;
                }
            }
        }
        let nearest = brackets.iter().min_by(|a, b| a.2.total_cmp(&b.2));
        if let Some(&(u, _, hi)) = nearest.filter(|b| b.2 < d) {
            found[i] = Found {
                d: hi,
                estimated: false,
                toward: u,
            };
        }
        heap.push(Item(found[i].d, i, true));
    }
    true
}

/// The region's longest side over this: the side of the cubes whose points are measured
/// with one narrowed field.
const GROUPS: f64 = 16.0;
/// The longest side over this: how far around its cube a group's field is narrowed, so
/// the searches of points near the surface stay inside.
const GROUP_REACH: f64 = 128.0;
/// Tapes shorter than this many steps are measured whole: a narrowed short tape saves less
/// than the groups' smaller batches cost (measured at depth 8 through the sink: grouped,
/// spheres_chain's 635 steps took 1.3 s instead of 2.2; gyroid_sphere's 26 took 7 % more
/// time, heart's 17 took 13 % more).
const GROUP_TAPE: usize = 128;

/// [`distances`] for any number of points, in parallel; grouped by place
/// ([`distances_grouped`]) when the tape is long.
fn distances_nearby(field: &ClippedField, points: &[[f64; 3]]) -> Vec<Found> {
    if field.tape().len() >= GROUP_TAPE {
        return distances_grouped(field, points);
    }
    points
        .par_chunks(CHUNK)
        .flat_map_iter(|chunk| distances(field, chunk))
        .collect()
}

/// [`distances`], each group of points in one small cube of the region measured with the
/// field narrowed to the cube and a margin around it ([`ClippedField::narrow`]: equal to
/// the field there, and often far shorter: a union of many parts is one part or two in a
/// small cube). A point whose search would reach past the margin is measured with the
/// whole field, so the answers are the whole field's.
fn distances_grouped(field: &ClippedField, points: &[[f64; 3]]) -> Vec<Found> {
    let bounds = field.bounds();
    let longest = bounds.longest_side();
    let (side, reach) = (longest / GROUPS, longest / GROUP_REACH);
    let cube = |p: &[f64; 3]| -> [i64; 3] {
        [0, 1, 2].map(|a| ((p[a] - bounds.min[a]) / side).floor() as i64)
    };
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    order.par_sort_unstable_by_key(|&i| cube(&points[i as usize]));
    // Tasks: runs of one cube, cut to batches of at most CHUNK points.
    let mut tasks: Vec<&[u32]> = Vec::new();
    for run in order.chunk_by(|&a, &b| cube(&points[a as usize]) == cube(&points[b as usize])) {
        tasks.extend(run.chunks(CHUNK));
    }
    // In the order of `order`: the tasks are its slices, one after another.
    let measured: Vec<Option<Found>> = tasks
        .par_iter()
        .map_init(IntervalEval::new, |ev, &task| {
            let c = cube(&points[task[0] as usize]);
            let b = [0, 1, 2].map(|a| {
                let lo = bounds.min[a] + side * c[a] as f64 - reach;
                Interval::try_from((lo, lo + side + 2.0 * reach)).unwrap_or(Interval::ENTIRE)
            });
            field.interval(ev, b);
            let narrowed = field.narrow(ev);
            let mine: Vec<[f64; 3]> = task.iter().map(|&i| points[i as usize]).collect();
            distances_within(&narrowed, &mine, reach)
        })
        .flatten_iter()
        .collect();
    let mut out = vec![Found::default(); points.len()];
    let mut far: Vec<u32> = Vec::new();
    for (&i, f) in order.iter().zip(measured) {
        match f {
            Some(f) => out[i as usize] = f,
            None => far.push(i),
        }
    }
    let far_points: Vec<[f64; 3]> = far.iter().map(|&i| points[i as usize]).collect();
    let far_found: Vec<Found> = far_points
        .par_chunks(CHUNK)
        .flat_map_iter(|chunk| distances(field, chunk))
        .collect();
    for (&i, f) in far.iter().zip(far_found) {
        out[i as usize] = f;
    }
    out
}

/// The distance to the surface of each point, and whether it is the first-order estimate.
fn distances(field: &ClippedField, points: &[[f64; 3]]) -> Vec<Found> {
    distances_within(field, points, f64::INFINITY)
        .into_iter()
        .map(|f| f.unwrap_or_default())
        .collect()
}

/// As [`distances`], but a point whose search would go farther than `reach` from it is
/// `None` (not measured: `field` may be one narrowed to a box that far around the points).
fn distances_within(field: &ClippedField, points: &[[f64; 3]], reach: f64) -> Vec<Option<Found>> {
    let mut grad = GradEval::new();
    let mut batch = Batch::default();
    let n = points.len();
    // Per point: the direction towards the surface and the first-order distance.
    let mut dir = vec![DVec3::ZERO; n];
    let mut first = vec![0.0; n];
    let mut out = vec![Found::default(); n];
    let mut sign0 = vec![false; n];
    let mut todo: Vec<usize> = Vec::with_capacity(n);
    let mut beyond_reach = vec![false; n];
    for (i, p) in points.iter().enumerate() {
        let g = field.grad(&mut grad, *p);
        sign0[i] = g.v < 0.0;
        let slope = DVec3::from(g.d).length();
        if g.v == 0.0 {
            continue;
        }
        if !g.v.is_finite() || slope.is_nan() || slope <= 0.0 || !slope.is_finite() {
            // No direction to search in: report what can be said.
            out[i] = Found {
                d: if g.v.is_finite() {
                    g.v.abs()
                } else {
                    f64::INFINITY
                },
                estimated: true,
                toward: DVec3::ZERO,
            };
            continue;
        }
        first[i] = g.v.abs() / slope;
        if first[i] * SEARCH[SEARCH.len() - 1] > reach {
            beyond_reach[i] = true;
            continue;
        }
        dir[i] = DVec3::from(g.d) / slope * -g.v.signum();
        todo.push(i);
    }
    // Bracket: the first search step where F changes sign.
    let mut lo = vec![0.0; n];
    let mut hi = vec![f64::NAN; n];
    let mut open = todo.clone();
    for &k in &SEARCH {
        if open.is_empty() {
            break;
        }
        let f = batch.eval(
            field,
            open.iter()
                .map(|&i| DVec3::from(points[i]) + dir[i] * (first[i] * k)),
        );
        let mut still = Vec::new();
        for (j, &i) in open.iter().enumerate() {
            if (f[j] < 0.0) != sign0[i] {
                hi[i] = first[i] * k;
            } else {
                lo[i] = first[i] * k;
                still.push(i);
            }
        }
        open = still;
    }
    for &i in &open {
        out[i] = Found {
            d: first[i],
            estimated: true,
            toward: dir[i],
        };
    }
    let bracketed: Vec<usize> = todo.into_iter().filter(|&i| hi[i].is_finite()).collect();
    for _ in 0..BISECTIONS {
        let f = batch.eval(
            field,
            bracketed
                .iter()
                .map(|&i| DVec3::from(points[i]) + dir[i] * (0.5 * (lo[i] + hi[i]))),
        );
        for (j, &i) in bracketed.iter().enumerate() {
            let mid = 0.5 * (lo[i] + hi[i]);
            if (f[j] < 0.0) != sign0[i] {
                hi[i] = mid;
            } else {
                lo[i] = mid;
            }
        }
    }
    for &i in &bracketed {
        out[i] = Found {
            d: 0.5 * (lo[i] + hi[i]),
            estimated: false,
            toward: dir[i],
        };
    }
    out.into_iter()
        .zip(beyond_reach)
        .map(|(f, far)| (!far).then_some(f))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples;
    use isoforge_field::{Bounds, Shape};

    #[test]
    fn a_cube_on_its_own_faces_is_at_zero() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        // max(|x|, |y|, |z|) − 1: the cube [-1, 1]³.
        let cube = x.abs().max(&y.abs()).max(&z.abs()) - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        let mesh = samples::cuboid([-1.0; 3], [1.0; 3]);
        let d = deviation(&mesh, &ClippedField::new(&cube, region));
        assert!(d.max < 1e-6, "{d:?}");
    }

    #[test]
    fn near_a_crease_the_nearer_surface_counts() {
        // max(x − 1, 10 (y − 1)): inside, near the edge x = y = 1. At (0.95, 0.99, 0) the
        // x branch is the larger (−0.05 against −0.1), so its gradient points along x, 0.05
        // to its face; but the face y = 1 is only 0.01 away.
        let (x, y) = (Shape::x(), Shape::y());
        let wedge = (x - 1.0).max(&((y - 1.0) * 10.0));
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        let mesh = Mesh {
            vertices: vec![
                [0.95, 0.99, 0.0],
                [0.9501, 0.99, 0.0],
                [0.95, 0.9901, 0.0001],
            ],
            triangles: vec![[0, 1, 2]],
        };
        let d = deviation(&mesh, &ClippedField::new(&wedge, region));
        assert!((d.max - 0.01).abs() < 2e-4, "{d:?}");
    }

    #[test]
    fn a_sphere_inscribed_polyhedron_deviates_by_its_sagitta() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        // Its face centres are at 1/√3.
        let mesh = samples::octahedron();
        let d = deviation(&mesh, &ClippedField::new(&ball, region));
        assert_eq!((d.facing_against, d.area_facing_against), (0, 0.0));
        let expected = 1.0 - 1.0 / 3f64.sqrt();
        assert!((d.max - expected).abs() < 1e-6, "{d:?}");
        assert!(d.mean > 0.0 && d.mean < d.max);
        assert_eq!(d.samples, 56);
        assert_eq!(d.estimated, 0);
        // The share of the area beyond a tolerance, by the sample points' weights: past
        // every point nothing; at 0 all but the corners (3 × 3/60 of each face); between
        // the edge middles (1 − 1/√2 off) and the centroids, the centroids alone (27/60).
        let field = ClippedField::new(&ball, region);
        let over = |t: f64| deviation_beyond(&mesh, &field, t);
        assert_eq!((over(0.5).area_beyond, over(0.5).points_beyond), (0.0, 0));
        assert!(over(0.5).holds(0.5) && !over(0.35).holds(0.35));
        assert!((over(0.0).area_beyond - 51.0 / 60.0).abs() < 1e-9);
        assert_eq!(over(0.0).points_beyond, 32);
        assert!((over(0.35).area_beyond - 27.0 / 60.0).abs() < 1e-9);
        assert_eq!(over(0.35).points_beyond, 8);
        assert!(over(0.35).beyond_exact);
    }

    #[test]
    fn points_measured_with_narrowed_fields_get_the_whole_fields_answers() {
        // A row of balls: in a small cube the union narrows to one or two of them.
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = |cx: f64| ((x.clone() - cx).square() + y.square() + z.square()).sqrt() - 0.6;
        let row = (1..8).fold(ball(0.0), |u, k| u.min(&ball(k as f64)));
        let region = Bounds::new([-1.0, -1.0, -1.0], [8.0, 1.0, 1.0]).expect("box");
        let field = ClippedField::new(&row, region);
        let mesh = crate::mesh_shape(&row, &crate::MeshSettings::new(region, 6));
        let mut points: Vec<[f64; 3]> = mesh
            .triangles
            .iter()
            .flat_map(|&t| sample_points(mesh.corners(t)))
            .collect();
        // And points far off, whose searches reach past any group's margin.
        points.extend([[3.5, 0.0, 0.9], [-0.9, 0.9, 0.9], [7.5, -0.5, 0.0]]);
        let nearby = distances_grouped(&field, &points);
        let whole = distances(&field, &points);
        assert_eq!(nearby.len(), whole.len());
        for (i, (a, b)) in nearby.iter().zip(&whole).enumerate() {
            assert_eq!(
                (a.d, a.estimated, a.toward),
                (b.d, b.estimated, b.toward),
                "{i}"
            );
        }
        // The narrowed tapes are shorter: the point of measuring this way.
        let mut ev = IntervalEval::new();
        let side = region.longest_side() / GROUPS;
        let b = [0.0, 0.0, 0.0].map(|c: f64| Interval::try_from((c, c + side)).unwrap());
        field.interval(&mut ev, b);
        assert!(field.narrow(&ev).tape().len() * 3 < field.tape().len());
    }

    #[test]
    fn a_fold_is_counted_as_facing_against() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        // The top corner pushed down through the middle: still closed and manifold, but
        // its four triangles now face down, into the ball at their centroids.
        let mut mesh = samples::octahedron();
        mesh.vertices[4] = [0.0, 0.0, -0.3];
        assert!(crate::check(&mesh).is_closed_manifold());
        let d = deviation(&mesh, &ClippedField::new(&ball, region));
        assert_eq!(d.facing_against, 4);
        let [a, b, c] = mesh.corners(mesh.triangles[0]);
        let [p, q, r] = mesh.corners(mesh.triangles[4]);
        let (top, bottom) = ((b - a).cross(c - a).length(), (q - p).cross(r - p).length());
        let share = top / (top + bottom);
        assert!((d.area_facing_against - share).abs() < 1e-9, "{d:?}");
    }
}
