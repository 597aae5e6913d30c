//! Meshing time for the six benchmark scripts at depths 8 and 9, and the colonnade `.vm`
//! model at depth 8 over [-1, 1]³: the figures compared with fidget (the models are in
//! `fixtures/bench`; docs/contributing.md says how to run and compare). Quick subset:
//! `cargo bench --bench mesh -- d8`.

use std::path::PathBuf;

use divan::Bencher;
use isoforge_field::Bounds;
use isoforge_mesh::{MeshSettings, mesh_shape};
use isoforge_script::{Model, load_file};

fn main() {
    divan::main();
}

const MODELS: [&str; 6] = [
    "sphere",
    "gyroid_sphere",
    "heart",
    "drope_block",
    "sinus_sphere",
    "spheres_chain",
];

fn fixture(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures")
        .join(rel)
}

fn load(rel: &str) -> Model {
    match load_file(&fixture(rel), &[]) {
        Ok(m) => m,
        Err(e) => panic!("{rel}: {e}"),
    }
}

fn run(bencher: Bencher, model: &Model, bounds: Bounds, depth: u8) {
    let settings = MeshSettings::new(bounds, depth);
    bencher.bench(|| {
        let mesh = mesh_shape(&model.shape, &settings);
        divan::black_box(mesh.triangles.len())
    });
}

fn bench_model(bencher: Bencher, name: &str, depth: u8) {
    let model = load(&format!("bench/{name}.rhai"));
    let Some(bounds) = model.bounds else {
        panic!("{name}: the bench script declares its bounds")
    };
    run(bencher, &model, bounds, depth);
}

#[divan::bench(args = MODELS, sample_count = 3, sample_size = 1)]
fn d8(bencher: Bencher, name: &str) {
    bench_model(bencher, name, 8);
}

#[divan::bench(args = MODELS, sample_count = 2, sample_size = 1)]
fn d9(bencher: Bencher, name: &str) {
    bench_model(bencher, name, 9);
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn colonnade_d8(bencher: Bencher) {
    let model = load("vm/colonnade.vm");
    let bounds = Bounds::new([-1.0; 3], [1.0; 3]).expect("box");
    run(bencher, &model, bounds, 8);
}
