//! Meshing time for the six benchmark scripts at depths 8 and 9, and the colonnade `.vm`
//! model at depth 8 over [-1, 1]³: the figures compared with fidget (the models are in
//! `fixtures/bench`; docs/contributing.md says how to run and compare). Quick subset:
//! `cargo bench --bench mesh -- d8`.
//!
//! The mesh streams into a counting sink, as `isoforge mesh` streams it into a file, so
//! the memory figures are the mesher's own: divan's allocation profiler reports the most
//! bytes held at once (per thread: the calling thread's share; whole-process peaks, with
//! fidget's beside them, come from `tools/mesh-vs-fidget.sh`). Triangles are the items
//! counter, shown next to the time as a rate.
//!
//! `measured_d8` is the same mesh measured against the model on its way (the
//! `DeviationSink` that `isoforge mesh --max-depth` puts in front of the file): its time
//! less `d8`'s is what the measure costs.
//!
//! `refined_d8` is the mesh of the two bench models that miss their tolerance at depth 8,
//! with the blocks around their misses (measured once, before the timing) sampled two
//! levels finer, as one round of `isoforge mesh`'s refining makes it (docs/meshing.md,
//! session 45): its time against `d8`'s is what the refinement costs.

use std::path::PathBuf;
use std::sync::Arc;

use divan::counter::ItemsCount;
use divan::{AllocProfiler, Bencher};
use isoforge_field::Bounds;
use isoforge_field::ClippedField;
use isoforge_mesh::{DeviationSink, MeshSettings, Refinement, Tally, mesh_shape_into};

#[global_allocator]
static ALLOC: AllocProfiler = AllocProfiler::system();
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
    run_with(bencher, model, MeshSettings::new(bounds, depth));
}

fn run_with(bencher: Bencher, model: &Model, settings: MeshSettings) {
    let mesh = |settings: &MeshSettings| {
        let mut tally = Tally::around([0.0; 3]);
        match mesh_shape_into(&model.shape, settings, &mut tally) {
            Ok(()) => tally.triangles,
            Err(e) => panic!("meshing failed: {e}"),
        }
    };
    let triangles = mesh(&settings);
    bencher
        .counter(ItemsCount::new(triangles as usize))
        .bench(|| divan::black_box(mesh(&settings)));
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

#[divan::bench(args = MODELS, sample_count = 2, sample_size = 1)]
fn measured_d8(bencher: Bencher, name: &str) {
    let model = load(&format!("bench/{name}.rhai"));
    let Some(bounds) = model.bounds else {
        panic!("{name}: the bench script declares its bounds")
    };
    let settings = MeshSettings::new(bounds, 8);
    let field = ClippedField::new(&model.shape, bounds);
    let measured = || {
        let tally = Tally::around([0.0; 3]);
        let mut sink = DeviationSink::new(tally, &field, settings.effective_tolerance());
        if let Err(e) = mesh_shape_into(&model.shape, &settings, &mut sink) {
            panic!("meshing failed: {e}");
        }
        let (deviation, tally) = sink.finish();
        (deviation.max, tally.triangles)
    };
    let (_, triangles) = measured();
    bencher
        .counter(ItemsCount::new(triangles as usize))
        .bench(|| divan::black_box(measured()));
}

#[divan::bench(args = ["gyroid_sphere", "sinus_sphere"], sample_count = 2, sample_size = 1)]
fn refined_d8(bencher: Bencher, name: &str) {
    let model = load(&format!("bench/{name}.rhai"));
    let Some(bounds) = model.bounds else {
        panic!("{name}: the bench script declares its bounds")
    };
    let mut settings = MeshSettings::new(bounds, 8);
    let field = ClippedField::new(&model.shape, bounds);
    let mut sink = DeviationSink::new(
        Tally::around([0.0; 3]),
        &field,
        settings.effective_tolerance(),
    )
    .keeping_misses(200_000);
    if let Err(e) = mesh_shape_into(&model.shape, &settings, &mut sink) {
        panic!("meshing failed: {e}");
    }
    let (_, misses, _) = sink.finish_with_misses();
    let blocks = Refinement::blocks_near(&bounds, 8, &misses, 2.0);
    assert!(!blocks.is_empty(), "{name} misses its tolerance at depth 8");
    settings.refine = Some(Arc::new(Refinement {
        levels: 2,
        blocks: blocks.into_keys().collect(),
        tight_merges: false,
    }));
    run_with(bencher, &model, settings);
}
