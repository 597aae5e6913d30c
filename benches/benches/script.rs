//! Model scripts: how long a script takes to run (engine set-up, parse, graph build) and
//! how long finding a region by interval pruning takes, on the classic fixtures.
//!
//! Run: `cargo bench -p isoforge-benches --bench script`.

use std::path::PathBuf;

use divan::black_box;
use isoforge_field::find_bounds;
use isoforge_script::load_file;

fn main() {
    divan::main();
}

const MODELS: [&str; 6] = [
    "classic/heart.rhai",
    "classic/drope_block.rhai",
    "classic/spaceship.rhai",
    "classic/stacked_sphere_circle.rhai",
    "classic/curve_cyl.rhai",
    "bench/spheres_chain.rhai",
];

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
        .join(name)
}

/// Running the script: a fresh sandboxed engine, the notation pass, parse, evaluate.
#[divan::bench(args = MODELS)]
fn load(name: &str) {
    let p = path(name);
    black_box(load_file(&p, &[]).expect("fixture loads"));
}

/// Finding the region by interval pruning of ±1e4 mm, as when a script has no `bounds`.
#[divan::bench(args = MODELS)]
fn bounds(bencher: divan::Bencher, name: &str) {
    let model = load_file(&path(name), &[]).expect("fixture loads");
    bencher.bench(|| black_box(find_bounds(&model.shape).expect("bounded")));
}
