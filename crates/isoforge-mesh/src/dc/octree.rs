//! The interval octree: from the root cube down to blocks of `2^BLOCK_SHIFT` cells a side,
//! keeping only the blocks whose interval may change sign.
//!
//! Below the block level the mesher stops using intervals and samples the block densely in
//! one batch call with the block's simplified tape (see `hermite.rs`): at that size a dense
//! grid costs less than the interval evaluations and simplifications it would replace, and
//! it has no per-cell overhead. Every cell beside a sign-changing edge lies in a block whose
//! closed box holds both of the edge's corners, so that block's interval cannot be
//! one-signed: such blocks are always kept.

use isoforge_field::Bounds;
use isoforge_field::Interval;
use rayon::prelude::*;

use super::sampler::{EvalPool, Sampler};

/// Blocks are 2^BLOCK_SHIFT cells a side. Measured on the bench models at depth 9 (CPU
/// seconds, 8³ vs 16³ blocks): gyroid_sphere 8.3 vs 7.3, sphere 1.6 vs 1.2, heart 1.7 vs
/// 1.5. Bigger blocks sample more empty corners but recompute fewer crossings on block
/// faces (each block finds the crossings of its closed box) and walk fewer tree nodes.
pub const BLOCK_SHIFT: u32 = 4;

/// The lattice: cubes of side `cell` from `origin`, `2^depth` along each axis.
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    /// The lattice's lowest corner (the region's lowest corner).
    pub origin: [f64; 3],
    /// The finest cell's side.
    pub cell: f64,
    /// Finest level.
    pub depth: u32,
    /// Level of the blocks.
    pub block_level: u32,
    /// Cells per block side.
    pub block: usize,
    /// The region's highest corner: the lattice reaches it along the longest side and
    /// passes it along the others, where vertices are kept on the region's side.
    pub top: [f64; 3],
}

impl Grid {
    /// The lattice over a region: the longest side is split in 2^depth cells, blocks of
    /// 2^block_shift cells a side (fewer when the lattice is smaller).
    pub fn new(bounds: &Bounds, depth: u32, block_shift: u32) -> Grid {
        let shift = block_shift.min(depth);
        Grid {
            origin: bounds.min,
            cell: bounds.longest_side() / f64::from(1u32 << depth),
            depth,
            block_level: depth - shift,
            block: 1 << shift,
            top: bounds.max,
        }
    }

    /// The position of lattice corner `g`.
    pub fn corner(&self, g: [i64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|i| self.origin[i] + g[i] as f64 * self.cell)
    }

    /// Where a vertex of the cube with lowest corner `lo` and side `size` may go: the cube
    /// inset by `inset`, and on the region's side of its highest walls (a vertex there
    /// would be as far out as its cell reaches, a cell's size away from the region at
    /// coarse depths). The region's lowest walls are lattice planes already.
    pub fn vertex_box(&self, lo: [f64; 3], size: f64, inset: f64) -> ([f64; 3], [f64; 3]) {
        let hi = [0, 1, 2].map(|a| (lo[a] + size - inset).min(self.top[a]));
        let lo = [0, 1, 2].map(|a| (lo[a] + inset).min(hi[a]));
        (lo, hi)
    }

    /// Blocks per axis.
    pub fn blocks_per_side(&self) -> i64 {
        1 << self.block_level
    }

    /// The box of the cube `coords` at `level`.
    fn cube(&self, level: u32, coords: [i64; 3]) -> [Interval; 3] {
        let cells = (1i64 << (self.depth - level)) as f64 * self.cell;
        [0, 1, 2].map(|i| {
            let lo = self.origin[i] + coords[i] as f64 * cells;
            Interval::try_from((lo, lo + cells)).unwrap_or(Interval::ENTIRE)
        })
    }
}

/// What a block of the lattice is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Every point outside (or outside the lattice).
    Empty,
    /// Every point inside.
    Full,
    /// May hold surface: the block with this index in [`Octree::blocks`].
    Block(u32),
}

enum Node {
    Empty,
    Full,
    Block(u32),
    Branch(Vec<Node>),
}

enum Built<L> {
    Empty,
    Full,
    Block(L),
    Branch(Vec<Built<L>>),
}

/// A block that may hold surface, with the field narrowed to it.
pub struct Block<L> {
    /// Block coordinates (block units).
    pub coords: [i64; 3],
    /// The field narrowed to the block.
    pub local: L,
}

/// The pruned tree, and its blocks in Morton order.
pub struct Octree<L> {
    root: Node,
    /// The blocks that may hold surface.
    pub blocks: Vec<Block<L>>,
    /// The lattice.
    pub grid: Grid,
}

impl<L: Clone + Send + Sync> Octree<L> {
    /// Builds the tree with interval pruning, in parallel over subtrees.
    pub fn build<S: Sampler<Local = L>>(sampler: &S, grid: Grid) -> Octree<L> {
        let pool = EvalPool::new(sampler);
        let ctx = BuildCtx {
            sampler,
            pool: &pool,
            grid,
        };
        let built = ctx.build(0, [0; 3], &sampler.root());
        let mut blocks = Vec::new();
        let root = number(built, [0; 3], &mut blocks);
        Octree { root, blocks, grid }
    }

    /// The class of the block at `coords` (block units); outside the lattice is empty.
    pub fn class(&self, coords: [i64; 3]) -> Class {
        let n = self.grid.blocks_per_side();
        if coords.iter().any(|&c| c < 0 || c >= n) {
            return Class::Empty;
        }
        let mut node = &self.root;
        let mut level = 0;
        loop {
            match node {
                Node::Empty => return Class::Empty,
                Node::Full => return Class::Full,
                Node::Block(i) => return Class::Block(*i),
                Node::Branch(children) => {
                    let shift = self.grid.block_level - level - 1;
                    let child = ((coords[0] >> shift) & 1)
                        | ((coords[1] >> shift) & 1) << 1
                        | ((coords[2] >> shift) & 1) << 2;
                    match children.get(child as usize) {
                        Some(c) => node = c,
                        None => return Class::Empty,
                    }
                    level += 1;
                }
            }
        }
    }
}

/// What a fine block of a refined block is (`refined.rs`).
#[derive(Clone, Debug)]
pub enum Sub<L> {
    /// Every point outside.
    Empty,
    /// Every point inside.
    Full,
    /// May hold surface; the field narrowed to it.
    Block(L),
}

/// The fine blocks of the block at `coords` (coarse block units) on `fine`, a lattice
/// `levels` finer than the one the block was found on, pruned by intervals from the block's
/// own narrowed field `local`. `2^(3 levels)` of them, `i + m (j + m k)` for fine block
/// `(i, j, k)` of the `m = 2^levels` a side.
pub fn refine_block<S: Sampler>(
    sampler: &S,
    fine: Grid,
    levels: u32,
    coords: [i64; 3],
    local: &S::Local,
) -> Vec<Sub<S::Local>> {
    let pool = EvalPool::new(sampler);
    let ctx = BuildCtx {
        sampler,
        pool: &pool,
        grid: fine,
    };
    let m = 1usize << levels;
    let mut out: Vec<Sub<S::Local>> = (0..m * m * m).map(|_| Sub::Empty).collect();
    let start = fine.block_level - levels;
    let built = ctx.build(start, coords, local);
    let base = coords.map(|c| c << levels);
    fill_subs(built, coords, levels, base, m, &mut out);
    out
}

/// Writes a built subtree's fine blocks into their places (`refine_block`'s order).
fn fill_subs<L>(
    built: Built<L>,
    coords: [i64; 3],
    depth_left: u32,
    base: [i64; 3],
    m: usize,
    out: &mut [Sub<L>],
) {
    let put = |c: [i64; 3]| -> usize {
        let l = [0, 1, 2].map(|a| (c[a] - base[a]) as usize);
        l[0] + m * (l[1] + m * l[2])
    };
    // Every fine block under `coords`, for a node that is the same all through.
    let span = |coords: [i64; 3], depth_left: u32| {
        let n = 1i64 << depth_left;
        let lo = coords.map(|c| c << depth_left);
        (0..n * n * n).map(move |k| [lo[0] + k % n, lo[1] + (k / n) % n, lo[2] + k / (n * n)])
    };
    match built {
        Built::Empty => {}
        Built::Full => {
            for c in span(coords, depth_left) {
                out[put(c)] = Sub::Full;
            }
        }
        Built::Block(local) => out[put(coords)] = Sub::Block(local),
        Built::Branch(children) => {
            for (c, child) in children.into_iter().enumerate() {
                let cc = [0, 1, 2].map(|i| coords[i] * 2 + ((c as i64 >> i) & 1));
                fill_subs(child, cc, depth_left - 1, base, m, out);
            }
        }
    }
}

struct BuildCtx<'a, 's, S: Sampler> {
    sampler: &'s S,
    pool: &'a EvalPool<'s, S>,
    grid: Grid,
}

impl<S: Sampler> BuildCtx<'_, '_, S> {
    fn build(&self, level: u32, coords: [i64; 3], local: &S::Local) -> Built<S::Local> {
        let b = self.grid.cube(level, coords);
        let mut guard = self.pool.take();
        // The clipped field: no point inside when its lower end is >= 0 (inside is F < 0).
        let f = self.sampler.interval(guard.get(), local, b);
        if f.inf() >= 0.0 {
            return Built::Empty;
        }
        // The lattice's last plane of corners belongs to no block and counts as outside,
        // so a cube touching it is never full, whatever the interval says (it can say so
        // when that plane lands a rounding error inside the region's wall).
        let last = 1i64 << level;
        if f.sup() < 0.0 && coords.iter().all(|&c| c + 1 < last) {
            return Built::Full;
        }
        let narrowed = self.sampler.narrow(guard.get(), local);
        drop(guard);
        if level == self.grid.block_level {
            return Built::Block(narrowed);
        }
        let children: Vec<Built<S::Local>> = (0..8i64)
            .into_par_iter()
            .map(|c| {
                let child = [0, 1, 2].map(|i| coords[i] * 2 + ((c >> i) & 1));
                self.build(level + 1, child, &narrowed)
            })
            .collect();
        if children.iter().all(|c| matches!(c, Built::Empty)) {
            Built::Empty
        } else {
            Built::Branch(children)
        }
    }
}

/// Numbers the blocks in tree (Morton) order, so output is the same on every run.
fn number<L>(built: Built<L>, coords: [i64; 3], blocks: &mut Vec<Block<L>>) -> Node {
    match built {
        Built::Empty => Node::Empty,
        Built::Full => Node::Full,
        Built::Block(local) => {
            blocks.push(Block { coords, local });
            Node::Block((blocks.len() - 1) as u32)
        }
        Built::Branch(children) => Node::Branch(
            children
                .into_iter()
                .enumerate()
                .map(|(c, child)| {
                    let cc = [0, 1, 2].map(|i| coords[i] * 2 + ((c as i64 >> i) & 1));
                    number(child, cc, blocks)
                })
                .collect(),
        ),
    }
}
