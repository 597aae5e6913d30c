//! What a mesh will cost before it is made, so that work which cannot fit the machine is
//! refused at once instead of filling memory for minutes.
//!
//! The mesher's memory is, above everything else, one entry per octree block that may hold
//! surface (its coordinates and simplified tape, kept from the octree pass to the end), plus
//! a few slabs of cells. The blocks are counted by building the octree itself at a probe
//! depth (cheap: at most 32³ blocks) and, for deeper meshes, scaled by 4 a level, as a
//! surface's area in cells grows. Interval pruning keeps more blocks at coarse levels than
//! at fine ones, so the scaled count errs high.

use isoforge_field::Shape;

use super::octree::{BLOCK_SHIFT, Grid, Octree};
use super::{MeshSettings, tape_sampler};

/// The depth the blocks are counted at; deeper meshes scale its count.
const PROBE_DEPTH: u8 = 9;

/// Peak bytes of a mesh run besides its blocks: the program, the writer's buffers, one
/// slab's scratch per thread. Measured: `docs/meshing.md`, "Memory estimate".
const BASE_BYTES: f64 = 24.0 * 1024.0 * 1024.0;

/// Peak bytes per surface block, all stages together (fitted on the bench models at depths
/// 10 to 12 and rounded up; `docs/meshing.md`).
const BYTES_PER_BLOCK: f64 = 2048.0;

/// The cost of meshing a shape at a depth, before any of it is done.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The finest level estimated for.
    pub depth: u8,
    /// Blocks of 16³ cells that may hold surface: counted at depths up to the probe depth,
    /// scaled from it beyond.
    pub blocks: f64,
    /// Finest cells in those blocks (each is sampled).
    pub cells: f64,
    /// Peak memory of the run, in bytes.
    pub bytes: f64,
}

/// Estimates the cost of `mesh_shape_into(shape, settings, ..)` from the blocks that may
/// hold surface, counted by building the octree at the probe depth.
pub fn estimate(shape: &Shape, settings: &MeshSettings) -> Estimate {
    let depth = settings.depth;
    let probe = depth.min(PROBE_DEPTH);
    let sampler = tape_sampler(shape, settings);
    let grid = Grid::new(&settings.bounds, u32::from(probe), BLOCK_SHIFT);
    let counted = Octree::build(&sampler, grid).blocks.len() as f64;
    of_blocks(
        depth,
        counted * 4f64.powi(i32::from(depth - probe)) + refined_blocks(settings),
    )
}

/// The fine blocks a refinement adds: a refined block's surface crosses about `4^levels`
/// of its `8^levels` fine blocks (as the blocks of a whole lattice grow from one depth to
/// the next).
fn refined_blocks(settings: &MeshSettings) -> f64 {
    settings.refine.as_ref().map_or(0.0, |r| {
        r.blocks.len() as f64 * 4f64.powi(i32::from(r.levels.min(super::refined::MAX_LEVELS)))
    })
}

/// The most a mesh at the settings' depth can cost, whatever the shape: every block of the
/// lattice kept. Nothing is evaluated, so a caller can skip [`estimate`]'s octree (which the
/// mesher would build again) whenever this bound already fits.
pub fn estimate_bound(settings: &MeshSettings) -> Estimate {
    let depth = settings.depth.min(super::MAX_DEPTH);
    let per_side = 2f64.powi(i32::from(depth) - BLOCK_SHIFT.min(u32::from(depth)) as i32);
    let refined = settings.refine.as_ref().map_or(0.0, |r| {
        r.blocks.len() as f64 * 8f64.powi(i32::from(r.levels.min(super::refined::MAX_LEVELS)))
    });
    of_blocks(depth, per_side.powi(3) + refined)
}

fn of_blocks(depth: u8, blocks: f64) -> Estimate {
    let block_cells = f64::from(1u32 << (3 * BLOCK_SHIFT.min(u32::from(depth))));
    Estimate {
        depth,
        blocks,
        cells: blocks * block_cells,
        bytes: BASE_BYTES + blocks * BYTES_PER_BLOCK,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isoforge_field::Bounds;

    fn sphere() -> Shape {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        x.square() + y.square() + z.square() - 1.0
    }

    #[test]
    fn blocks_grow_four_times_a_level_beyond_the_probe() {
        let bounds = Bounds::new([-1.5; 3], [1.5; 3]).unwrap();
        let at = |d| estimate(&sphere(), &MeshSettings::new(bounds, d));
        let (nine, ten, sixteen) = (at(9), at(10), at(16));
        assert!(nine.blocks > 100.0, "{nine:?}");
        assert_eq!(ten.blocks, nine.blocks * 4.0);
        assert_eq!(sixteen.blocks, nine.blocks * 4f64.powi(7));
        assert!(
            sixteen.bytes > 16e9,
            "depth 16 of a sphere is many GB: {sixteen:?}"
        );
    }

    #[test]
    fn the_bound_holds_every_count() {
        let bounds = Bounds::new([-1.5; 3], [1.5; 3]).unwrap();
        for d in [3, 6, 9, 12] {
            let s = MeshSettings::new(bounds, d);
            let (count, bound) = (estimate(&sphere(), &s), estimate_bound(&s));
            assert!(
                count.blocks <= bound.blocks,
                "depth {d}: {count:?} > {bound:?}"
            );
        }
        // Depth 9: 32 blocks a side, 88 MiB at most, whatever the model.
        let nine = estimate_bound(&MeshSettings::new(bounds, 9));
        assert_eq!(nine.blocks, 32768.0);
        assert!(nine.bytes < 100.0 * 1024.0 * 1024.0);
    }

    #[test]
    fn an_empty_region_costs_only_the_base() {
        let bounds = Bounds::new([5.0; 3], [6.0; 3]).unwrap();
        let e = estimate(&sphere(), &MeshSettings::new(bounds, 12));
        assert_eq!(e.blocks, 0.0);
        assert_eq!(e.bytes, BASE_BYTES);
    }
}
