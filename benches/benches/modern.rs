//! Meshing time for the modern-library fixtures (`fixtures/modern`: hull, metaballs,
//! function volumes, an imported mesh, a shell) at depths 8 and 9, to read beside the
//! classic benchmark models of `mesh.rs` (same settings: all cores, the script's bounds).
//! Quick subset: `cargo bench --bench modern -- d8`. `sampled_hull` and
//! `offset_of_gyroids` time two slow fields (a sampled hull, a first-order distance).

use std::path::PathBuf;

use divan::Bencher;
use isoforge_mesh::{MeshSettings, mesh_shape};
use isoforge_script::{Model, load_file};

fn main() {
    divan::main();
}

const MODELS: [&str; 7] = [
    "tetrahedron_hull",
    "lava_lamp",
    "ripple_tile",
    "spiky_ball",
    "trefoil_tube",
    "drilled_import",
    "heart_shell",
];

fn bench_model(bencher: Bencher, name: &str, depth: u8) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/modern")
        .join(format!("{name}.rhai"));
    let model = match load_file(&path, &[]) {
        Ok(m) => m,
        Err(e) => panic!("{name}: {e}"),
    };
    bench_loaded(bencher, name, &model, depth);
}

/// Times meshing a loaded model over the region its script declares.
fn bench_loaded(bencher: Bencher, name: &str, model: &Model, depth: u8) {
    let Some(bounds) = model.bounds else {
        panic!("{name}: the script declares its bounds")
    };
    let settings = MeshSettings::new(bounds, depth);
    bencher.bench(|| {
        let mesh = mesh_shape(&model.shape, &settings);
        divan::black_box(mesh.triangles.len())
    });
}

#[divan::bench(args = MODELS, sample_count = 3, sample_size = 1)]
fn d8(bencher: Bencher, name: &str) {
    bench_model(bencher, name, 8);
}

#[divan::bench(args = MODELS, sample_count = 2, sample_size = 1)]
fn d9(bencher: Bencher, name: &str) {
    bench_model(bencher, name, 9);
}

/// A hull of a part that is no known convex body (a torus), so sampled: a polytope of
/// about 1,300 facets, whose field is read group by group (`hull/planes.rs`). Its meshing
/// time is nearly all that field.
const SAMPLED_HULL: &str = "bounds([-5, -5, -3], [5, 5, 3]);\nhull([torus(3, 1)])\n";

#[divan::bench(args = [7, 8], sample_count = 3, sample_size = 1)]
fn sampled_hull(bencher: Bencher, depth: u8) {
    let model =
        isoforge_script::load_script(std::path::Path::new("sampled_hull.rhai"), SAMPLED_HULL, &[])
            .unwrap_or_else(|e| panic!("sampled_hull: {e}"));
    bench_loaded(bencher, "sampled_hull", &model, depth);
}

/// An `offset` of two gyroids in balls, turned (the fuzz run's slowest model, session
/// 36): neither is a distance, so the offset meshes their first-order distance
/// f / |∇f|, and the late stages ask for its gradient at every point they check.
const OFFSET_OF_GYROIDS: &str = "bounds([-3, -3, -3], [3, 3, 3]);
offset(intersection(difference(sphere(0.903), intersection(gyroid(1.374, 0.185),
sphere(1.161)).move([-0.457, 0.646, -0.022])), smooth_difference(intersection(gyroid(2.997,
0.274), sphere(0.509)).scale([0.544, 0.599, 0.541]), sphere(0.353), 0.307)).rotate([0.106,
-0.812, 0.537], 86.363), 0.248)
";

#[divan::bench(args = [6, 7], sample_count = 3, sample_size = 1)]
fn offset_of_gyroids(bencher: Bencher, depth: u8) {
    let model = isoforge_script::load_script(
        std::path::Path::new("offset_of_gyroids.rhai"),
        OFFSET_OF_GYROIDS,
        &[],
    )
    .unwrap_or_else(|e| panic!("offset_of_gyroids: {e}"));
    bench_loaded(bencher, "offset_of_gyroids", &model, depth);
}
