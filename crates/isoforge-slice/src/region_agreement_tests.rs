//! (Unit tests: outlines are internal to the slicer.)
//!
//! The mesher, the slicer and the renderer agree on what is inside a model's region: all
//! three evaluate `isoforge_field::ClippedField`, and this checks that they do.
//!
//! The model is a prism constant in z, x² + y² < 1.44, undefined (NaN) for x < 0, in the
//! region [-1, 1] x [-1, 1] x [-0.5, 0.5]: what is inside is the half disc x ≥ 0 of radius
//! 1.2 cut by the region's faces at x = 1 and y = ±1, one unit tall. A caller that let the
//! region's distance hide a NaN (float `max` does) would see the half x < 0 as inside; one
//! that ignored the region would see the whole half disc. Each is off by 20 % or more.

use crate::{Source, geom::Contour};
use isoforge_field::{Bounds, Shape};
use isoforge_mesh::{MeshSettings, check, mesh_shape};
use isoforge_render::{RenderSettings, View, render};

fn model() -> (Shape, Bounds) {
    let (x, y) = (Shape::x(), Shape::y());
    let shape = x.square() + y.square() - 1.44 + x.sqrt() * 0.0 + Shape::z() * 0.0;
    let region = Bounds::new([-1.0, -1.0, -0.5], [1.0, 1.0, 0.5]).expect("box");
    (shape, region)
}

/// The exact section: ∫ over x in [0, 1] of 2 · min(1, sqrt(1.44 − x²)), by the midpoint
/// rule on a fine grid (error far below the tolerances here).
fn exact_area() -> f64 {
    let n = 100_000;
    (0..n)
        .map(|i| {
            let x = (i as f64 + 0.5) / n as f64;
            2.0 * (1.44 - x * x).sqrt().min(1.0)
        })
        .sum::<f64>()
        / n as f64
}

fn area(contours: &[Contour]) -> f64 {
    contours
        .iter()
        .map(|c| {
            let n = c.len();
            (0..n)
                .map(|i| {
                    let (a, b) = (c[i], c[(i + 1) % n]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
                * 0.5
        })
        .sum()
}

#[test]
fn mesher_slicer_and_renderer_agree_on_the_inside() {
    let (shape, region) = model();
    let want = exact_area();

    // The mesher: a closed mesh of the prism, one unit tall.
    let mesh = mesh_shape(&shape, &MeshSettings::new(region, 7));
    let report = check(&mesh);
    assert!(report.is_closed_manifold(), "{:?}", report.problems());
    assert!(
        (report.volume / want - 1.0).abs() < 0.01,
        "mesh volume {} vs {want}",
        report.volume
    );

    // The slicer: the same section at every height, and the same height range.
    let sliceable = Source::field(&shape, region)
        .prepare(0.01, 0.001)
        .expect("the model has material");
    let (z0, z1) = sliceable.z_range;
    assert!(
        (z0 + 0.5).abs() < 0.01 && (z1 - 0.5).abs() < 0.01,
        "{z0} .. {z1}"
    );
    for z in [-0.4, 0.0, 0.37] {
        let got = area(&sliceable.outline(z, (z - 0.05, z + 0.05)));
        assert!(
            (got / want - 1.0).abs() < 0.005,
            "z {z}: area {got} vs {want}"
        );
    }

    // The renderer: seen from the top, the filled pixels cover the section.
    let (w, h) = (200, 200);
    let settings = RenderSettings {
        view: View::Top,
        fit: false,
        ..RenderSettings::new(w, h)
    };
    let img = render(&shape, &region, &settings);
    let background = img.pixel(0, 0);
    let filled = (0..w * h)
        .filter(|i| img.pixel(i % w, i / w) != background)
        .count() as f64;
    // Without fitting, the region's 2 mm span the width / 1.08.
    let pixel = 2.0 * 1.08 / f64::from(w);
    let got = filled * pixel * pixel;
    assert!(
        (got / want - 1.0).abs() < 0.02,
        "picture area {got} vs {want}"
    );
}
