//! [`DeviationSink`]: the distance from the surface of a mesh that passes by on its way to
//! another sink, measured as in [`super::deviation_beyond`] but a chunk of triangles at a
//! time, so the mesh is never held whole (`isoforge mesh --max-depth` measures every mesh
//! it writes this way).

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec3};
use isoforge_field::ClippedField;

use super::{Deviation, SAMPLES, Sums, distances_nearby, refine_largest, sample_points};
use crate::sink::MeshSink;

/// Triangles measured together: enough points for the batches to be full and the work
/// shared among threads, few enough to keep memory small (about 3 MB of points).
const TRIANGLES: usize = 8192;

/// A sink that measures what passes through it on the way to `inner`.
pub struct DeviationSink<'f, S> {
    inner: S,
    field: &'f ClippedField,
    tolerance: f64,
    waiting: Vec<[DVec3; 3]>,
    out: Deviation,
    sums: Sums,
    /// Set once a chunk measured is farther than the tolerance, when the caller asked
    /// ([`DeviationSink::stop_on_miss`]); measuring stops then.
    missed: Option<Arc<AtomicBool>>,
    /// The sample points beyond the tolerance and their distances, when the caller asked
    /// ([`DeviationSink::keeping_misses`]), at most `keep` of them.
    misses: Vec<([f64; 3], f64)>,
    keep: usize,
}

impl<'f, S: MeshSink> DeviationSink<'f, S> {
    /// Measures against `field` on the way to `inner`; the points farther than
    /// `tolerance` are searched around, as [`super::deviation_beyond`] does.
    pub fn new(inner: S, field: &'f ClippedField, tolerance: f64) -> Self {
        DeviationSink {
            inner,
            field,
            tolerance,
            waiting: Vec::with_capacity(TRIANGLES),
            out: Deviation {
                beyond_exact: true,
                ..Deviation::default()
            },
            sums: Sums::default(),
            missed: None,
            misses: Vec::new(),
            keep: 0,
        }
    }

    /// Keeps up to `keep` of the sample points farther than the tolerance, with their
    /// distances: where a finer lattice is needed (`isoforge mesh` refines the blocks
    /// around them). Past `keep`, the farthest are kept.
    pub fn keeping_misses(mut self, keep: usize) -> Self {
        self.keep = keep;
        self
    }

    /// The points kept by [`DeviationSink::keeping_misses`], farthest first.
    pub fn take_misses(&mut self) -> Vec<([f64; 3], f64)> {
        let mut out = std::mem::take(&mut self.misses);
        out.sort_by(|a, b| b.1.total_cmp(&a.1));
        out
    }

    /// Sets `flag` (and measures no more) as soon as a measured point is farther than the
    /// tolerance: a caller that will drop a mesh that misses needs no more than that, and
    /// may pass the same flag to the mesher as its cancel flag to stop it too.
    pub fn stop_on_miss(mut self, flag: Arc<AtomicBool>) -> Self {
        self.missed = Some(flag);
        self
    }

    /// Whether measuring stopped at a miss.
    fn stopped(&self) -> bool {
        self.missed
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// The triangles waiting, measured.
    fn measure(&mut self) {
        let points: Vec<[f64; 3]> = self
            .waiting
            .iter()
            .flat_map(|&t| sample_points(t))
            .collect();
        let mut found = distances_nearby(self.field, &points);
        self.out.beyond_exact &= refine_largest(self.field, &points, &mut found, self.tolerance);
        for (ti, &corners) in self.waiting.iter().enumerate() {
            let first = SAMPLES * ti;
            self.sums.add(
                &mut self.out,
                self.tolerance,
                corners,
                &points[first..first + SAMPLES],
                &found[first..first + SAMPLES],
                |_| false,
            );
        }
        if self.keep > 0 {
            for (p, f) in points.iter().zip(&found) {
                if f.d > self.tolerance {
                    self.misses.push((*p, f.d));
                }
            }
            if self.misses.len() > self.keep {
                self.misses.sort_by(|a, b| b.1.total_cmp(&a.1));
                self.misses.truncate(self.keep);
            }
        }
        self.waiting.clear();
        if let Some(flag) = &self.missed
            && self.out.max > self.tolerance
        {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// The distance of everything that passed (of what passed until a miss, after
    /// [`DeviationSink::stop_on_miss`]), and the inner sink.
    pub fn finish(self) -> (Deviation, S) {
        let (d, _, inner) = self.finish_with_misses();
        (d, inner)
    }

    /// As [`DeviationSink::finish`], with the points kept by
    /// [`DeviationSink::keeping_misses`], farthest first.
    pub fn finish_with_misses(mut self) -> (Deviation, Vec<([f64; 3], f64)>, S) {
        if !self.stopped() {
            self.measure();
        }
        self.sums.finish(&mut self.out);
        let misses = self.take_misses();
        (self.out, misses, self.inner)
    }
}

impl<S: MeshSink> MeshSink for DeviationSink<'_, S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        self.inner.vertex(p)
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        self.inner.triangle(t, corners)?;
        if self.stopped() {
            return Ok(());
        }
        self.waiting.push(corners.map(|p| Vec3::from(p).as_dvec3()));
        if self.waiting.len() == TRIANGLES {
            self.measure();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::replay;
    use crate::{Mesh, deviation_beyond, samples};
    use isoforge_field::{Bounds, Shape};

    /// The unit ball's field over [-2, 2]³, and its uniform mesh at depth 7: more triangles
    /// than one chunk, so the sums run over chunks.
    fn ball_in_chunks() -> (ClippedField, Mesh) {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        let mut settings = crate::MeshSettings::new(region, 7);
        settings.tolerance = Some(0.0);
        let mesh = crate::mesh_shape(&ball, &settings);
        assert!(mesh.triangles.len() > TRIANGLES, "{}", mesh.triangles.len());
        (ClippedField::new(&ball, region), mesh)
    }

    #[test]
    fn measures_what_the_whole_mesh_measure_does_and_passes_it_on() {
        let (field, mesh) = ball_in_chunks();
        for tolerance in [0.0, 1e-3, f64::INFINITY] {
            let mut sink = DeviationSink::new(Mesh::default(), &field, tolerance);
            replay(&mesh, &mut sink);
            let (d, passed) = sink.finish();
            assert_eq!(passed, mesh);
            let whole = deviation_beyond(&mesh, &field, tolerance);
            assert_eq!(
                (d.max, d.at, d.samples),
                (whole.max, whole.at, whole.samples)
            );
            assert_eq!(d.points_beyond, whole.points_beyond);
            assert!(
                (d.mean - whole.mean).abs() <= 1e-12 * whole.mean.max(1e-30),
                "{d:?}"
            );
            assert!((d.area_beyond - whole.area_beyond).abs() < 1e-9, "{d:?}");
        }
    }

    #[test]
    fn the_points_beyond_are_kept_farthest_first() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        let field = ClippedField::new(&ball, region);
        let mesh = samples::octahedron();
        for keep in [1usize, 3, 100] {
            let mut sink = DeviationSink::new(Mesh::default(), &field, 0.35).keeping_misses(keep);
            replay(&mesh, &mut sink);
            let (d, misses, _) = sink.finish_with_misses();
            // Each face's centroid is beyond: eight of them at the sagitta.
            assert_eq!(misses.len(), keep.min(d.points_beyond), "{keep}");
            assert!(misses.iter().all(|m| m.1 > 0.35));
            assert!(misses.windows(2).all(|w| w[0].1 >= w[1].1));
            assert_eq!(misses[0].1, d.max);
        }
    }

    #[test]
    fn a_polyhedron_inside_the_ball_is_off_by_its_sagitta() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        let field = ClippedField::new(&ball, region);
        let mut sink = DeviationSink::new(Mesh::default(), &field, 0.35);
        replay(&samples::octahedron(), &mut sink);
        let (d, _) = sink.finish();
        assert!((d.max - (1.0 - 1.0 / 3f64.sqrt())).abs() < 1e-6, "{d:?}");
        assert!(!d.holds(0.35) && d.holds(0.5));
        assert_eq!(d.points_beyond, 8);
    }

    #[test]
    fn a_miss_sets_the_flag_and_ends_the_measuring_but_not_the_passing_on() {
        let (field, mesh) = ball_in_chunks();
        // Missed at once (a tolerance no uniform mesh holds), and held (any mesh holds).
        for (tolerance, misses) in [(1e-9, true), (f64::INFINITY, false)] {
            let flag = Arc::new(AtomicBool::new(false));
            let mut sink =
                DeviationSink::new(Mesh::default(), &field, tolerance).stop_on_miss(flag.clone());
            replay(&mesh, &mut sink);
            assert_eq!(flag.load(Ordering::Relaxed), misses);
            let (d, passed) = sink.finish();
            assert_eq!(passed, mesh, "everything is passed on");
            let measured = if misses {
                TRIANGLES
            } else {
                mesh.triangles.len()
            };
            assert_eq!(d.samples, measured * SAMPLES, "{d:?}");
            assert_eq!(d.max > tolerance, misses, "{d:?}");
        }
    }
}
