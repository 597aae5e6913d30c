//! Layer images: white area per layer against the exact section, from the field and from a
//! mesh; a model larger than the display is refused.

mod common;

use common::{Known, sphere, torus};
use isoforge_mesh::{MeshSettings, mesh_shape};
use isoforge_slice::{GridSpec, SliceError, Source, render_layers};

const PIXEL: f64 = 0.05;

fn display() -> GridSpec {
    GridSpec::Display {
        width: 900,
        height: 900,
        pixel: PIXEL,
        frame: isoforge_slice::DisplayFrame::default(),
    }
}

/// Checks every layer whose section is at least `min_area` mm² (tiny caps are a handful of
/// pixels, where 1% is below one pixel).
fn check_areas(k: &Known, source: Source, tol: f64, min_area: f64) {
    let img = render_layers(&source, 0.2, display(), &|_, _| {}).unwrap();
    let mut checked = 0;
    for (l, a) in img.layers.iter().zip(&img.areas) {
        let exact = (k.area)(l.model_z);
        if exact < min_area {
            continue;
        }
        checked += 1;
        assert!(
            (a / exact - 1.0).abs() < tol,
            "z {}: {a} vs {exact}",
            l.model_z
        );
    }
    assert!(checked > 10);
    // The stored PNGs hold the same pixels.
    let mid = img.layers.len() / 2;
    let dec = png::Decoder::new(std::io::Cursor::new(&img.pngs[mid]));
    let mut reader = dec.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    let white: f64 = buf.iter().map(|&v| v as f64 / 255.0).sum::<f64>() * PIXEL * PIXEL;
    assert!((white - img.areas[mid]).abs() < 1e-6 * img.areas[mid].max(1.0));
}

#[test]
fn field_layers_have_the_exact_area() {
    let s = sphere(10.0);
    check_areas(&s, Source::field(&s.shape, s.bounds), 0.01, 10.0);
    let t = torus(15.0, 5.0);
    let t = Known {
        bounds: isoforge_field::Bounds::new([-21.0, -21.0, -6.0], [21.0, 21.0, 6.0]).unwrap(),
        ..t
    };
    check_areas(&t, Source::field(&t.shape, t.bounds), 0.01, 10.0);
}

#[test]
fn mesh_layers_have_the_mesh_area() {
    let s = sphere(10.0);
    let mesh = mesh_shape(&s.shape, &MeshSettings::new(s.bounds, 7));
    // The mesh itself is within ~0.2% of the sphere at this depth.
    check_areas(&s, Source::mesh(&mesh), 0.015, 10.0);
}

#[test]
fn a_model_larger_than_the_display_is_refused() {
    let s = sphere(30.0);
    match render_layers(
        &Source::field(&s.shape, s.bounds),
        1.0,
        display(),
        &|_, _| {},
    ) {
        Err(SliceError::LargerThanDisplay { display, .. }) => {
            assert!(display[0] < 60.0, "{display:?}");
        }
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a 60 mm sphere fit a 45 mm display"),
    }
}
