//! The interval octree and dual contouring: a field to a closed, manifold, consistently
//! oriented triangle mesh.
//!
//! Stages, each in its own file:
//! 1. `octree.rs`: interval pruning from the root cube down to 16³-cell blocks, the tape
//!    simplified on the way (rayon over subtrees);
//! 2. `hermite.rs`: every kept block sampled densely in one batch call; corner signs agreed
//!    across block faces; crossings on sign-changing edges by batched bisection; normals
//!    from the gradient with fallbacks;
//! 3. `cell.rs` + `qef.rs`: per cell, its patches (marching-cubes face pairing with one
//!    fixed rule for ambiguous faces) and one QEF vertex per patch, kept in the cell;
//! 4. `contour.rs`: one polygon per sign-changing edge, split into triangles so that the
//!    result is a 2-manifold (the module doc there has the argument).
//!
//! Everything samples the field clipped to the region (`isoforge_field::ClippedField`:
//! F = max(f, d_box), NaN = outside), so models cut by their region come out capped.

pub mod cell;
pub mod contour;
pub mod hermite;
pub mod octree;
pub mod qef;
pub mod sampler;

#[cfg(test)]
mod tests;

use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use isoforge_field::{Bounds, ClippedField, Shape};
use rayon::prelude::*;

use crate::mesh::Mesh;
use contour::{BlockOut, CENTRE_FLAG};
use hermite::{Crossing, EdgeRef, Scratch};
use octree::{Class, Grid, Octree};
use qef::Qef;
use sampler::{EvalPool, Sampler, TapeSampler};

/// The deepest level accepted: 2^16 cells a side is far beyond any printer's resolution
/// for a region, and keeps lattice indices small.
pub const MAX_DEPTH: u8 = 16;

/// A progress callback: called with the fraction done, 0 to 1.
pub type Progress = Arc<dyn Fn(f64) + Send + Sync>;

/// How to mesh.
#[derive(Clone)]
pub struct MeshSettings {
    /// The region; outside it counts as outside.
    pub bounds: Bounds,
    /// The finest level: 2^depth cells along the longest side.
    pub depth: u8,
    /// Worker threads; 0 uses rayon's global pool (all cores).
    pub threads: usize,
    /// Called now and then with the fraction done.
    pub progress: Option<Progress>,
}

impl fmt::Debug for MeshSettings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeshSettings")
            .field("bounds", &self.bounds)
            .field("depth", &self.depth)
            .field("threads", &self.threads)
            .field("progress", &self.progress.is_some())
            .finish()
    }
}

impl MeshSettings {
    /// Settings for a region and depth, all cores, no progress reports.
    pub fn new(bounds: Bounds, depth: u8) -> Self {
        MeshSettings {
            bounds,
            depth,
            threads: 0,
            progress: None,
        }
    }
}

/// Meshing could not run.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The depth is beyond [`MAX_DEPTH`].
    #[error("depth {depth} is too deep (at most {MAX_DEPTH})")]
    TooDeep {
        /// The requested depth.
        depth: u8,
    },
    /// The worker pool could not start.
    #[error("cannot start {threads} worker threads: {message}")]
    Threads {
        /// Threads asked for.
        threads: usize,
        /// Why.
        message: String,
    },
}

/// Meshes a shape over the settings' region. Depths beyond [`MAX_DEPTH`] are clamped to
/// it; use [`try_mesh_shape`] to have them refused instead.
pub fn mesh_shape(shape: &Shape, settings: &MeshSettings) -> Mesh {
    let mut s = settings.clone();
    s.depth = s.depth.min(MAX_DEPTH);
    match try_mesh_shape(shape, &s) {
        Ok(mesh) => mesh,
        // Only the worker pool can fail here: mesh on the global pool instead.
        Err(_) => mesh_sampler(&tape_sampler(shape, &s), &s),
    }
}

/// Meshes a shape over the settings' region; an empty mesh when nothing is inside it.
pub fn try_mesh_shape(shape: &Shape, settings: &MeshSettings) -> Result<Mesh, MeshError> {
    if settings.depth > MAX_DEPTH {
        return Err(MeshError::TooDeep {
            depth: settings.depth,
        });
    }
    let sampler = tape_sampler(shape, settings);
    let run = || mesh_sampler(&sampler, settings);
    if settings.threads == 0 {
        return Ok(run());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(settings.threads)
        .build()
        .map_err(|e| MeshError::Threads {
            threads: settings.threads,
            message: e.to_string(),
        })?;
    Ok(pool.install(run))
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

/// The mesher proper, on any sampler.
pub(crate) fn mesh_sampler<S: Sampler>(sampler: &S, settings: &MeshSettings) -> Mesh {
    mesh_sampler_blocks(sampler, settings, octree::BLOCK_SHIFT)
}

/// The mesher with a chosen block size (tests use small blocks to put block boundaries
/// inside small lattices).
pub(crate) fn mesh_sampler_blocks<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    block_shift: u32,
) -> Mesh {
    let progress = settings.progress.as_ref();
    let depth = u32::from(settings.depth.min(MAX_DEPTH));
    let grid = Grid::new(&settings.bounds, depth, block_shift);
    if let Some(p) = progress {
        p(0.0);
    }
    let tree = Octree::build(sampler, grid);
    let blocks = &tree.blocks;
    let pool = EvalPool::new(sampler);

    // Pass 1: every kept block's own corner signs.
    let s = hermite::side(&grid);
    let words = (s * s * s).div_ceil(64);
    let mut bits = vec![0u64; blocks.len() * words];
    let report = Reporter::new(progress, blocks.len(), 0.1, 0.4);
    bits.par_chunks_mut(words)
        .zip(blocks.par_iter())
        .for_each_init(
            || (pool.take(), Scratch::default()),
            |(guard, scratch), (out, block)| {
                hermite::own_signs(
                    sampler,
                    guard.get(),
                    &block.local,
                    &grid,
                    block.coords,
                    scratch,
                    out,
                );
                report.tick();
            },
        );

    let neighbours: Vec<[Class; 27]> = blocks
        .par_iter()
        .map(|block| {
            std::array::from_fn(|n| {
                let d = [n as i64 % 3 - 1, (n as i64 / 3) % 3 - 1, n as i64 / 9 - 1];
                tree.class([0, 1, 2].map(|i| block.coords[i] + d[i]))
            })
        })
        .collect();

    // Pass 2: agreed signs, crossings, normals, vertices.
    let report = Reporter::new(progress, blocks.len(), 0.4, 0.85);
    let outs: Vec<BlockOut> = blocks
        .par_iter()
        .zip(neighbours.par_iter())
        .map_init(
            || (pool.take(), Pass2Scratch::default()),
            |(guard, sc), (block, nb)| {
                let mut out = BlockOut::default();
                hermite::canonical_signs(
                    &grid,
                    nb,
                    |b| &bits[b as usize * words..(b as usize + 1) * words],
                    &mut sc.signs,
                );
                hermite::crossings(
                    sampler,
                    guard.get(),
                    &block.local,
                    &grid,
                    block.coords,
                    &sc.signs,
                    &mut sc.scratch,
                    &mut sc.edges,
                    &mut sc.slots,
                    &mut sc.crossings,
                );
                contour::cell_vertices(
                    &grid,
                    block.coords,
                    &sc.signs,
                    &sc.slots,
                    &sc.edges,
                    &sc.crossings,
                    &mut sc.qefs,
                    &mut out,
                );
                report.tick();
                out
            },
        )
        .collect();
    drop(bits);

    let mut offsets = Vec::with_capacity(outs.len());
    let mut total = 0u32;
    for o in &outs {
        offsets.push(total);
        total += o.vertices.len() as u32;
    }

    // Pass 3: polygons.
    let report = Reporter::new(progress, blocks.len(), 0.85, 0.98);
    let emitted: Vec<Emitted> = (0..outs.len())
        .into_par_iter()
        .map(|me| {
            let (mut tris, mut centres) = (Vec::new(), Vec::new());
            let nb = &neighbours[me];
            let missing = contour::emit(
                &grid,
                &outs,
                &offsets,
                me,
                |d| match nb[((d[0] + 1) + 3 * (d[1] + 1) + 9 * (d[2] + 1)) as usize] {
                    Class::Block(i) => Some(i as usize),
                    _ => None,
                },
                &mut tris,
                &mut centres,
            );
            debug_assert_eq!(missing, 0, "edge without its 4 cells");
            report.tick();
            (tris, centres)
        })
        .collect();

    let mut mesh = Mesh::default();
    mesh.vertices.reserve(total as usize);
    for o in &outs {
        mesh.vertices.extend_from_slice(&o.vertices);
    }
    drop(outs);
    for (tris, centres) in emitted {
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend_from_slice(&centres);
        mesh.triangles.extend(tris.into_iter().map(|t| {
            t.map(|v| {
                if v & CENTRE_FLAG != 0 {
                    base + (v & !CENTRE_FLAG)
                } else {
                    v
                }
            })
        }));
    }
    if let Some(p) = progress {
        p(1.0);
    }
    mesh
}

/// A block's triangles and polygon centres.
type Emitted = (Vec<[u32; 3]>, Vec<[f32; 3]>);

#[derive(Default)]
struct Pass2Scratch {
    scratch: Scratch,
    signs: Vec<u8>,
    edges: Vec<EdgeRef>,
    slots: Vec<u32>,
    crossings: Vec<Crossing>,
    qefs: [Qef; 4],
}
