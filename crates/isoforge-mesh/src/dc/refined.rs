//! Blocks sampled finer: a refined block's cells are `R = 2^levels` times smaller a side
//! than its neighbours', so a feature narrower than the lattice there is resolved without
//! sampling the whole model finer.
//!
//! A refined block is cut into fine blocks of the usual size on the finer lattice, pruned by
//! intervals (`octree::refine_block`) and meshed by the same stages as any block (hermite
//! data, leaves, polygons). Octree dual contouring joins leaves of any sizes across a face
//! (`contour.rs`); what is new is the seam: the fine lattice points on a face that a refined
//! block shares with a coarse one take the signs `seam.rs` gives them, which make the coarse
//! face's surface exactly (one fine crossing on each crossed coarse edge, curves that join
//! the coarse crossings in the coarse pairing), so the coarse block is meshed as if its
//! neighbour were coarse too, and the fine cells along the seam connect to its leaves.
//!
//! Who does what at a seam, so that every crossing edge of the finer lattice gets its one
//! polygon: an edge belongs to the block whose half-open range holds its lower end, as on
//! one lattice. A fine block's seam edges come out of its polygons' pass (`Near::Seam`);
//! a coarse block's are the fine pieces of its own coarse edges beside a refined block and
//! the fine edges inside its lower faces that a refined block is across
//! ([`coarse_seam_edges`]). Either way the four cells around the edge are looked up on
//! both lattices ([`Lattices::around`]) and joined by `contour::polygon`.
//!
//! Signs at a lattice point are one value wherever they are read: a point on a coarse
//! block's closed box takes its seam sign ([`virtual_sign`]); any other fine point the
//! rule of one lattice (proofs, then the owner's sample, as `hermite.rs`). A fine block
//! that intervals proved empty or full but whose seam face has a sign of the other kind is
//! sampled after all ([`needs_sampling`]).

use std::collections::{HashMap, HashSet};

use glam::DVec3;

use super::cell::{edge_id, other_axes};
use super::contour::{AROUND, Around, Ref, STEPS, Slot};
use super::hermite::corner_index;
use super::leaf::{BlockOut, OwnedEdge, face_middle};
use isoforge_field::Bounds;

use super::octree::{BLOCK_SHIFT, Grid};
use super::sampler::Sampler;
use super::seam::{self, FaceSeam, NO_SEGMENT};

/// Which blocks to sample finer, and how much finer.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Refinement {
    /// Levels finer: the cells of a refined block are `2^levels` times smaller a side (at
    /// most [`MAX_LEVELS`], and never past [`MAX_DEPTH`](super::MAX_DEPTH) in all).
    pub levels: u8,
    /// The blocks (of [`BLOCK_SHIFT`](super::octree::BLOCK_SHIFT) cells a side at the
    /// settings' depth), by block coordinates.
    pub blocks: HashSet<[i64; 3]>,
    /// Whether the refined blocks' leaves merge under the tolerance scaled to their fine
    /// cell (as a mesh of the fine lattice would merge them) rather than under the mesh's
    /// own. The merge bounds a merged vertex's distance to its crossings' planes, not the
    /// chords between leaves: fine leaves merged as far as coarse ones bring back the
    /// chords that missed (spaceship's mast meeting its hull's ripples, depth 8 refined
    /// three levels: 2.18 tolerances; the whole model at depth 11 under depth 8's tolerance,
    /// 2.26; with tight merges 0.98).
    pub tight_merges: bool,
}

/// The most levels a block may be refined by: 16 times finer a side is 256 times the
/// samples of a block where the surface crosses it (16³ fine blocks, pruned to those the
/// surface passes through).
pub const MAX_LEVELS: u8 = 4;

impl Refinement {
    /// The blocks within `margin` finest cells of any of `points` (on the lattice of
    /// `depth` over `bounds`), each with the largest distance among the points near it:
    /// the blocks to refine for the sample points of a mesh that miss a tolerance. The
    /// margin takes in the block across a face the point is close to: a refined block's
    /// seam keeps the coarse lattice's surface on it (`seam.rs`), so a miss just beside the
    /// seam needs the block across refined too.
    pub fn blocks_near(
        bounds: &Bounds,
        depth: u8,
        points: &[([f64; 3], f64)],
        margin: f64,
    ) -> HashMap<[i64; 3], f64> {
        let grid = Grid::new(bounds, u32::from(depth.min(super::MAX_DEPTH)), BLOCK_SHIFT);
        let span = grid.cell * grid.block as f64;
        let per_side = grid.blocks_per_side();
        let reach = margin * grid.cell;
        let mut out: HashMap<[i64; 3], f64> = HashMap::new();
        for &(p, d) in points {
            let lo = [0, 1, 2].map(|a| ((p[a] - reach - grid.origin[a]) / span).floor() as i64);
            let hi = [0, 1, 2].map(|a| ((p[a] + reach - grid.origin[a]) / span).floor() as i64);
            for z in lo[2].max(0)..=hi[2].min(per_side - 1) {
                for y in lo[1].max(0)..=hi[1].min(per_side - 1) {
                    for x in lo[0].max(0)..=hi[0].min(per_side - 1) {
                        let e = out.entry([x, y, z]).or_insert(0.0);
                        *e = e.max(d);
                    }
                }
            }
        }
        out
    }
}

/// The coarse and the fine lattice, and how their indices relate.
#[derive(Clone, Copy, Debug)]
pub struct Lattices {
    /// The lattice of the settings' depth.
    pub coarse: Grid,
    /// The lattice `levels` finer, with blocks of the same number of cells.
    pub fine: Grid,
    /// Levels between them.
    pub levels: u32,
    /// Fine cells per coarse cell side.
    pub r: i64,
}

impl Lattices {
    /// The lattices for `coarse` refined by `levels`.
    pub fn new(coarse: Grid, levels: u32) -> Lattices {
        let mut fine = coarse;
        fine.depth = coarse.depth + levels;
        fine.block_level = coarse.block_level + levels;
        fine.cell = coarse.cell / f64::from(1u32 << levels);
        Lattices {
            coarse,
            fine,
            levels,
            r: 1 << levels,
        }
    }

    /// Cells a block side (both lattices).
    pub fn block(&self) -> i64 {
        self.coarse.block as i64
    }

    /// The coarse block holding fine block `s`.
    pub fn coarse_block_of(&self, s: [i64; 3]) -> [i64; 3] {
        s.map(|c| c >> self.levels)
    }

    /// The coarse blocks whose closed boxes hold fine lattice point `p`.
    fn holding(&self, p: [i64; 3]) -> impl Iterator<Item = [i64; 3]> {
        let span = self.r * self.block();
        let range = p.map(|v| {
            let b = v.div_euclid(span);
            if v.rem_euclid(span) == 0 {
                (b - 1, b)
            } else {
                (b, b)
            }
        });
        (range[2].0..=range[2].1).flat_map(move |z| {
            (range[1].0..=range[1].1)
                .flat_map(move |y| (range[0].0..=range[0].1).map(move |x| [x, y, z]))
        })
    }

    /// True when fine lattice point `p` lies on the closed box of a coarse block that is not
    /// refined: a seam point.
    pub fn on_seam(&self, p: [i64; 3], refined: &impl Fn([i64; 3]) -> bool) -> bool {
        self.holding(p).any(|b| !refined(b))
    }
}

/// A seam's coarse edge: its axis and its lower coarse lattice corner.
pub type EdgeKey = (u8, [i64; 3]);
/// A seam's coarse face: its normal axis and its lowest coarse lattice corner.
pub type FaceKey = (u8, [i64; 3]);

/// The seam signs of the coarse edges and faces around the refined blocks of a few slabs.
#[derive(Default)]
pub struct Seams {
    /// Per crossed coarse edge on a seam, the signs of its `R + 1` fine points, and the
    /// slab that made it.
    pub edges: HashMap<EdgeKey, (Vec<bool>, i64)>,
    /// Per coarse face on a seam with a crossing, its fine signs, and the slab that made it.
    pub faces: HashMap<FaceKey, (FaceSeam, i64)>,
}

impl Seams {
    /// Adds what a slab's refined blocks made (the first of equal entries is kept: two
    /// blocks that share an edge make it alike from the same field).
    pub fn add(&mut self, slab: i64, made: SeamsMade) {
        for (k, v) in made.edges {
            self.edges.entry(k).or_insert((v, slab));
        }
        for (k, v) in made.faces {
            self.faces.entry(k).or_insert((v, slab));
        }
    }

    /// Forgets what slabs up to `slab` made.
    pub fn prune(&mut self, slab: i64) {
        self.edges.retain(|_, v| v.1 > slab);
        self.faces.retain(|_, v| v.1 > slab);
    }
}

/// What one refined block's seams are.
#[derive(Default)]
pub struct SeamsMade {
    edges: Vec<(EdgeKey, Vec<bool>)>,
    faces: Vec<(FaceKey, FaceSeam)>,
}

/// Builds the seams of refined block `coords`: every coarse edge and face on its closed box
/// that a block not refined also holds, where the coarse signs (`coarse_signs`, the block's
/// agreed corner signs) cross. The fine points are read from the whole field `root`, so
/// every block that builds the same edge builds it alike.
#[allow(clippy::too_many_arguments)]
pub fn seams_of<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    root: &S::Local,
    lat: &Lattices,
    coords: [i64; 3],
    coarse_signs: &[u8],
    refined: &impl Fn([i64; 3]) -> bool,
) -> SeamsMade {
    let grid = &lat.coarse;
    let b = lat.block();
    let s = (b + 1) as usize;
    let r = lat.r as usize;
    let base = coords.map(|c| c * b);
    let sign = |l: [i64; 3]| {
        coarse_signs[corner_index(s, l[0] as usize, l[1] as usize, l[2] as usize)] == 1
    };
    let mut made = SeamsMade::default();
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let mut zs = Vec::new();
    let mut out = Vec::new();
    let mut sample = |points: &[[f64; 3]], ev: &mut S::Evals| -> Vec<bool> {
        xs.clear();
        ys.clear();
        zs.clear();
        for p in points {
            xs.push(p[0]);
            ys.push(p[1]);
            zs.push(p[2]);
        }
        out.clear();
        out.resize(points.len(), 0.0);
        sampler.batch(ev, root, &xs, &ys, &zs, &mut out);
        out.iter().map(|&f| f < 0.0).collect()
    };
    let mut edge_signs: HashMap<EdgeKey, Vec<bool>> = HashMap::new();
    // Edges: along `a` from local corner `l`, on the closed box's boundary.
    for a in 0..3 {
        let (ab, ac) = other_axes(a);
        for k in 0..=b {
            for j in 0..=b {
                for i in 0..b {
                    let mut l = [0i64; 3];
                    l[a] = i;
                    l[ab] = j;
                    l[ac] = k;
                    let on = l[ab] == 0 || l[ab] == b || l[ac] == 0 || l[ac] == b;
                    if !on {
                        continue;
                    }
                    let mut end = l;
                    end[a] += 1;
                    let ends = [sign(l), sign(end)];
                    if ends[0] == ends[1] {
                        continue;
                    }
                    // A seam edge: a block not refined holds it (its middle's fine twin).
                    let mut mid = [0i64; 3];
                    for v in 0..3 {
                        mid[v] = (base[v] + l[v]) * lat.r;
                    }
                    mid[a] += lat.r / 2;
                    if !lat.on_seam(mid, refined) {
                        continue;
                    }
                    let start = grid.corner([0, 1, 2].map(|v| base[v] + l[v]));
                    let points: Vec<[f64; 3]> = (1..r)
                        .map(|t| {
                            let mut p = start;
                            p[a] += t as f64 / r as f64 * grid.cell;
                            p
                        })
                        .collect();
                    let inner = sample(&points, ev);
                    let key = (a as u8, [0, 1, 2].map(|v| base[v] + l[v]));
                    let signs = seam::edge_signs(ends, &inner);
                    edge_signs.insert(key, signs.clone());
                    made.edges.push((key, signs));
                }
            }
        }
    }
    // Faces: normal `n`, on the lower (side 0) or upper (side 1) face of the block, where
    // the block across is not refined.
    for n in 0..3 {
        let (u, v) = other_axes(n);
        for side in 0..2i64 {
            let mut across = coords;
            across[n] += if side == 0 { -1 } else { 1 };
            if refined(across) {
                continue;
            }
            for j in 0..b {
                for i in 0..b {
                    let mut l = [0i64; 3];
                    l[n] = side * b;
                    l[u] = i;
                    l[v] = j;
                    let at = |du: i64, dv: i64| {
                        let mut q = l;
                        q[u] += du;
                        q[v] += dv;
                        q
                    };
                    let corners = [
                        sign(at(0, 0)),
                        sign(at(1, 0)),
                        sign(at(0, 1)),
                        sign(at(1, 1)),
                    ];
                    if corners.iter().all(|&c| c == corners[0]) {
                        continue;
                    }
                    let global = |q: [i64; 3]| [0, 1, 2].map(|w| base[w] + q[w]);
                    let edge = |axis: usize, from: [i64; 3], ends: [bool; 2]| -> Vec<bool> {
                        edge_signs
                            .get(&(axis as u8, global(from)))
                            .cloned()
                            .unwrap_or_else(|| seam::edge_signs(ends, &vec![ends[0]; r - 1]))
                    };
                    let e0 = edge(u, at(0, 0), [corners[0], corners[1]]);
                    let e1 = edge(u, at(0, 1), [corners[2], corners[3]]);
                    let e2 = edge(v, at(0, 0), [corners[0], corners[2]]);
                    let e3 = edge(v, at(1, 0), [corners[1], corners[3]]);
                    let lo = global(l);
                    let joined = sampler.grad(ev, root, face_middle(grid, lo, n))[0] < 0.0;
                    let origin = grid.corner(lo);
                    let point = |fi: f64, fj: f64| {
                        let mut p = origin;
                        p[u] += fi / r as f64 * grid.cell;
                        p[v] += fj / r as f64 * grid.cell;
                        p
                    };
                    let mut inner_points = Vec::with_capacity((r - 1) * (r - 1));
                    for jj in 1..r {
                        for ii in 1..r {
                            inner_points.push(point(ii as f64, jj as f64));
                        }
                    }
                    let inner = sample(&inner_points, ev);
                    let face = seam::face_signs([&e0, &e1, &e2, &e3], joined, &inner, |fi, fj| {
                        let m = point(fi as f64 + 0.5, fj as f64 + 0.5);
                        sampler.grad(ev, root, m)[0] < 0.0
                    });
                    made.faces.push(((n as u8, lo), face));
                }
            }
        }
    }
    made
}

/// The seam sign (1 = inside) of fine lattice point `p`, which lies on the closed box of
/// refined block `coords`, whose agreed coarse corner signs are `coarse_signs`.
pub fn virtual_sign(
    seams: &Seams,
    lat: &Lattices,
    coords: [i64; 3],
    coarse_signs: &[u8],
    p: [i64; 3],
) -> u8 {
    let r = lat.r;
    let q = p.map(|v| v.div_euclid(r));
    let m = p.map(|v| v.rem_euclid(r));
    let b = lat.block();
    let s = (b + 1) as usize;
    let corner = |q: [i64; 3]| {
        let l = [0, 1, 2].map(|a| (q[a] - coords[a] * b).clamp(0, b) as usize);
        coarse_signs[corner_index(s, l[0], l[1], l[2])]
    };
    let off: Vec<usize> = (0..3).filter(|&a| m[a] != 0).collect();
    match off.as_slice() {
        [] => corner(q),
        [a] => match seams.edges.get(&(*a as u8, q)) {
            Some((signs, _)) => u8::from(signs[m[*a] as usize]),
            None => corner(q),
        },
        [x, y] => {
            let n = 3 - x - y;
            let (u, v) = other_axes(n);
            match seams.faces.get(&(n as u8, q)) {
                Some((face, _)) => u8::from(face.sign(m[u] as usize, m[v] as usize)),
                None => corner(q),
            }
        }
        // Not on a coarse plane: no seam point (callers ask only of those).
        _ => corner(q),
    }
}

/// What lies around a fine block, for its agreed signs: a fine block (empty, full, or
/// sampled, with its own signs), or a coarse block's ground (a seam).
#[derive(Clone, Copy)]
pub enum FineNear<'a> {
    /// Proved empty.
    Empty,
    /// Proved full.
    Full,
    /// Sampled: its own inside bits.
    Block(&'a [u64]),
    /// Not refined: points shared with it take their seam sign.
    Coarse,
}

/// The agreed sign of every corner of fine block `s` (1 = inside), as
/// `hermite::canonical_signs` agrees them on one lattice, except that a point shared with
/// a coarse block takes `seam_sign`.
pub fn fine_signs(
    lat: &Lattices,
    s: [i64; 3],
    near: &[FineNear<'_>; 27],
    seam_sign: impl Fn([i64; 3]) -> u8,
    out: &mut Vec<u8>,
) {
    let b = lat.block() as usize;
    let side = b + 1;
    out.clear();
    out.resize(side * side * side, 0);
    let FineNear::Block(mine) = near[13] else {
        return;
    };
    let base = s.map(|c| c * b as i64);
    for k in 0..side {
        for j in 0..side {
            for i in 0..side {
                let c = corner_index(side, i, j, k);
                let l = [i, j, k];
                if l.iter().all(|&v| v > 0 && v < b) {
                    out[c] = (mine[c / 64] >> (c % 64) & 1) as u8;
                    continue;
                }
                let range = |v: usize| -> (i64, i64) {
                    if v == 0 {
                        (-1, 0)
                    } else if v == b {
                        (0, 1)
                    } else {
                        (0, 0)
                    }
                };
                let (rx, ry, rz) = (range(i), range(j), range(k));
                let (mut empty, mut full, mut coarse) = (false, false, false);
                for dz in rz.0..=rz.1 {
                    for dy in ry.0..=ry.1 {
                        for dx in rx.0..=rx.1 {
                            match near[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize] {
                                FineNear::Empty => empty = true,
                                FineNear::Full => full = true,
                                FineNear::Coarse => coarse = true,
                                FineNear::Block(_) => {}
                            }
                        }
                    }
                }
                out[c] = if coarse {
                    seam_sign([0, 1, 2].map(|a| base[a] + l[a] as i64))
                } else if empty {
                    0
                } else if full {
                    1
                } else {
                    let o = l.map(|v| usize::from(v == b));
                    match near[(o[0] + 1) + 3 * (o[1] + 1) + 9 * (o[2] + 1)] {
                        FineNear::Block(bits) => {
                            let oc = corner_index(side, i - o[0] * b, j - o[1] * b, k - o[2] * b);
                            (bits[oc / 64] >> (oc % 64) & 1) as u8
                        }
                        _ => 0,
                    }
                };
            }
        }
    }
}

/// Whether a fine block that intervals proved `inside` (or empty) has a seam point of the
/// other sign on its closed box, so that it must be sampled and meshed after all.
pub fn needs_sampling(
    lat: &Lattices,
    s: [i64; 3],
    inside: bool,
    refined: &impl Fn([i64; 3]) -> bool,
    seam_sign: impl Fn([i64; 3]) -> u8,
) -> bool {
    let b = lat.block();
    let base = s.map(|c| c * b);
    // Only the faces on the coarse block's boundary can hold seam points.
    let span = lat.r * b;
    for n in 0..3 {
        for side in 0..2 {
            let plane = base[n] + side * b;
            if plane.rem_euclid(span) != 0 {
                continue;
            }
            let (u, v) = other_axes(n);
            for j in 0..=b {
                for i in 0..=b {
                    let mut p = [0i64; 3];
                    p[n] = plane;
                    p[u] = base[u] + i;
                    p[v] = base[v] + j;
                    if lat.on_seam(p, refined) && (seam_sign(p) == 1) != inside {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// The joined rule of a fine finest face on a seam face of refined block `coords` (the
/// seam's, which the fine cells must follow), or `None` for any other face.
pub fn seam_joined(
    seams: &Seams,
    lat: &Lattices,
    coords: [i64; 3],
    refined: &impl Fn([i64; 3]) -> bool,
    at: [i64; 3],
    n: usize,
    side: usize,
) -> Option<bool> {
    let span = lat.r * lat.block();
    let plane = at[n] + side as i64;
    if plane.rem_euclid(span) != 0 {
        return None;
    }
    let mut across = coords;
    across[n] += if plane == coords[n] * span { -1 } else { 1 };
    if refined(across) {
        return None;
    }
    let mut lo = at;
    lo[n] = plane;
    let q = lo.map(|v| v.div_euclid(lat.r));
    let (u, v) = other_axes(n);
    let (face, _) = seams.faces.get(&(n as u8, q))?;
    let (i, j) = (lo[u].rem_euclid(lat.r), lo[v].rem_euclid(lat.r));
    Some(face.joined[(i + lat.r * j) as usize])
}

/// Where [`Lattices::around`] finds the cells of either lattice.
pub trait CellsAt {
    /// What the coarse block at `coarse` (coarse block units) is.
    fn lookup(&self, coarse: [i64; 3]) -> Lookup<'_>;
    /// A refined block's fine block at `fine` (fine block units): its record index and
    /// output, if it was sampled.
    fn fine(&self, fine: [i64; 3]) -> Option<(u32, &BlockOut)>;
}

/// What a coarse block is, to the seam's polygons.
pub enum Lookup<'a> {
    /// Coarse, with its record index and output.
    Coarse(u32, &'a BlockOut),
    /// Refined: its cells are fine ones.
    Refined,
    /// No cells.
    Nothing,
}

impl Lattices {
    /// The four cells around the fine lattice edge along `axis` from fine point `p`, in
    /// `contour::AROUND` order, on whichever lattice each lies; `None` if one is missing.
    pub fn around<'a>(
        &self,
        cells: &'a impl CellsAt,
        seams: &Seams,
        p: [i64; 3],
        axis: usize,
    ) -> Option<[Around<'a>; 4]> {
        let (ab, ac) = other_axes(axis);
        let b = self.block();
        let mut found: [Option<Around<'a>>; 4] = [None; 4];
        for (slot, &(db, dc)) in found.iter_mut().zip(AROUND.iter()) {
            let mut c = p;
            c[ab] += db;
            c[ac] += dc;
            let dcell = c.map(|v| v.div_euclid(self.r));
            let block = dcell.map(|v| v.div_euclid(b));
            *slot = match cells.lookup(block) {
                Lookup::Refined => {
                    let sub = c.map(|v| v.div_euclid(b));
                    let (rec, out) = cells.fine(sub)?;
                    let l = [0, 1, 2].map(|a| (c[a] - sub[a] * b) as usize);
                    let idx = (l[0] + b as usize * (l[1] + b as usize * l[2])) as u16;
                    out.cell(idx).map(|cell| Around {
                        block: rec,
                        coords: sub,
                        out,
                        cell: *cell,
                        edge: edge_id(axis, usize::from(db == -1), usize::from(dc == -1)),
                        fine: true,
                    })
                }
                Lookup::Coarse(rec, out) => {
                    let l = [0, 1, 2].map(|a| (dcell[a] - block[a] * b) as usize);
                    let idx = (l[0] + b as usize * (l[1] + b as usize * l[2])) as u16;
                    let edge = self.coarse_edge(seams, p, axis, dcell)?;
                    out.cell(idx).map(|cell| Around {
                        block: rec,
                        coords: block,
                        out,
                        cell: *cell,
                        edge,
                        fine: false,
                    })
                }
                Lookup::Nothing => None,
            };
        }
        let [Some(a), Some(b), Some(c), Some(d)] = found else {
            return None;
        };
        Some([a, b, c, d])
    }

    /// The edge of coarse cell `dcell` that stands for the fine edge along `axis` from `p`
    /// on its boundary: the coarse edge it lies on, or, inside one of the cell's faces, a
    /// coarse edge of that face at an end of its curve (`FaceSeam::segment`).
    fn coarse_edge(
        &self,
        seams: &Seams,
        p: [i64; 3],
        axis: usize,
        dcell: [i64; 3],
    ) -> Option<usize> {
        let r = self.r;
        let rel = [0, 1, 2].map(|a| p[a] - dcell[a] * r);
        let (ab, ac) = other_axes(axis);
        let at_side = |v: i64| v == 0 || v == r;
        match (at_side(rel[ab]), at_side(rel[ac])) {
            (true, true) => Some(edge_id(
                axis,
                usize::from(rel[ab] == r),
                usize::from(rel[ac] == r),
            )),
            (on_b, _) => {
                // Inside the face normal to the axis the edge is flush with.
                let n = if on_b { ab } else { ac };
                let side = usize::from(rel[n] == r);
                let mut lo = dcell;
                lo[n] += side as i64;
                let (u, v) = other_axes(n);
                let (face, _) = seams.faces.get(&(n as u8, lo))?;
                let along_v = axis == v;
                let e = seam::edge_index(face.r, along_v, rel[u] as usize, rel[v] as usize);
                let k = face.segment[e];
                if k == NO_SEGMENT {
                    return None;
                }
                // The face's coarse edge k in the cell's numbering.
                let (along, mut o) = if k < 2 {
                    (u, [0usize; 3])
                } else {
                    (v, [0usize; 3])
                };
                o[n] = side;
                if k < 2 {
                    o[v] = usize::from(k == 1);
                } else {
                    o[u] = usize::from(k == 3);
                }
                let (b2, c2) = other_axes(along);
                Some(edge_id(along, o[b2], o[c2]))
            }
        }
    }
}

impl Lattices {
    /// The vertex of the pair of an ambiguous fine seam face that the step from cell `q`
    /// around the fine edge along `axis` from `p` crosses, or `None` when that face is not
    /// ambiguous. Where a fine cell meets a coarse leaf across such a face, its two pairs
    /// would otherwise join the same two vertices twice (`contour.rs` says why); the
    /// vertex sits between the pair's two fine edges' middles, and every polygon through
    /// the pair names it alike.
    pub fn seam_face_vertex(
        &self,
        seams: &Seams,
        p: [i64; 3],
        axis: usize,
        q: usize,
    ) -> Option<Slot> {
        let (ab, ac) = other_axes(axis);
        let (step_axis, _) = STEPS[q];
        let (m, o) = if step_axis == 0 { (ab, ac) } else { (ac, ab) };
        // The two cells share their offset along `o`.
        let (db, dc) = AROUND[q];
        let d_o = if o == ab { db } else { dc };
        let mut phi = p;
        phi[o] += d_o;
        let r = self.r;
        let q0 = phi.map(|v| v.div_euclid(r));
        let (face, _) = seams.faces.get(&(m as u8, q0))?;
        let (u, v) = other_axes(m);
        let (i, j) = (phi[u].rem_euclid(r) as usize, phi[v].rem_euclid(r) as usize);
        let n = face.r + 1;
        let at = |di: usize, dj: usize| face.signs[(i + di) + n * (j + dj)];
        let (c00, c10, c01, c11) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
        if !(c00 == c11 && c10 == c01 && c00 != c10) {
            return None;
        }
        // Which side of the fine face the edge is: bottom, top (along u), left, right.
        let (pu, pv) = (p[u] - q0[u] * r, p[v] - q0[v] * r);
        let side = if axis == u {
            if pv as usize == j { 0 } else { 1 }
        } else if pu as usize == i {
            2
        } else {
            3
        };
        let around_00_11 = c00 != face.joined[i + face.r * j];
        // Pairs: {bottom, left} and {top, right}, or {bottom, right} and {top, left}.
        let pairs: [[usize; 2]; 2] = if around_00_11 {
            [[0, 2], [1, 3]]
        } else {
            [[0, 3], [1, 2]]
        };
        let pair = usize::from(!pairs[0].contains(&side));
        let middle = |s: usize| -> DVec3 {
            let mut a = phi;
            let along = if s < 2 { u } else { v };
            if s == 1 {
                a[v] += 1;
            }
            if s == 3 {
                a[u] += 1;
            }
            let mut pt = DVec3::from(self.fine.corner(a));
            pt[along] += 0.5 * self.fine.cell;
            pt
        };
        let [s0, s1] = pairs[pair];
        let pos = ((middle(s0) + middle(s1)) * 0.5).as_vec3().to_array();
        Some(Slot {
            r: Ref::SeamFace(m as u8, phi, pair as u8),
            pos,
            face: true,
        })
    }
}

/// A fine crossing edge on a seam that a coarse block owns: its axis, its lower end (fine
/// lattice), the sign there and a point for its crossing.
#[derive(Clone, Copy, Debug)]
pub struct SeamEdge {
    /// The axis.
    pub axis: usize,
    /// Its lower end on the fine lattice.
    pub at: [i64; 3],
    /// True when that end is inside.
    pub start_inside: bool,
    /// A point of the edge where the surface crosses it (or its middle).
    pub pos: [f32; 3],
}

/// The seam edges coarse block `coords` owns: the crossed fine piece of each of its own
/// coarse edges that `contour::polygons` set aside as a seam's (`beside`), and the crossed
/// fine edges inside the coarse faces on its lower sides that a refined block is across.
pub fn coarse_seam_edges(
    lat: &Lattices,
    seams: &Seams,
    coords: [i64; 3],
    beside: &[OwnedEdge],
    refined: &impl Fn([i64; 3]) -> bool,
    out: &mut Vec<SeamEdge>,
) {
    let b = lat.block();
    let r = lat.r;
    let base = coords.map(|c| c * b);
    let fine_point = |p: [i64; 3]| lat.fine.corner(p);
    for e in beside {
        let a = e.axis as usize;
        let start = [0, 1, 2].map(|v| base[v] + i64::from(e.at[v]));
        let Some((signs, _)) = seams.edges.get(&(a as u8, start)) else {
            continue;
        };
        let Some(t) = (0..r as usize).find(|&t| signs[t] != signs[t + 1]) else {
            continue;
        };
        let mut at = start.map(|v| v * r);
        at[a] += t as i64;
        // The coarse crossing if it lies on this piece, else the piece's middle.
        let lo = fine_point(at)[a];
        let hi = lo + lat.fine.cell;
        let x = f64::from(e.pos[a]);
        let pos = if x >= lo && x <= hi {
            e.pos
        } else {
            let mut m = fine_point(at);
            m[a] += 0.5 * lat.fine.cell;
            m.map(|c| c as f32)
        };
        out.push(SeamEdge {
            axis: a,
            at,
            start_inside: signs[t],
            pos,
        });
    }
    for n in 0..3 {
        let mut across = coords;
        across[n] -= 1;
        if !refined(across) {
            continue;
        }
        let (u, v) = other_axes(n);
        for j in 0..b {
            for i in 0..b {
                let mut lo = base;
                lo[u] += i;
                lo[v] += j;
                let Some((face, _)) = seams.faces.get(&(n as u8, lo)) else {
                    continue;
                };
                let origin = lo.map(|c| c * r);
                let ru = r as usize;
                for (along_v, ii, jj) in (0..ru)
                    .flat_map(|fi| (1..ru).map(move |fj| (false, fi, fj)))
                    .chain((1..ru).flat_map(|fi| (0..ru).map(move |fj| (true, fi, fj))))
                {
                    let (ei, ej) = if along_v { (ii, jj + 1) } else { (ii + 1, jj) };
                    let (s0, s1) = (face.sign(ii, jj), face.sign(ei, ej));
                    if s0 == s1 {
                        continue;
                    }
                    let mut at = origin;
                    at[u] += ii as i64;
                    at[v] += jj as i64;
                    let axis = if along_v { v } else { u };
                    let mut mid = fine_point(at);
                    mid[axis] += 0.5 * lat.fine.cell;
                    out.push(SeamEdge {
                        axis,
                        at,
                        start_inside: s0,
                        pos: mid.map(|c| c as f32),
                    });
                }
            }
        }
    }
}

/// Where the surface crosses a fine seam edge, for its polygon's centre: bisected on the
/// field where the field's own signs cross there, else `pos` as given.
pub fn seam_crossing<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    root: &S::Local,
    lat: &Lattices,
    e: &SeamEdge,
) -> [f32; 3] {
    let a = lat.fine.corner(e.at);
    let mut b = a;
    b[e.axis] += lat.fine.cell;
    let f = |p: [f64; 3], ev: &mut S::Evals| sampler.grad(ev, root, p)[0] < 0.0;
    let (mut lo, mut hi) = (DVec3::from(a), DVec3::from(b));
    let inside_lo = f(a, ev);
    if inside_lo == f(b, ev) || inside_lo != e.start_inside {
        return e.pos;
    }
    for _ in 0..8 {
        let m = (lo + hi) * 0.5;
        if f(m.to_array(), ev) == inside_lo {
            lo = m;
        } else {
            hi = m;
        }
    }
    ((lo + hi) * 0.5).as_vec3().to_array()
}
