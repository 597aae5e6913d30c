//! Meshing time of the sweeps, textures and surfaces fixtures (`fixtures/sweeps`): every
//! one at depth 8, and the textured cylinder (knurled knob) and the path-swept knot ring
//! at depth 9 too. Before timing, it prints how much of the lattice the interval octree
//! keeps: the 16³-cell blocks whose interval could hold the surface, in cells, against the
//! dense lattice over the region. Quick subset: `cargo bench --bench sweeps -- d8`.

use std::path::PathBuf;

use divan::Bencher;
use isoforge_field::{Bounds, ClippedField, Interval, IntervalEval};
use isoforge_mesh::{MeshSettings, mesh_shape};
use isoforge_script::{Model, load_file};

/// Cells a side of the mesher's blocks (`isoforge_mesh`'s octree stops there and samples
/// each kept block densely).
const BLOCK: u32 = 16;

const D8: [&str; 8] = [
    "knurled_knob",
    "knot_ring",
    "threaded_rod",
    "twisted_vase",
    "boat_hull",
    "lecture_bezier",
    "lecture_bspline",
    "lecture_coons",
];

const D9: [&str; 2] = ["knurled_knob", "knot_ring"];

fn main() {
    for (name, depth) in D8.iter().map(|n| (*n, 8)).chain(D9.iter().map(|n| (*n, 9))) {
        let model = load(name);
        let (kept, dense) = pruning(&model, depth);
        eprintln!(
            "{name} depth {depth}: blocks kept hold {kept} cells of {dense} dense ({:.1}%)",
            100.0 * kept as f64 / dense as f64
        );
    }
    divan::main();
}

fn load(name: &str) -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/sweeps")
        .join(format!("{name}.rhai"));
    match load_file(&path, &[]) {
        Ok(m) => m,
        Err(e) => panic!("{name}: {e}"),
    }
}

fn region(model: &Model) -> Bounds {
    model
        .bounds
        .expect("every sweeps fixture declares its bounds")
}

/// The cells in the blocks an interval octree keeps (their parts inside the region), and
/// the cells of the dense lattice over the region: the root cube is split while its field interval could hold zero,
/// down to blocks of [`BLOCK`] cells.
fn pruning(model: &Model, depth: u32) -> (u64, u64) {
    let bounds = region(model);
    let field = ClippedField::new(&model.shape, bounds);
    let cell = bounds.longest_side() / f64::from(1u32 << depth);
    let dense: u64 = (0..3)
        .map(|i| ((bounds.max[i] - bounds.min[i]) / cell).ceil() as u64)
        .product();
    let mut eval = IntervalEval::new();
    let mut cells = 0u64;
    let block_side = cell * f64::from(BLOCK);
    let mut stack = vec![(bounds.min, bounds.longest_side())];
    while let Some((lo, side)) = stack.pop() {
        if (0..3).any(|i| lo[i] >= bounds.max[i]) {
            continue;
        }
        let b = [0, 1, 2].map(|i| Interval::try_from((lo[i], lo[i] + side)).expect("box"));
        let v = field.interval(&mut eval, b);
        if v.inf() > 0.0 || v.sup() < 0.0 {
            continue;
        }
        if side <= block_side * 1.000001 {
            // Only the block's cells inside the region are sampled.
            cells += (0..3)
                .map(|i| (((bounds.max[i] - lo[i]) / cell).ceil() as u64).min(u64::from(BLOCK)))
                .product::<u64>();
            continue;
        }
        let h = side / 2.0;
        for k in 0..8 {
            let c = [0, 1, 2].map(|i| lo[i] + if k >> i & 1 == 1 { h } else { 0.0 });
            stack.push((c, h));
        }
    }
    (cells, dense)
}

fn run(bencher: Bencher, name: &str, depth: u8) {
    let model = load(name);
    let settings = MeshSettings::new(region(&model), depth);
    bencher.bench(|| {
        let mesh = mesh_shape(&model.shape, &settings);
        divan::black_box(mesh.triangles.len())
    });
}

#[divan::bench(args = D8, sample_count = 3, sample_size = 1)]
fn d8(bencher: Bencher, name: &str) {
    run(bencher, name, 8);
}

#[divan::bench(args = D9, sample_count = 2, sample_size = 1)]
fn d9(bencher: Bencher, name: &str) {
    run(bencher, name, 9);
}
