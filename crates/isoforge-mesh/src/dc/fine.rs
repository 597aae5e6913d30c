//! A refined block's fine blocks on their way through the stream (`stream.rs`; what a
//! refined block is: `refined.rs`): cut and sampled when the slab's own signs are, given
//! their seams and leaves after the slab's coarse leaves, and their polygons (the seams'
//! among them) with the slab's polygons. A slab's fine blocks are dropped with its coarse
//! blocks, after the next slab's polygons.

use std::collections::HashMap;

use rayon::prelude::*;

use super::contour::{self, Near, Polygon};
use super::hermite::{self, Scratch};
use super::leaf::{self, BlockInput, BlockOut, Merging, NO_VERT, OwnedEdge};
use super::octree::{self, Class, Octree, Sub};
use super::refined::{self, CellsAt, FineNear, Lattices, Lookup, Seams, SeamsMade};
use super::sampler::{EvalPool, Sampler};
use super::stream::{Pass2Scratch, Record};

/// A refined block's fine blocks, from when its slab's signs are sampled until the slab
/// after it is done.
struct FineBlock<L> {
    /// In `octree::refine_block`'s order.
    subs: Vec<FineSub<L>>,
    /// The block's agreed coarse corner signs (its closed box), for its seams.
    coarse_signs: Vec<u8>,
}

/// One fine block of a refined block.
struct FineSub<L> {
    /// Proved empty, proved full, or sampled (then `rec` is its record).
    kind: SubKind,
    rec: u32,
    local: Option<L>,
    bits: Option<Vec<u64>>,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum SubKind {
    Empty,
    Full,
    Sampled,
}

impl<L> FineSub<L> {
    fn proved(kind: SubKind) -> Self {
        FineSub {
            kind,
            rec: NO_VERT,
            local: None,
            bits: None,
        }
    }
}

/// What the stream keeps of the refined blocks of the slabs at work.
pub struct FineState<L> {
    fine: HashMap<u32, FineBlock<L>>,
    seams: Seams,
    /// The record index the next sampled fine block gets (after every coarse block's).
    next_rec: u32,
}

impl<L> FineState<L> {
    /// Nothing yet; fine blocks' records come after the `blocks` coarse ones.
    pub fn new(blocks: usize) -> Self {
        FineState {
            fine: HashMap::new(),
            seams: Seams::default(),
            next_rec: blocks as u32,
        }
    }

    /// Records a refined block's agreed coarse corner signs, which its seams start from.
    pub fn set_coarse_signs(&mut self, b: u32, signs: Vec<u8>) {
        if let Some(fb) = self.fine.get_mut(&b) {
            fb.coarse_signs = signs;
        }
    }

    /// Drops what the slab's refined blocks kept (their fine records too) and the seams
    /// made with them.
    pub fn drop_slab(&mut self, slab: &[u32], z: i64, records: &mut [Option<Record>]) {
        for b in slab {
            if let Some(fb) = self.fine.remove(b) {
                for sub in fb.subs {
                    if sub.kind == SubKind::Sampled {
                        records[sub.rec as usize] = None;
                    }
                }
            }
        }
        self.seams.prune(z);
    }
}

/// What the fine blocks' passes read: the field, the lattices, the coarse blocks.
pub struct Refined<'a, S: Sampler> {
    /// The field.
    pub sampler: &'a S,
    /// Evaluators for the workers.
    pub pool: &'a EvalPool<'a, S>,
    /// The whole field, which seams are read from.
    pub root: &'a S::Local,
    /// Both lattices.
    pub lat: Lattices,
    /// The coarse octree.
    pub tree: &'a Octree<S::Local>,
    /// Per coarse block, whether it is refined.
    pub is_refined: &'a [bool],
    /// Per coarse block, its coordinates.
    pub coords: &'a [[i64; 3]],
    /// How far leaves merge.
    pub merging: Merging,
}

impl<S: Sampler> Refined<'_, S> {
    /// Whether the coarse block at `c` is refined.
    pub fn refined_at(&self, c: [i64; 3]) -> bool {
        matches!(self.tree.class(c), Class::Block(i) if self.is_refined[i as usize])
    }

    fn per_side(&self) -> i64 {
        1 << self.lat.levels
    }

    fn words(&self) -> usize {
        let s = self.lat.fine.block + 1;
        (s * s * s).div_ceil(64)
    }

    /// Own signs of fine blocks `(b, k)` with their fields.
    fn own_signs(&self, jobs: Vec<(u32, usize, S::Local)>) -> Vec<(u32, usize, Vec<u64>)> {
        let words = self.words();
        let per_side = self.per_side();
        jobs.into_par_iter()
            .map_init(
                || (self.pool.take(), Scratch::default()),
                |(guard, scratch), (b, k, local)| {
                    let mut out = vec![0u64; words];
                    let sub = sub_coords(self.coords[b as usize], per_side, k);
                    hermite::own_signs(
                        self.sampler,
                        guard.get(),
                        &local,
                        &self.lat.fine,
                        sub,
                        scratch,
                        &mut out,
                    );
                    (b, k, out)
                },
            )
            .collect()
    }

    /// Cuts a slab's refined blocks into fine blocks (intervals prune them) and samples
    /// the fine blocks that may hold surface.
    pub fn expand(
        &self,
        slab: &[u32],
        locals: &[Option<S::Local>],
        state: &mut FineState<S::Local>,
    ) {
        let mut jobs = Vec::new();
        for &b in slab {
            let (true, Some(local)) = (self.is_refined[b as usize], &locals[b as usize]) else {
                continue;
            };
            let subs = octree::refine_block(
                self.sampler,
                self.lat.fine,
                self.lat.levels,
                self.coords[b as usize],
                local,
            );
            let subs: Vec<FineSub<S::Local>> = subs
                .into_iter()
                .enumerate()
                .map(|(k, sub)| match sub {
                    Sub::Empty => FineSub::proved(SubKind::Empty),
                    Sub::Full => FineSub::proved(SubKind::Full),
                    Sub::Block(l) => {
                        jobs.push((b, k, l.clone()));
                        let rec = state.next_rec;
                        state.next_rec += 1;
                        FineSub {
                            kind: SubKind::Sampled,
                            rec,
                            local: Some(l),
                            bits: None,
                        }
                    }
                })
                .collect();
            state.fine.insert(
                b,
                FineBlock {
                    subs,
                    coarse_signs: Vec::new(),
                },
            );
        }
        for (b, k, out) in self.own_signs(jobs) {
            if let Some(fb) = state.fine.get_mut(&b) {
                fb.subs[k].bits = Some(out);
            }
        }
    }

    /// A slab's fine leaves: the seams of its refined blocks, the fine blocks their seams
    /// make meshed after all, then every sampled fine block's agreed signs, hermite data
    /// and leaves, into `records`.
    pub fn leaves(
        &self,
        z: i64,
        refined_here: &[u32],
        locals: &[Option<S::Local>],
        state: &mut FineState<S::Local>,
        records: &mut Vec<Option<Record>>,
    ) {
        let refined_at = |c: [i64; 3]| self.refined_at(c);
        let made: Vec<SeamsMade> = refined_here
            .par_iter()
            .map_init(
                || self.pool.take(),
                |guard, &b| {
                    let signs = state
                        .fine
                        .get(&b)
                        .map_or(&[][..], |fb| &fb.coarse_signs[..]);
                    refined::seams_of(
                        self.sampler,
                        guard.get(),
                        self.root,
                        &self.lat,
                        self.coords[b as usize],
                        signs,
                        &refined_at,
                    )
                },
            )
            .collect();
        for m in made {
            state.seams.add(z, m);
        }
        self.sample_where_seams_say(refined_here, locals, state);
        if records.len() < state.next_rec as usize {
            records.resize_with(state.next_rec as usize, || None);
        }
        let built = self.build(refined_here, state);
        for (rec, out) in built {
            let ids = vec![NO_VERT; out.vertices.len()];
            records[rec as usize] = Some(Record { out, ids });
        }
        // Their signs are read no more: the next slab's fine blocks own their lower faces.
        for &b in refined_here {
            if let Some(fb) = state.fine.get_mut(&b) {
                for sub in &mut fb.subs {
                    sub.bits = None;
                    sub.local = None;
                }
            }
        }
    }

    /// Fine blocks proved empty or full whose seam has a sign of the other kind
    /// (`refined::needs_sampling`) are sampled after all.
    fn sample_where_seams_say(
        &self,
        refined_here: &[u32],
        locals: &[Option<S::Local>],
        state: &mut FineState<S::Local>,
    ) {
        let refined_at = |c: [i64; 3]| self.refined_at(c);
        let per_side = self.per_side();
        let mut demote: Vec<(u32, usize)> = Vec::new();
        for &b in refined_here {
            let Some(fb) = state.fine.get(&b) else {
                continue;
            };
            let c = self.coords[b as usize];
            for (k, sub) in fb.subs.iter().enumerate() {
                if sub.kind == SubKind::Sampled {
                    continue;
                }
                let s = sub_coords(c, per_side, k);
                let sign = |p: [i64; 3]| {
                    refined::virtual_sign(&state.seams, &self.lat, c, &fb.coarse_signs, p)
                };
                if refined::needs_sampling(
                    &self.lat,
                    s,
                    sub.kind == SubKind::Full,
                    &refined_at,
                    sign,
                ) {
                    demote.push((b, k));
                }
            }
        }
        let mut jobs = Vec::new();
        for &(b, k) in &demote {
            let (Some(local), Some(fb)) = (&locals[b as usize], state.fine.get_mut(&b)) else {
                continue;
            };
            let sub = &mut fb.subs[k];
            sub.kind = SubKind::Sampled;
            sub.rec = state.next_rec;
            state.next_rec += 1;
            sub.local = Some(local.clone());
            jobs.push((b, k, local.clone()));
        }
        for (b, k, out) in self.own_signs(jobs) {
            if let Some(fb) = state.fine.get_mut(&b) {
                fb.subs[k].bits = Some(out);
            }
        }
    }

    /// What lies at fine block `s`, for a fine block's agreed signs.
    fn near<'s>(&self, fine: &'s HashMap<u32, FineBlock<S::Local>>, s: [i64; 3]) -> FineNear<'s> {
        let cb = self.lat.coarse_block_of(s);
        let Class::Block(i) = self.tree.class(cb) else {
            return FineNear::Coarse;
        };
        if !self.is_refined[i as usize] {
            return FineNear::Coarse;
        }
        let Some(fb) = fine.get(&i) else {
            return FineNear::Coarse;
        };
        let m = self.per_side();
        let l = [0, 1, 2].map(|a| s[a] - cb[a] * m);
        let sub = &fb.subs[(l[0] + m * (l[1] + m * l[2])) as usize];
        match sub.kind {
            SubKind::Empty => FineNear::Empty,
            SubKind::Full => FineNear::Full,
            SubKind::Sampled => FineNear::Block(sub.bits.as_deref().unwrap_or(&[])),
        }
    }

    /// Every sampled fine block of the slab's refined blocks: agreed signs, hermite data,
    /// leaves.
    fn build(&self, refined_here: &[u32], state: &FineState<S::Local>) -> Vec<(u32, BlockOut)> {
        let refined_at = |c: [i64; 3]| self.refined_at(c);
        let per_side = self.per_side();
        let jobs: Vec<(u32, usize)> = refined_here
            .iter()
            .filter_map(|&b| state.fine.get(&b).map(|fb| (b, fb)))
            .flat_map(|(b, fb)| {
                fb.subs
                    .iter()
                    .enumerate()
                    .filter(|(_, sub)| sub.kind == SubKind::Sampled)
                    .map(move |(k, _)| (b, k))
            })
            .collect();
        jobs.par_iter()
            .map_init(
                || (self.pool.take(), Pass2Scratch::default()),
                |(guard, sc), &(b, k)| {
                    let c = self.coords[b as usize];
                    let fb = &state.fine[&b];
                    let sub = &fb.subs[k];
                    let s = sub_coords(c, per_side, k);
                    let near: [FineNear<'_>; 27] = std::array::from_fn(|q| {
                        let d = [q as i64 % 3 - 1, (q as i64 / 3) % 3 - 1, q as i64 / 9 - 1];
                        self.near(&state.fine, [0, 1, 2].map(|a| s[a] + d[a]))
                    });
                    let sign = |p: [i64; 3]| {
                        refined::virtual_sign(&state.seams, &self.lat, c, &fb.coarse_signs, p)
                    };
                    refined::fine_signs(&self.lat, s, &near, sign, &mut sc.signs);
                    let mut out = BlockOut::default();
                    if let Some(local) = &sub.local {
                        hermite::crossings(
                            self.sampler,
                            guard.get(),
                            local,
                            &self.lat.fine,
                            s,
                            &sc.signs,
                            &mut sc.scratch,
                            &mut sc.edges,
                            &mut sc.slots,
                            &mut sc.crossings,
                        );
                        let joined = |at: [i64; 3], n: usize, side: usize| {
                            refined::seam_joined(
                                &state.seams,
                                &self.lat,
                                c,
                                &refined_at,
                                at,
                                n,
                                side,
                            )
                        };
                        let input = BlockInput {
                            grid: &self.lat.fine,
                            coords: s,
                            signs: &sc.signs,
                            edge_slot: &sc.slots,
                            edges: &sc.edges,
                            crossings: &sc.crossings,
                            merging: self.merging,
                            whole: false,
                            seam_joined: Some(&joined),
                            seam_sides: seam_sides(&self.lat, c, k, &refined_at),
                        };
                        leaf::build(
                            self.sampler,
                            guard.get(),
                            (self.root, local),
                            &input,
                            &mut sc.leaf,
                            &mut out,
                        );
                    }
                    (sub.rec, out)
                },
            )
            .collect()
    }

    /// The cells of both lattices, as the seams' polygons look them up.
    pub fn cells<'c>(
        &'c self,
        state: &'c FineState<S::Local>,
        records: &'c [Option<Record>],
    ) -> Cells<'c, S::Local> {
        Cells {
            tree: self.tree,
            refined: self.is_refined,
            records,
            fine: &state.fine,
            lat: &self.lat,
        }
    }

    /// A refined block's polygons: each sampled fine block's own, its seam edges' among
    /// them.
    pub fn polygons(
        &self,
        cells: &Cells<'_, S::Local>,
        state: &FineState<S::Local>,
        b: u32,
        polys: &mut Vec<Polygon>,
    ) {
        let lat = &self.lat;
        let Some(fb) = state.fine.get(&b) else {
            return;
        };
        let c = self.coords[b as usize];
        let block = lat.block();
        for (k, sub) in fb.subs.iter().enumerate() {
            if sub.kind != SubKind::Sampled {
                continue;
            }
            let Some(me) = &cells.records[sub.rec as usize] else {
                continue;
            };
            let s = sub_coords(c, self.per_side(), k);
            let mut beside = Vec::new();
            let missing = contour::polygons(
                &lat.fine,
                (sub.rec, s, &me.out),
                |d| {
                    let ns = [0, 1, 2].map(|i| s[i] + d[i]);
                    match cells.lookup(lat.coarse_block_of(ns)) {
                        Lookup::Refined => match cells.fine(ns) {
                            Some((rec, out)) => Near::Cells(rec, ns, out),
                            None => Near::Nothing,
                        },
                        _ => Near::Seam,
                    }
                },
                polys,
                &mut beside,
            );
            debug_assert_eq!(missing, 0, "fine edge without its 4 cells");
            for e in &beside {
                let at = [0, 1, 2].map(|a| s[a] * block + i64::from(e.at[a]));
                seam_polygon(
                    cells,
                    &state.seams,
                    at,
                    e.axis as usize,
                    e.pos,
                    e.start_inside,
                    polys,
                );
            }
        }
    }

    /// The seam polygons coarse block `b` owns (`refined::coarse_seam_edges`): `beside`
    /// are its coarse edges that `contour::polygons` set aside as a seam's.
    pub fn coarse_seam_polygons(
        &self,
        ev: &mut S::Evals,
        cells: &Cells<'_, S::Local>,
        state: &FineState<S::Local>,
        b: u32,
        beside: &[OwnedEdge],
        polys: &mut Vec<Polygon>,
    ) {
        let refined_at = |c: [i64; 3]| self.refined_at(c);
        let mut edges = Vec::new();
        let c = self.coords[b as usize];
        refined::coarse_seam_edges(&self.lat, &state.seams, c, beside, &refined_at, &mut edges);
        for e in &edges {
            let centre = refined::seam_crossing(self.sampler, ev, self.root, &self.lat, e);
            seam_polygon(
                cells,
                &state.seams,
                e.at,
                e.axis,
                centre,
                e.start_inside,
                polys,
            );
        }
    }
}

/// The polygon of one fine seam edge, if the edge is a leaf edge.
fn seam_polygon<L: Clone + Send + Sync>(
    cells: &Cells<'_, L>,
    seams: &Seams,
    at: [i64; 3],
    axis: usize,
    centre: [f32; 3],
    start_inside: bool,
    polys: &mut Vec<Polygon>,
) {
    let lat = cells.lat;
    let around = lat.around(cells, seams, at, axis);
    debug_assert!(around.is_some(), "seam edge without its 4 cells");
    let Some(around) = around else {
        return;
    };
    let face = |q: usize| lat.seam_face_vertex(seams, at, axis, q);
    if let Some(poly) = contour::polygon(axis, around, centre, start_inside, face) {
        polys.push(poly);
    }
}

/// Looks cells up on both lattices for the seams' polygons.
pub struct Cells<'a, L> {
    tree: &'a Octree<L>,
    refined: &'a [bool],
    records: &'a [Option<Record>],
    fine: &'a HashMap<u32, FineBlock<L>>,
    lat: &'a Lattices,
}

impl<L: Clone + Send + Sync> CellsAt for Cells<'_, L> {
    fn lookup(&self, coarse: [i64; 3]) -> Lookup<'_> {
        match self.tree.class(coarse) {
            Class::Block(i) if self.refined[i as usize] => Lookup::Refined,
            Class::Block(i) => match &self.records[i as usize] {
                Some(r) => Lookup::Coarse(i, &r.out),
                None => Lookup::Nothing,
            },
            _ => Lookup::Nothing,
        }
    }
    fn fine(&self, sub: [i64; 3]) -> Option<(u32, &BlockOut)> {
        let cb = self.lat.coarse_block_of(sub);
        let Class::Block(i) = self.tree.class(cb) else {
            return None;
        };
        let fb = self.fine.get(&i)?;
        let m = 1i64 << self.lat.levels;
        let l = [0, 1, 2].map(|a| sub[a] - cb[a] * m);
        let entry = &fb.subs[(l[0] + m * (l[1] + m * l[2])) as usize];
        if entry.kind != SubKind::Sampled {
            return None;
        }
        let rec = self.records[entry.rec as usize].as_ref()?;
        Some((entry.rec, &rec.out))
    }
}

/// The faces of fine block `k` of refined block `coords` that lie on a seam (bit
/// `2 axis + side`): on the refined block's boundary, with a block not refined across.
fn seam_sides(
    lat: &Lattices,
    coords: [i64; 3],
    k: usize,
    refined: &impl Fn([i64; 3]) -> bool,
) -> u8 {
    let m = 1i64 << lat.levels;
    let k = k as i64;
    let l = [k % m, (k / m) % m, k / (m * m)];
    let mut sides = 0u8;
    for a in 0..3 {
        for side in 0..2i64 {
            let edge = if side == 0 { 0 } else { m - 1 };
            if l[a] != edge {
                continue;
            }
            let mut across = coords;
            across[a] += 2 * side - 1;
            if !refined(across) {
                sides |= 1 << (2 * a as i64 + side);
            }
        }
    }
    sides
}

/// The fine block at place `k` of refined block `coords`, in fine block units.
fn sub_coords(coords: [i64; 3], per_side: i64, k: usize) -> [i64; 3] {
    let k = k as i64;
    let l = [
        k % per_side,
        (k / per_side) % per_side,
        k / (per_side * per_side),
    ];
    [0, 1, 2].map(|a| coords[a] * per_side + l[a])
}
