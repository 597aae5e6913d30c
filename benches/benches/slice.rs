//! Slicing time for the torus (R 15 mm, r 5 mm): as a model and as an STL-like mesh,
//! 0.2 mm layers, 2 perimeters, 20% infill to G-code with every default feature on (thin
//! walls, gap fill, bridges, overhangs, cooling, combing, the planner's time); the overhang
//! ramp with tree supports; and the model at 0.05 mm to an SL1 archive at 1440 x 2560.
//! Whole processes on this 2-core machine, paired runs, medians: `isoforge slice` of the
//! torus script took 0.53 s wall (0.97 s CPU), of its 250k-triangle STL 0.92 s, while
//! CuraEngine 4.13 took 1.5-2.5 s wall (2.4-2.5 s CPU) on the same STL (ratio 0.40-0.46);
//! PrusaSlicer 2.5 took 30 s wall on a loaded machine (docs/slicing.md has the table).
//! This bench, same day: torus from the model 0.49 s, from the mesh 0.51 s, the ramp with
//! tree supports 0.19 s (medians of 5).

use std::path::PathBuf;

use divan::Bencher;
use isoforge_mesh::{Mesh, MeshSettings, mesh_shape};
use isoforge_script::{Model, load_file};
use isoforge_slice::{FdmSettings, GridSpec, Profile, Source, render_layers, sl1, slice_gcode};

fn main() {
    divan::main();
}

fn torus() -> Model {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/slice/torus.rhai");
    match load_file(&path, &[]) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

fn fdm() -> FdmSettings {
    let mut p = Profile::default_fdm();
    for s in ["layer_height=0.2", "perimeters=2", "infill_density=0.2"] {
        p.set(s).expect("a known key");
    }
    p.fdm().expect("complete settings")
}

fn no_progress(_: usize, _: usize) {}

#[divan::bench(sample_count = 5)]
fn gcode_from_model(bencher: Bencher) {
    let model = torus();
    let bounds = model.bounds.expect("the fixture declares bounds");
    let s = fdm();
    bencher.bench(|| {
        let source = Source::field(&model.shape, bounds);
        slice_gcode(&source, &s, &no_progress).expect("slices")
    });
}

#[divan::bench(sample_count = 5)]
fn gcode_from_mesh(bencher: Bencher) {
    let model = torus();
    let bounds = model.bounds.expect("the fixture declares bounds");
    // Depth 8 over the 42 mm region: 0.16 mm cells, a ~250k-triangle STL.
    let mesh: Mesh = mesh_shape(&model.shape, &MeshSettings::new(bounds, 8));
    let s = fdm();
    bencher.bench(|| {
        let source = Source::mesh(&mesh);
        slice_gcode(&source, &s, &no_progress).expect("slices")
    });
}

#[divan::bench(sample_count = 5)]
fn gcode_overhang_ramp_with_tree_supports(bencher: Bencher) {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fixtures/slice/overhang_ramp.rhai");
    let model = match load_file(&path, &[]) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    };
    let bounds = model.bounds.expect("the fixture declares bounds");
    let mut p = Profile::default_fdm();
    p.set("supports=tree").expect("a known key");
    let s = p.fdm().expect("complete settings");
    bencher.bench(|| {
        let source = Source::field(&model.shape, bounds);
        slice_gcode(&source, &s, &no_progress).expect("slices")
    });
}

#[divan::bench(sample_count = 3)]
fn sl1_from_model(bencher: Bencher) {
    let model = torus();
    let bounds = model.bounds.expect("the fixture declares bounds");
    let r = Profile::default_resin().resin().expect("complete settings");
    bencher.bench(|| {
        let source = Source::field(&model.shape, bounds);
        let spec = GridSpec::Display {
            width: r.resolution[0],
            height: r.resolution[1],
            pixel: r.pixel_size,
            frame: r.frame(),
        };
        let images = render_layers(&source, 0.05, spec, &no_progress).expect("renders");
        let thumb = sl1::thumbnail(
            &images.silhouette,
            images.silhouette_size.0,
            images.silhouette_size.1,
            sl1::THUMBNAIL,
        )
        .expect("thumbnail");
        let mut out = std::io::Cursor::new(Vec::new());
        sl1::write_sl1(&mut out, &images, &r, "torus", &thumb).expect("archive");
        out.into_inner().len()
    });
}
