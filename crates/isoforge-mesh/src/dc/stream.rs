//! The mesher's schedule: blocks slab by slab along z, each slab's polygons handed to the
//! sink as soon as the slab below it is done, so memory holds a few slabs, not the mesh.
//!
//! For slab z: (1) sample the corner signs of slab z + 1 (a block's corners on its upper
//! faces are owned by the blocks above it); (2) agree slab z's signs, find its crossings,
//! merge its cells into leaves (`leaf.rs`); (3) build the polygons of slab z's own edges,
//! which need its leaves and those of slab z − 1 (`contour.rs`), and give them global
//! vertex indices in a fixed order, so the output is the same on every run; (4) let the
//! merges above the block level (`merge.rs`) decide the nodes whose last slab this was, and
//! finish the polygons that waited for them. Slab z − 1 is then dropped.

use std::cell::RefCell;
use std::io;
use std::sync::atomic::Ordering;

use rayon::prelude::*;

use std::collections::HashMap;

use super::contour::{self, Near, Polygon, Ref};
use super::decimate::{self, Decimator};
use super::fine::{FineState, Refined};
use super::flips::Flipper;
use super::hermite::{self, Crossing, EdgeRef, Scratch};
use super::leaf::{self, BlockInput, BlockOut, LeafScratch, Merging, NO_VERT};
use super::left_off::LeftOff;
use super::merge::{AboveBlocks, Resolved};
use super::octree::{Class, Grid, Octree};
use super::pipe;
use super::refine::Refiner;
use super::refined::{self, Lattices};
use super::sampler::{EvalPool, Sampler};
use super::shells::SmallShells;
use super::{MAX_DEPTH, MeshError, MeshSettings, Reporter};
use crate::sink::MeshSink;

/// A finished block: its leaves and cells, and the global indices its vertices got.
pub struct Record {
    pub out: BlockOut,
    pub ids: Vec<u32>,
}

/// One worker's buffers for a block's leaves.
#[derive(Default)]
pub struct Pass2Scratch {
    pub scratch: Scratch,
    pub leaf: LeafScratch,
    pub signs: Vec<u8>,
    pub edges: Vec<EdgeRef>,
    pub slots: Vec<u32>,
    pub crossings: Vec<Crossing>,
}

/// Meshes a sampled field into a sink; with merging on, through the edge collapses of
/// `decimate.rs` and the splits of `refine.rs`. With more than one worker those stages
/// and the sink run on a thread of their own (`pipe.rs`), fed in order.
pub fn run<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    merging: Merging,
    block_shift: u32,
    sink: &mut (dyn MeshSink + Send),
) -> Result<(), MeshError> {
    let done = if rayon::current_num_threads() <= 1 {
        behind(sampler, settings, merging, sink, |s| {
            contour_into(sampler, settings, merging, block_shift, s)
        })
    } else {
        piped(sampler, settings, merging, block_shift, sink)
    };
    // Done only when the stages behind are: they may still be at work on the last slabs.
    if let (Ok(()), Some(p)) = (&done, &settings.progress) {
        p(1.0);
    }
    done
}

/// [`run`] with the stages behind the emitter on a thread of their own.
fn piped<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    merging: Merging,
    block_shift: u32,
    sink: &mut (dyn MeshSink + Send),
) -> Result<(), MeshError> {
    let (mut pipe, drain) = pipe::pipe();
    let (made, staged) = std::thread::scope(|scope| {
        let spawned = std::thread::Builder::new()
            .name("isoforge-mesh-stages".into())
            .spawn_scoped(scope, move || {
                behind(sampler, settings, merging, sink, |s| drain.into_sink(s))
            });
        let stages = match spawned {
            Ok(handle) => handle,
            // (The sink went with the closure: nothing was written to it.)
            Err(e) => {
                let error = MeshError::Threads {
                    threads: 1,
                    message: e.to_string(),
                };
                return (Err(error), Ok(()));
            }
        };
        let made = match contour_into(sampler, settings, merging, block_shift, &mut pipe) {
            Ok(()) => pipe.end().map_err(MeshError::Write),
            // Dropping the pipe without its end tells the stages not to finish.
            Err(e) => {
                drop(pipe);
                Err(e)
            }
        };
        let staged = match stages.join() {
            Ok(r) => r,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        (made, staged)
    });
    match (made, staged) {
        (Ok(()), staged) => staged,
        // The pipe stopped because the stages behind did: theirs is the cause.
        (Err(MeshError::Write(_)), Err(e)) => Err(e),
        (Err(e), _) => Err(e),
    }
}

/// The stages behind the emitter, given what `feed` sends them, and finished when it
/// says the mesh is complete: with merging on the edge collapses, the splits and the small
/// parts' check, then the sink; with it off the sink alone.
fn behind<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    merging: Merging,
    sink: &mut dyn MeshSink,
    feed: impl FnOnce(&mut dyn MeshSink) -> Result<(), MeshError>,
) -> Result<(), MeshError> {
    if !merging.on() {
        return feed(sink);
    }
    let tolerance = settings
        .effective_tolerance()
        .min(settings.cell() * decimate::MAX_CELLS);
    let mut shells = SmallShells::new(sampler, settings.cell(), sink);
    let places = RefCell::new(LeftOff::default());
    let mut flipper =
        Flipper::new(sampler, tolerance, settings.cell(), &mut shells).keeping_places(&places);
    let mut refiner = Refiner::new(
        sampler,
        tolerance,
        &settings.bounds,
        settings.cell(),
        &mut flipper,
    )
    .keeping_places(&places);
    let mut decimator = Decimator::new(sampler, tolerance, settings.cell(), &mut refiner);
    feed(&mut decimator)?;
    decimator.finish().map_err(MeshError::Write)?;
    refiner.finish().map_err(MeshError::Write)?;
    let thin_triangles = refiner.thin_triangles;
    drop(refiner);
    flipper.finish().map_err(MeshError::Write)?;
    drop(flipper);
    shells.finish().map_err(MeshError::Write)?;
    if let Some(notes) = &settings.notes {
        notes
            .thin_triangles
            .fetch_add(thin_triangles, Ordering::Relaxed);
        notes
            .parts_turned
            .fetch_add(shells.turned, Ordering::Relaxed);
        let places = places.into_inner();
        notes
            .left_off_found
            .fetch_add(places.found, Ordering::Relaxed);
        if let Ok(mut kept) = notes.left_off.lock() {
            kept.extend(places.into_points());
        }
    }
    Ok(())
}

/// What one block of a slab made in the leaf pass.
enum Made {
    /// A coarse block's leaves.
    Coarse(u32, Box<BlockOut>),
    /// A refined block's agreed coarse corner signs (its fine blocks come next).
    Refined(u32, Vec<u8>),
}

/// The octree, the leaves and their polygons, into a sink.
fn contour_into<S: Sampler>(
    sampler: &S,
    settings: &MeshSettings,
    merging: Merging,
    block_shift: u32,
    sink: &mut dyn MeshSink,
) -> Result<(), MeshError> {
    let progress = settings.progress.as_ref();
    let cancelled = || {
        settings
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    };
    let depth = u32::from(settings.depth);
    let grid = Grid::new(&settings.bounds, depth, block_shift);
    if let Some(p) = progress {
        p(0.0);
    }
    let mut tree = Octree::build(sampler, grid);
    if cancelled() {
        return Err(MeshError::Cancelled);
    }
    let blocks = std::mem::take(&mut tree.blocks);
    let coords: Vec<[i64; 3]> = blocks.iter().map(|b| b.coords).collect();
    let mut locals: Vec<Option<S::Local>> = blocks.into_iter().map(|b| Some(b.local)).collect();
    let n = grid.blocks_per_side() as usize;
    let mut slabs: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (i, c) in coords.iter().enumerate() {
        slabs[c[2] as usize].push(i as u32);
    }
    for slab in &mut slabs {
        slab.sort_by_key(|&i| (coords[i as usize][1], coords[i as usize][0]));
    }

    // Blocks sampled finer (`refined.rs`).
    let levels = settings
        .refine
        .as_ref()
        .map_or(0, |r| u32::from(r.levels.min(refined::MAX_LEVELS)));
    let levels = levels.min(u32::from(MAX_DEPTH).saturating_sub(depth));
    let lat = Lattices::new(grid, levels);
    let is_refined: Vec<bool> = coords
        .iter()
        .map(|c| {
            levels > 0
                && settings
                    .refine
                    .as_ref()
                    .is_some_and(|r| r.blocks.contains(c))
        })
        .collect();
    let mut fine = FineState::new(coords.len());
    if let Some(notes) = &settings.notes {
        notes
            .blocks
            .fetch_add(coords.len() as u64, Ordering::Relaxed);
        let refined = is_refined.iter().filter(|&&r| r).count() as u64;
        notes.refined_blocks.fetch_add(refined, Ordering::Relaxed);
    }

    let pool = EvalPool::new(sampler);
    // The whole field, for what cells on both sides of a block face must read alike.
    let root = sampler.root();
    let s = hermite::side(&grid);
    let words = (s * s * s).div_ceil(64);
    let mut bits: Vec<Option<Vec<u64>>> = vec![None; coords.len()];
    let mut records: Vec<Option<Record>> = (0..coords.len()).map(|_| None).collect();
    let mut above = AboveBlocks::new(grid, merging);
    let mut emitter = Emitter {
        sink,
        next: 0,
        seam_faces: HashMap::new(),
        deferred: Vec::new(),
        tris: Vec::new(),
    };
    let report = Reporter::new(progress, coords.len(), 0.1, 0.99);
    let refined = Refined {
        sampler,
        pool: &pool,
        root: &root,
        lat,
        tree: &tree,
        is_refined: &is_refined,
        coords: &coords,
        merging: match &settings.refine {
            Some(r) if r.tight_merges => merging.scaled(0.5f64.powi(levels as i32)),
            _ => merging,
        },
    };

    let own_signs = |slab: &[u32], locals: &[Option<S::Local>]| -> Vec<(u32, Vec<u64>)> {
        slab.par_iter()
            .map_init(
                || (pool.take(), Scratch::default()),
                |(guard, scratch), &b| {
                    let mut out = vec![0u64; words];
                    if let Some(local) = &locals[b as usize] {
                        hermite::own_signs(
                            sampler,
                            guard.get(),
                            local,
                            &grid,
                            coords[b as usize],
                            scratch,
                            &mut out,
                        );
                    }
                    (b, out)
                },
            )
            .collect()
    };
    if let Some(first) = slabs.first() {
        for (b, out) in own_signs(first, &locals) {
            bits[b as usize] = Some(out);
        }
        refined.expand(first, &locals, &mut fine);
    }
    for z in 0..n {
        if cancelled() {
            return Err(MeshError::Cancelled);
        }
        if z + 1 < n {
            for (b, out) in own_signs(&slabs[z + 1], &locals) {
                bits[b as usize] = Some(out);
            }
            refined.expand(&slabs[z + 1], &locals, &mut fine);
        }
        // (2) This slab's leaves; a refined block's agreed coarse signs.
        let empty: Vec<u64> = vec![0; words];
        let bits_of = |b: u32| -> &[u64] { bits[b as usize].as_deref().unwrap_or(&empty) };
        let made: Vec<Made> = slabs[z]
            .par_iter()
            .map_init(
                || (pool.take(), Pass2Scratch::default()),
                |(guard, sc), &b| {
                    let c = coords[b as usize];
                    let neighbours: [Class; 27] = std::array::from_fn(|k| {
                        let d = [k as i64 % 3 - 1, (k as i64 / 3) % 3 - 1, k as i64 / 9 - 1];
                        tree.class([0, 1, 2].map(|i| c[i] + d[i]))
                    });
                    hermite::canonical_signs(&grid, &neighbours, bits_of, &mut sc.signs);
                    if is_refined[b as usize] {
                        report.tick();
                        return Made::Refined(b, sc.signs.clone());
                    }
                    let mut out = BlockOut::default();
                    if let Some(local) = &locals[b as usize] {
                        hermite::crossings(
                            sampler,
                            guard.get(),
                            local,
                            &grid,
                            c,
                            &sc.signs,
                            &mut sc.scratch,
                            &mut sc.edges,
                            &mut sc.slots,
                            &mut sc.crossings,
                        );
                        let input = BlockInput {
                            grid: &grid,
                            coords: c,
                            signs: &sc.signs,
                            edge_slot: &sc.slots,
                            edges: &sc.edges,
                            crossings: &sc.crossings,
                            merging,
                            whole: true,
                            seam_joined: None,
                            seam_sides: 0,
                        };
                        leaf::build(
                            sampler,
                            guard.get(),
                            (&root, local),
                            &input,
                            &mut sc.leaf,
                            &mut out,
                        );
                    }
                    report.tick();
                    Made::Coarse(b, Box::new(out))
                },
            )
            .collect();
        let mut refined_here = Vec::new();
        for m in made {
            match m {
                Made::Coarse(b, out) => {
                    above.add_block(coords[b as usize], out.candidate, !out.cells.is_empty());
                    let ids = vec![NO_VERT; out.vertices.len()];
                    records[b as usize] = Some(Record { out: *out, ids });
                }
                Made::Refined(b, signs) => {
                    above.add_block(coords[b as usize], None, true);
                    fine.set_coarse_signs(b, signs);
                    refined_here.push(b);
                }
            }
        }
        if !refined_here.is_empty() {
            refined.leaves(z as i64, &refined_here, &locals, &mut fine, &mut records);
        }
        for &b in &slabs[z] {
            bits[b as usize] = None;
            locals[b as usize] = None;
        }

        // (3) This slab's polygons, in block order (a refined block's fine blocks in turn).
        let cells = refined.cells(&fine, &records);
        let polys: Vec<Vec<Polygon>> = slabs[z]
            .par_iter()
            .map_init(
                || pool.take(),
                |guard, &b| {
                    let mut polys = Vec::new();
                    let c = coords[b as usize];
                    if is_refined[b as usize] {
                        refined.polygons(&cells, &fine, b, &mut polys);
                        return polys;
                    }
                    let Some(me) = &records[b as usize] else {
                        return polys;
                    };
                    let mut beside = Vec::new();
                    let missing = contour::polygons(
                        &grid,
                        (b, c, &me.out),
                        |d| {
                            let nc = [0, 1, 2].map(|i| c[i] + d[i]);
                            match tree.class(nc) {
                                Class::Block(i) if is_refined[i as usize] => Near::Seam,
                                Class::Block(i) => match &records[i as usize] {
                                    Some(r) => Near::Cells(i, nc, &r.out),
                                    None => Near::Nothing,
                                },
                                _ => Near::Nothing,
                            }
                        },
                        &mut polys,
                        &mut beside,
                    );
                    debug_assert_eq!(missing, 0, "edge without its 4 cells");
                    if !beside.is_empty() || levels > 0 {
                        refined.coarse_seam_polygons(
                            guard.get(),
                            &cells,
                            &fine,
                            b,
                            &beside,
                            &mut polys,
                        );
                    }
                    polys
                },
            )
            .collect();
        for block_polys in polys {
            for poly in block_polys {
                emitter.polygon(poly, &mut records, &mut above)?;
            }
        }

        // (4) Merges above the blocks, and the polygons that waited for them.
        {
            let mut guard = pool.take();
            above.finish_slab(z as i64, sampler, guard.get());
        }
        emitter.sweep(&mut above)?;
        above.prune(z as i64);
        if z >= 1 {
            for &b in &slabs[z - 1] {
                records[b as usize] = None;
            }
            fine.drop_slab(&slabs[z - 1], z as i64 - 1, &mut records);
        }
    }
    // Everything is decided once the last slab is: the leaves still waiting are final.
    emitter.sweep(&mut above)?;
    debug_assert!(emitter.deferred.is_empty(), "polygons left waiting");
    Ok(())
}

/// Gives vertices their global indices and polygons their triangles, in order.
struct Emitter<'s> {
    sink: &'s mut dyn MeshSink,
    next: u32,
    /// Global indices of the seams' face vertices (`Ref::SeamFace`).
    seam_faces: HashMap<(u8, [i64; 3], u8), u32>,
    /// Polygons waiting for a candidate's leaf (all their other corners global).
    deferred: Vec<Polygon>,
    tris: Vec<([u32; 3], [[f32; 3]; 3])>,
}

impl Emitter<'_> {
    fn new_vertex(&mut self, p: [f32; 3]) -> Result<u32, MeshError> {
        let id = self.next;
        self.next = self.next.checked_add(1).ok_or(MeshError::TooManyVertices)?;
        self.sink.vertex(p).map_err(MeshError::Write)?;
        Ok(id)
    }

    /// Takes a polygon fresh from a block: its block-local corners get global indices now
    /// (their blocks will be dropped), and it is finished or set aside to wait.
    fn polygon(
        &mut self,
        mut poly: Polygon,
        records: &mut [Option<Record>],
        above: &mut AboveBlocks,
    ) -> Result<(), MeshError> {
        for slot in poly.corners_mut() {
            if let Ref::SeamFace(n, at, pair) = slot.r {
                let id = match self.seam_faces.get(&(n, at, pair)) {
                    Some(&id) => id,
                    None => {
                        let id = self.new_vertex(slot.pos)?;
                        self.seam_faces.insert((n, at, pair), id);
                        id
                    }
                };
                slot.r = Ref::Global(id);
                continue;
            }
            if let Ref::Local { block, vert } = slot.r {
                let Some(rec) = records[block as usize].as_mut() else {
                    continue;
                };
                let mut id = rec.ids[vert as usize];
                if id == NO_VERT {
                    id = self.new_vertex(rec.out.vertices[vert as usize])?;
                    rec.ids[vert as usize] = id;
                }
                slot.r = Ref::Global(id);
            }
        }
        if self.resolve(&mut poly, above)? {
            self.finish(&poly)
        } else {
            self.deferred.push(poly);
            Ok(())
        }
    }

    /// Replaces candidate corners whose leaf is known by that leaf's vertex; true when none
    /// is left.
    fn resolve(&mut self, poly: &mut Polygon, above: &mut AboveBlocks) -> Result<bool, MeshError> {
        let mut done = true;
        for slot in poly.corners_mut() {
            let Ref::Candidate(c) = slot.r else { continue };
            match above.resolve(c) {
                Resolved::Waiting => done = false,
                Resolved::Leaf(key) => {
                    let Some((pos, mut id)) = above.vertex(key) else {
                        done = false;
                        continue;
                    };
                    let p = pos.as_vec3().to_array();
                    if id == NO_VERT {
                        id = self.new_vertex(p)?;
                        above.set_id(key, id);
                    }
                    slot.r = Ref::Global(id);
                    slot.pos = p;
                }
            }
        }
        Ok(done)
    }

    /// Retries every waiting polygon.
    fn sweep(&mut self, above: &mut AboveBlocks) -> Result<(), MeshError> {
        let waiting = std::mem::take(&mut self.deferred);
        for mut poly in waiting {
            if self.resolve(&mut poly, above)? {
                self.finish(&poly)?;
            } else {
                self.deferred.push(poly);
            }
        }
        Ok(())
    }

    /// Triangulates a polygon whose corners are all global and hands the triangles over.
    fn finish(&mut self, poly: &Polygon) -> Result<(), MeshError> {
        let corners: Vec<(u32, [f32; 3], bool)> = poly
            .corners()
            .iter()
            .map(|s| match s.r {
                Ref::Global(id) => (id, s.pos, s.face),
                // Not reachable: callers resolve every corner first.
                Ref::Local { .. } | Ref::Candidate(_) | Ref::SeamFace(..) => {
                    (NO_VERT, s.pos, s.face)
                }
            })
            .collect();
        if corners.iter().any(|c| c.0 == NO_VERT) {
            return Err(MeshError::Write(io::Error::other(
                "internal error: a polygon corner without a vertex",
            )));
        }
        let mut tris = std::mem::take(&mut self.tris);
        tris.clear();
        let mut centre_err = None;
        contour::triangulate(
            &corners,
            || match self.new_vertex(poly.centre) {
                Ok(id) => (id, poly.centre),
                Err(e) => {
                    centre_err = Some(e);
                    (NO_VERT, poly.centre)
                }
            },
            &mut tris,
        );
        if let Some(e) = centre_err {
            return Err(e);
        }
        for (t, c) in &tris {
            self.sink.triangle(*t, *c).map_err(MeshError::Write)?;
        }
        self.tris = tris;
        Ok(())
    }
}
