//! The renderer end to end on small pictures: sizes, shading, clipping, NaN, framing,
//! and that each view shows the model from its own side.

use isoforge_field::{Bounds, Shape};

use crate::shade::{BACKGROUND, to_rgb};
use crate::{Image, RenderSettings, View, render};

fn sphere(r: f64) -> Shape {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    x.square() + y.square() + z.square() - r * r
}

fn region(h: f64) -> Bounds {
    Bounds::new([-h; 3], [h; 3]).unwrap()
}

fn is_background(p: [u8; 3]) -> bool {
    p == to_rgb(BACKGROUND)
}

/// Pixels that show the model.
fn filled(img: &Image) -> usize {
    (0..img.width * img.height)
        .filter(|i| !is_background(img.pixel(i % img.width, i / img.width)))
        .count()
}

/// The filled pixels' bounding box: (columns, rows).
fn extent(img: &Image) -> (u32, u32) {
    let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            if !is_background(img.pixel(x, y)) {
                (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
            }
        }
    }
    (x1.saturating_sub(x0), y1.saturating_sub(y0))
}

fn view(view: View, w: u32, h: u32) -> RenderSettings {
    RenderSettings {
        view,
        fit: false,
        ..RenderSettings::new(w, h)
    }
}

#[test]
fn sphere_fills_a_disc_of_the_right_size() {
    for v in View::ALL {
        let s = RenderSettings {
            view: v,
            ..RenderSettings::new(64, 64)
        };
        let img = render(&sphere(1.0), &region(1.0), &s);
        assert_eq!(img.pixels.len(), 64 * 64 * 3);
        assert!(
            !is_background(img.pixel(32, 32)),
            "{v:?}: centre is surface"
        );
        assert!(
            is_background(img.pixel(0, 0)),
            "{v:?}: corner is background"
        );
        if v != View::Iso {
            // The region's projection spans the image width / 1.08: a disc of radius
            // 64 / 2 / 1.08 pixels.
            let r = 32.0 / 1.08;
            let want = std::f64::consts::PI * r * r;
            let got = filled(&img) as f64;
            assert!((got - want).abs() / want < 0.05, "{v:?}: {got} vs {want}");
        }
    }
}

#[test]
fn each_view_shows_its_own_side() {
    // A box 1.6 long in x, 0.8 in y, 0.4 in z, in a cube region: its picture is wide and
    // short from the front, wide and taller from the top, narrow from the right.
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let bar = (x.abs() - 0.8).max(&(y.abs() - 0.4)).max(&(z.abs() - 0.2));
    let size = |v: View| extent(&render(&bar, &region(1.0), &view(v, 60, 60)));
    let (top, front, right) = (size(View::Top), size(View::Front), size(View::Right));
    // One pixel is 2 * 1.08 / 60 mm: 1.6 mm is about 44 pixels, 0.8 about 22, 0.4 about 11.
    let near = |got: u32, mm: f64| (f64::from(got) - mm * 60.0 / 2.16).abs() <= 2.0;
    assert!(near(top.0, 1.6) && near(top.1, 0.8), "top {top:?}");
    assert!(near(front.0, 1.6) && near(front.1, 0.4), "front {front:?}");
    assert!(near(right.0, 0.8) && near(right.1, 0.4), "right {right:?}");
    // From the iso view, all three faces show with three different shades.
    let img = render(&bar, &region(1.0), &view(View::Iso, 80, 80));
    let mut shades: Vec<[u8; 3]> = (0..80 * 80)
        .map(|i| img.pixel(i % 80, i / 80))
        .filter(|p| !is_background(*p))
        .collect();
    shades.sort_unstable();
    shades.dedup();
    assert!(shades.len() >= 3, "{shades:?}");
}

#[test]
fn lit_side_is_brighter_than_the_shadow_side() {
    let img = render(&sphere(1.0), &region(1.0), &RenderSettings::new(64, 64));
    let lum = |p: [u8; 3]| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
    // The key light comes from the upper left.
    assert!(lum(img.pixel(22, 22)) > lum(img.pixel(42, 42)) + 60);
}

#[test]
fn clipped_half_space_shows_its_cut_face() {
    // z < 0 everywhere below: clipped to the box it is a slab whose top is flat.
    let img = render(&Shape::z(), &region(1.0), &view(View::Top, 16, 16));
    let centre = img.pixel(8, 8);
    assert!(!is_background(centre));
    for (x, y) in [(4, 4), (12, 5), (6, 11)] {
        assert_eq!(img.pixel(x, y), centre, "a flat face shades evenly");
    }
}

#[test]
fn undefined_parts_show_as_background() {
    // sqrt(x) is NaN for x < 0: the left half of a top view shows nothing, the right
    // half the slab x > 0.25 of the (clipped) half space.
    let (x, y) = (Shape::x(), Shape::y());
    let f = 0.5 - x.sqrt() + y * 0.0;
    let img = render(&f, &region(1.0), &view(View::Top, 40, 40));
    assert!(is_background(img.pixel(8, 20)));
    assert!(is_background(img.pixel(22, 20)));
    assert!(!is_background(img.pixel(34, 20)));
}

#[test]
fn fitting_frames_the_model_not_the_region() {
    // A small ball in a large region: framed on the ball it fills far more of the picture.
    let whole = render(&sphere(0.5), &region(4.0), &view(View::Top, 48, 48));
    let fitted = render(
        &sphere(0.5),
        &region(4.0),
        &RenderSettings {
            view: View::Top,
            ..RenderSettings::new(48, 48)
        },
    );
    assert!(
        filled(&fitted) > 8 * filled(&whole),
        "{} vs {}",
        filled(&fitted),
        filled(&whole)
    );
    assert!(is_background(fitted.pixel(0, 0)), "the margin stays");
}

#[test]
fn empty_region_is_all_background() {
    let img = render(
        &sphere(0.5),
        &Bounds::new([3.0; 3], [4.0; 3]).unwrap(),
        &RenderSettings::new(20, 10),
    );
    assert_eq!((img.width, img.height), (20, 10));
    assert_eq!(filled(&img), 0);
}
