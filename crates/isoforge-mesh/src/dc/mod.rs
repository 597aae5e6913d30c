//! The interval octree and dual contouring: a field to a closed, manifold, consistently
//! oriented triangle mesh, with cells merged where the surface is flat enough.
//!
//! Stages, each in its own file:
//! 1. `octree.rs`: interval pruning from the root cube down to 16³-cell blocks, the tape
//!    simplified on the way (rayon over subtrees);
//! 2. `hermite.rs`: every kept block sampled densely in one batch call; corner signs agreed
//!    across block faces; crossings on sign-changing edges by batched bisection; normals
//!    from the gradient with fallbacks;
//! 3. `leaf.rs` + `topology.rs` + `qef.rs`: a block's cells merged bottom up into leaves
//!    where the QEF vertex stays within the tolerance and the topology does not change;
//!    one vertex per leaf (per patch for a finest cell, with marching-cubes face pairing;
//!    an ambiguous face joins its inside corners where the field puts its middle inside,
//!    and such cells never merge), kept in its box; `merge.rs` merges whole blocks
//!    further;
//! 4. `contour.rs`: one polygon per sign-changing edge on the leaves' boundaries, split
//!    into triangles so that the result is a 2-manifold (the module doc there has the
//!    argument);
//! 5. `stream.rs`: the schedule, slab by slab along z, polygons handed on as soon as
//!    they are known; with more than one worker, stages 6 to 9 and the sink take them on
//!    a thread of their own, in order (`pipe.rs`);
//! 6. `decimate.rs`: with a tolerance, edge collapses checked against the field (on
//!    chunks of 65,536 triangles, for as long as collapsing pays);
//! 7. `refine.rs`: with a tolerance, vertices off the surface moved onto it and triangles
//!    that cut a crease split along it;
//! 8. `flips.rs`: with a tolerance, an edge that strays from the surface turned to the
//!    other diagonal of its two triangles where that one keeps nearer;
//! 9. `shells.rs`: with a tolerance, a small closed part that came out inside out turned
//!    the right way out, then the [`MeshSink`].
//!
//! Everything samples the field clipped to the region (`isoforge_field::ClippedField`:
//! F = max(f, d_box), NaN = outside), so models cut by their region come out capped.

pub mod cell;
pub mod contour;
pub mod decimate;
pub mod estimate;
pub mod fine;
pub mod flips;
pub mod hermite;
pub mod leaf;
pub mod left_off;
pub mod merge;
pub mod narrowed;
pub mod octree;
pub mod pipe;
pub mod qef;
pub mod refine;
pub mod refined;
pub mod sampler;
pub mod seam;
pub mod shells;
pub mod stream;
pub mod topology;

#[cfg(test)]
mod refined_tests;
#[cfg(test)]
mod tests;

use std::fmt;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use isoforge_field::{Bounds, ClippedField, Shape};

pub use estimate::{Estimate, estimate, estimate_bound};
pub use refined::{MAX_LEVELS as MAX_REFINE_LEVELS, Refinement};

use crate::mesh::Mesh;
use crate::sink::MeshSink;
use leaf::Merging;
#[cfg(test)]
use sampler::Sampler;
use sampler::TapeSampler;

/// The deepest level accepted: 2^16 cells a side is far beyond any printer's resolution
/// for a region, and keeps lattice indices small.
pub const MAX_DEPTH: u8 = 16;

/// The default tolerance, as a fraction of the finest cell. Swept at depth 8: at 0.1 the
/// unit sphere's volume is within 0.04 % of the exact one with 17 times fewer triangles than
/// the uniform mesh; at 0.2 it is 0.13 % off (docs/meshing.md).
pub const DEFAULT_TOLERANCE_CELLS: f64 = 0.1;

/// A progress callback: called with the fraction done, 0 to 1.
pub type Progress = Arc<dyn Fn(f64) + Send + Sync>;

/// How to mesh.
#[derive(Clone)]
pub struct MeshSettings {
    /// The region; outside it counts as outside.
    pub bounds: Bounds,
    /// The finest level: 2^depth cells along the longest side.
    pub depth: u8,
    /// The largest distance allowed between the mesh and the true surface, in the model's
    /// units: cells merge where the surface is flat enough for it. `None` is
    /// [`DEFAULT_TOLERANCE_CELLS`] of the finest cell; `Some(0.0)` keeps every cell at the
    /// finest level (the uniform mesh).
    pub tolerance: Option<f64>,
    /// Worker threads; 0 uses rayon's global pool (all cores).
    pub threads: usize,
    /// Called now and then with the fraction done.
    pub progress: Option<Progress>,
    /// Set from another thread to stop the work ([`MeshError::Cancelled`]).
    pub cancel: Option<Arc<AtomicBool>>,
    /// Where to count what the mesher noticed on the way, for the caller to tell.
    pub notes: Option<Arc<MeshNotes>>,
    /// Blocks to sample on a finer lattice (`refined.rs`); `None` samples every block at
    /// the finest level.
    pub refine: Option<Arc<Refinement>>,
}

/// What the mesher noticed on the way.
#[derive(Debug, Default)]
pub struct MeshNotes {
    /// Triangles (before the splits onto the surface; counted with a tolerance above 0)
    /// that join the two sides of a part thinner than about two finest cells: a sheet, a
    /// needle, a gap the lattice does not resolve, where the mesh may be off by up to
    /// about a cell. A finer depth resolves them.
    pub thin_triangles: AtomicU64,
    /// Small closed parts (a blob a cell or two wide, at a large tolerance) that came out
    /// inside out and were turned the right way out (`shells.rs`).
    pub parts_turned: AtomicU64,
    /// Places on the mesh (a chord's middle, a triangle's centre, a vertex) that the
    /// splits onto the surface left off it, because every split there would fold the mesh
    /// or none could be placed: where the mesh may miss the tolerance. Each once, at most
    /// 65,536 of them (`left_off.rs`); measure them with
    /// [`farthest`](crate::farthest).
    pub left_off: Mutex<Vec<[f64; 3]>>,
    /// How many such places were found in all (more than [`MeshNotes::left_off`] holds
    /// when that is full).
    pub left_off_found: AtomicU64,
    /// Blocks of the lattice that intervals could not prove empty or full: what a run
    /// samples, and what a refinement's cost is told against.
    pub blocks: AtomicU64,
    /// Of them, the blocks sampled on a finer lattice ([`MeshSettings::refine`]).
    pub refined_blocks: AtomicU64,
}

impl fmt::Debug for MeshSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeshSettings")
            .field("bounds", &self.bounds)
            .field("depth", &self.depth)
            .field("tolerance", &self.tolerance)
            .field("threads", &self.threads)
            .field("progress", &self.progress.is_some())
            .field("cancel", &self.cancel.is_some())
            .field("notes", &self.notes)
            .field(
                "refine",
                &self.refine.as_ref().map(|r| (r.levels, r.blocks.len())),
            )
            .finish()
    }
}

impl MeshSettings {
    /// Settings for a region and depth: the default tolerance, all cores, no progress
    /// reports.
    pub fn new(bounds: Bounds, depth: u8) -> Self {
        MeshSettings {
            bounds,
            depth,
            tolerance: None,
            threads: 0,
            progress: None,
            cancel: None,
            notes: None,
            refine: None,
        }
    }

    /// The finest cell's side.
    pub fn cell(&self) -> f64 {
        self.bounds.longest_side() / f64::from(1u32 << self.depth.min(MAX_DEPTH))
    }

    /// The tolerance in effect: the one given, or the default for the finest cell.
    pub fn effective_tolerance(&self) -> f64 {
        self.tolerance
            .unwrap_or(DEFAULT_TOLERANCE_CELLS * self.cell())
    }

    /// How far cells may merge under the tolerance.
    fn merging(&self) -> Merging {
        let t = self.effective_tolerance();
        if t.is_nan() || t <= 0.0 {
            return Merging::OFF;
        }
        Merging {
            plane: t * PLANE_SHARE,
            surface: t * SURFACE_SHARE,
        }
    }
}

/// The share of the tolerance a merged vertex may be from any crossing's plane: the tangent
/// planes are the surface to first order, so all of it.
const PLANE_SHARE: f64 = 1.0;

/// The share of the tolerance a merged vertex may be from the surface, by the field's
/// first-order estimate |F| / |∇F|: half, so that the estimate's own error on curved parts
/// stays within the tolerance.
const SURFACE_SHARE: f64 = 0.5;

/// Meshing could not run.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The depth is beyond [`MAX_DEPTH`].
    #[error("depth {depth} is too deep (at most {MAX_DEPTH})")]
    TooDeep {
        /// The requested depth.
        depth: u8,
    },
    /// The tolerance is negative or not a number.
    #[error("tolerance {tolerance}: expected a distance of 0 or more")]
    BadTolerance {
        /// The tolerance given.
        tolerance: f64,
    },
    /// The worker pool could not start.
    #[error("cannot start {threads} worker threads: {message}")]
    Threads {
        /// Threads asked for.
        threads: usize,
        /// Why.
        message: String,
    },
    /// The cancel flag was set.
    #[error("meshing was cancelled")]
    Cancelled,
    /// More vertices than 32-bit indices can name.
    #[error(
        "the mesh has more than 4,294,967,295 vertices; use a coarser --depth or a larger --tolerance"
    )]
    TooManyVertices,
    /// The sink could not take the output.
    #[error("cannot write the mesh: {0}")]
    Write(#[source] std::io::Error),
}

/// Meshes a shape over the settings' region. Depths beyond [`MAX_DEPTH`] are clamped to
/// it and a bad tolerance counts as the default; use [`try_mesh_shape`] to have them
/// refused instead.
pub fn mesh_shape(shape: &Shape, settings: &MeshSettings) -> Mesh {
    let mut s = settings.clone();
    s.depth = s.depth.min(MAX_DEPTH);
    if s.tolerance.is_some_and(|t| t.is_nan() || t < 0.0) {
        s.tolerance = None;
    }
    s.cancel = None;
    match try_mesh_shape(shape, &s) {
        Ok(mesh) => mesh,
        // Only the worker pool can fail here: mesh on the global pool instead.
        Err(_) => {
            let mut mesh = Mesh::default();
            let _ = stream::run(
                &tape_sampler(shape, &s),
                &s,
                s.merging(),
                octree::BLOCK_SHIFT,
                &mut mesh,
            );
            mesh
        }
    }
}

/// Meshes a shape over the settings' region; an empty mesh when nothing is inside it.
pub fn try_mesh_shape(shape: &Shape, settings: &MeshSettings) -> Result<Mesh, MeshError> {
    let mut mesh = Mesh::default();
    mesh_shape_into(shape, settings, &mut mesh)?;
    Ok(mesh)
}

/// Meshes a shape into a sink, piece by piece: nothing is held but a few slabs of cells,
/// so a mesh larger than memory can go straight to a file.
pub fn mesh_shape_into(
    shape: &Shape,
    settings: &MeshSettings,
    sink: &mut (dyn MeshSink + Send),
) -> Result<(), MeshError> {
    if settings.depth > MAX_DEPTH {
        return Err(MeshError::TooDeep {
            depth: settings.depth,
        });
    }
    if let Some(t) = settings.tolerance
        && (t.is_nan() || t < 0.0)
    {
        return Err(MeshError::BadTolerance { tolerance: t });
    }
    let sampler = tape_sampler(shape, settings);
    let merging = settings.merging();
    let run = |sink: &mut (dyn MeshSink + Send)| {
        stream::run(&sampler, settings, merging, octree::BLOCK_SHIFT, sink)
    };
    if settings.threads == 0 {
        return run(sink);
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| MeshError::Threads {
            threads: settings.threads,
            message: e.to_string(),
        })?;
    pool.install(|| run(sink))
}

/// The shape clipped to the settings' region, as the mesher samples it.
fn tape_sampler(shape: &Shape, settings: &MeshSettings) -> TapeSampler {
    TapeSampler::new(ClippedField::new(shape, settings.bounds))
}

/// Reports progress from many workers, about a hundred times in all.
struct Reporter<'a> {
    progress: Option<&'a Progress>,
    done: AtomicUsize,
    total: usize,
    from: f64,
    to: f64,
}

impl<'a> Reporter<'a> {
    fn new(progress: Option<&'a Progress>, total: usize, from: f64, to: f64) -> Self {
        if let Some(p) = progress {
            p(from);
        }
        Reporter {
            progress,
            done: AtomicUsize::new(0),
            total: total.max(1),
            from,
            to,
        }
    }
    fn tick(&self) {
        let Some(p) = self.progress else { return };
        let n = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        let step = (self.total / 100).max(1);
        if n.is_multiple_of(step) || n == self.total {
            p(self.from + (self.to - self.from) * n as f64 / self.total as f64);
        }
    }
}

/// The mesher on any sampler, into a mesh (tests sample plain closures), with a chosen
/// block size (tests use small blocks to put block boundaries inside small lattices).
#[cfg(test)]
pub(crate) fn mesh_sampler_blocks<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    block_shift: u32,
) -> Mesh {
    let mut mesh = Mesh::default();
    if let Err(e) = stream::run(
        sampler,
        settings,
        settings.merging(),
        block_shift,
        &mut mesh,
    ) {
        panic!("meshing failed: {e}");
    }
    mesh
}
