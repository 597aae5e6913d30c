//! Every name of the script contract's "2D profiles and sweeps" (with textures) and
//! "Surfaces" parts, called from a script and checked to do what the contract says: points
//! that must be inside are, points that must be outside are, and each option changes the
//! shape the way it is documented to.

use std::path::Path;

use isoforge_field::{PointEval, Shape, Tape};
use isoforge_script::{ScriptError, load_file, load_script};

fn load(src: &str) -> Result<Shape, ScriptError> {
    load_script(Path::new("test.rhai"), src, &[]).map(|m| m.shape)
}

fn shape(src: &str) -> Shape {
    load(src).unwrap_or_else(|e| panic!("script failed: {e}\n{src}"))
}

/// Asserts which points are inside (field < 0) and which outside.
fn expect(src: &str, inside: &[[f64; 3]], outside: &[[f64; 3]]) {
    let s = shape(src);
    let tape = Tape::new(&s);
    let mut eval = PointEval::new();
    for &p in inside {
        let v = eval.eval(&tape, p);
        assert!(v < 0.0, "{src}\n{p:?} should be inside, field {v}");
    }
    for &p in outside {
        let v = eval.eval(&tape, p);
        assert!(v > 0.0, "{src}\n{p:?} should be outside, field {v}");
    }
}

/// The error message of a script that must fail.
fn error(src: &str) -> String {
    match load(src) {
        Ok(_) => panic!("should fail: {src}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn profiles_circle_rect_polygon() {
    expect(
        "linear_sweep(circle(2), 4)",
        &[[0.0, 0.0, 2.0], [1.9, 0.0, 0.1], [0.0, -1.9, 3.9]],
        &[[2.1, 0.0, 2.0], [0.0, 0.0, 4.1], [0.0, 0.0, -0.1]],
    );
    // A coarse circle is a regular polygon: its flat sides cut inside the round one.
    expect(
        "linear_sweep(circle(2, #{segments: 4}), 1)",
        &[[1.9, 0.0, 0.5]],
        &[[1.1, 1.1, 0.5]],
    );
    // rect is centred; rounding cuts its corners.
    expect(
        "linear_sweep(rect([4, 2]), 1)",
        &[[1.95, 0.95, 0.5], [-1.95, -0.95, 0.5]],
        &[[2.05, 0.0, 0.5], [0.0, 1.05, 0.5]],
    );
    expect(
        "linear_sweep(rect([4, 2], #{rounding: 0.5}), 1)",
        &[[1.95, 0.0, 0.5], [1.6, 0.6, 0.5]],
        &[[1.95, 0.95, 0.5]],
    );
    // A polygon with a hole.
    expect(
        "linear_sweep(polygon([[[0, 0], [4, 0], [4, 4], [0, 4]], [[1, 1], [3, 1], [3, 3], [1, 3]]]), 1)",
        &[[0.5, 0.5, 0.5], [3.5, 2.0, 0.5]],
        &[[2.0, 2.0, 0.5], [4.5, 2.0, 0.5]],
    );
    expect(
        "linear_sweep(polygon([[0, 0], [4, 0], [0, 4]]), 1)",
        &[[1.0, 1.0, 0.5]],
        &[[2.5, 2.5, 0.5]],
    );
}

#[test]
fn profile_transforms() {
    let at = |src: &str, inside: [f64; 2], outside: [f64; 2]| {
        expect(
            &format!("linear_sweep({src}, 1)"),
            &[[inside[0], inside[1], 0.5]],
            &[[outside[0], outside[1], 0.5]],
        )
    };
    at("move(circle(1), [5, 0])", [5.5, 0.0], [0.0, 0.0]);
    at("circle(1).move([0, 5])", [0.0, 5.5], [0.0, 0.0]);
    at("rotate(rect([4, 1]), 90)", [0.0, 1.8], [1.8, 0.0]);
    at("scale(circle(1), 3)", [2.9, 0.0], [3.1, 0.0]);
    at("scale(circle(1), [3, 1])", [2.9, 0.0], [0.0, 1.1]);
    at("mirror_x(move(circle(1), [5, 0]))", [-5.0, 0.0], [5.0, 0.0]);
    at("mirror_y(move(circle(1), [0, 5]))", [0.0, -5.0], [0.0, 5.0]);
    at("offset(circle(1), 1)", [1.9, 0.0], [2.1, 0.0]);
    at("offset(rect([4, 4]), -1)", [0.9, 0.9], [1.1, 0.0]);
}

#[test]
fn linear_sweep_twist_scale_shift_center() {
    // A bar twisted a quarter turn lies across at the top.
    expect(
        "linear_sweep(rect([4, 1]), 10, #{twist: 90})",
        &[[1.8, 0.0, 0.01], [0.0, 1.8, 9.99]],
        &[[0.0, 1.8, 0.01], [1.8, 0.0, 9.99]],
    );
    expect(
        "linear_sweep(circle(2), 10, #{scale: 0.5})",
        &[[1.9, 0.0, 0.01], [0.9, 0.0, 9.99]],
        &[[1.5, 0.0, 9.99]],
    );
    expect(
        "linear_sweep(circle(1), 10, #{scale: [2, 1]})",
        &[[1.9, 0.0, 9.99]],
        &[[0.0, 1.1, 9.99], [1.1, 0.0, 0.01]],
    );
    expect(
        "linear_sweep(circle(1), 10, #{shift: [3, 0]})",
        &[[0.0, 0.0, 0.01], [3.0, 0.0, 9.99]],
        &[[0.0, 0.0, 9.99]],
    );
    expect(
        "linear_sweep(circle(1), 10, #{center: true, slices: 20})",
        &[[0.0, 0.0, -4.9], [0.0, 0.0, 4.9]],
        &[[0.0, 0.0, 5.1], [0.0, 0.0, -5.1]],
    );
    assert!(error("linear_sweep(circle(1), 10, #{twsit: 90})").contains("twsit"));
}

#[test]
fn revolve_and_rotate_sweep() {
    for name in ["revolve", "rotate_sweep"] {
        // A 2 x 2 square at r = 5 turned about z: a ring.
        expect(
            &format!("{name}(move(rect([2, 2]), [5, 0]))"),
            &[[5.0, 0.0, 0.0], [0.0, 5.0, 0.5], [-4.1, 0.0, -0.9]],
            &[[0.0, 0.0, 0.0], [6.1, 0.0, 0.0], [5.0, 0.0, 1.1]],
        );
    }
    // A quarter turn from +x counter-clockwise, capped at both ends.
    expect(
        "revolve(move(rect([2, 2]), [5, 0]), #{angle: 90})",
        &[[3.5, 3.5, 0.0], [5.0, 0.1, 0.0], [0.1, 5.0, 0.0]],
        &[[-5.0, 0.0, 0.0], [0.0, -5.0, 0.0], [5.0, -0.1, 0.0]],
    );
}

#[test]
fn spiral_sweep_handedness_and_taper() {
    // Radius 5, 10 mm tall centred on z = 0, two turns: the disc's centre passes +x at
    // z = -5, 0, 5, and +y a quarter turn later (right-handed) or earlier (left-handed).
    expect(
        "spiral_sweep(circle(0.5), 10, 5, 2)",
        &[[5.0, 0.0, 0.0], [0.0, 5.0, 1.25]],
        &[[5.0, 0.0, 2.5], [0.0, 5.0, -1.25], [0.0, 0.0, 0.0]],
    );
    expect(
        "spiral_sweep(circle(0.5), 10, 5, -2)",
        &[[5.0, 0.0, 0.0], [0.0, 5.0, -1.25]],
        &[[0.0, 5.0, 1.25]],
    );
    // A taper taken from the turns shrinks the ends to a sliver: 5 degrees after the
    // start, 0.3 mm out from the helix is inside the full disc and outside the sliver.
    let a = 5f64.to_radians();
    let near_start = [
        5.3 * a.cos(),
        5.3 * a.sin(),
        -5.0 + 10.0 / 2.0 * 5.0 / 360.0,
    ];
    expect(
        "spiral_sweep(circle(0.5), 10, 5, 2, #{taper: -10})",
        &[[5.0, 0.0, 0.0], [5.3, 0.0, 0.0]],
        &[near_start],
    );
    expect("spiral_sweep(circle(0.5), 10, 5, 2)", &[near_start], &[]);
}

/// A circle of radius 10 in the xy plane as a path, point array or closure.
const RING_POINTS: &str = "let ring = []; for i in 0..64 { let a = i * 2 * PI / 64; ring.push([10 * cos(a), 10 * sin(a), 0]); }";

#[test]
fn path_sweep_paths_methods_and_options() {
    // Along a straight path the profile's x and y map across it.
    expect(
        "path_sweep(circle(1), [[0, 0, 0], [0, 0, 10]])",
        &[[0.0, 0.0, 5.0], [0.9, 0.0, 9.9]],
        &[[1.1, 0.0, 5.0], [0.0, 0.0, 10.5]],
    );
    for method in ["incremental", "natural"] {
        expect(
            &format!(
                "{RING_POINTS} path_sweep(circle(1), ring, #{{closed: true, method: \"{method}\"}})"
            ),
            &[[10.0, 0.0, 0.0], [0.0, -10.5, 0.0], [-7.07, 7.07, 0.9]],
            &[[0.0, 0.0, 0.0], [11.1, 0.0, 0.0], [10.0, 0.0, 1.1]],
        );
    }
    // A closure path, closed: a torus without a seam where it meets itself.
    expect(
        "path_sweep(circle(1), |s| [10 * cos(2 * PI * s), 10 * sin(2 * PI * s), 0], #{closed: true})",
        &[[10.0, 0.0, 0.0], [10.0, -0.05, 0.0], [10.0, 0.05, 0.0]],
        &[[0.0, 0.0, 0.0]],
    );
    // manual: the profile's y follows the given normal, so a 4 x 0.4 bar is thin along it.
    expect(
        "path_sweep(rect([4, 0.4]), [[0, 0, 0], [10, 0, 0]], #{method: \"manual\", normal: [0, 0, 1]})",
        &[[5.0, 0.0, 0.15], [5.0, 1.5, 0.0]],
        &[[5.0, 0.0, 1.5], [5.0, 2.5, 0.0]],
    );
    expect(
        "path_sweep(rect([4, 0.4]), [[0, 0, 0], [10, 0, 0]], #{method: \"manual\", normal: [0, 1, 0]})",
        &[[5.0, 0.15, 0.0], [5.0, 0.0, 1.5]],
        &[[5.0, 1.5, 0.0], [5.0, 0.0, 2.5]],
    );
    // twist turns the profile by the end, scale grows it.
    expect(
        "path_sweep(rect([4, 0.4]), [[0, 0, 0], [0, 0, 10]], #{twist: 90})",
        &[[1.8, 0.0, 0.05], [0.0, 1.8, 9.95]],
        &[[0.0, 1.8, 0.05], [1.8, 0.0, 9.95]],
    );
    expect(
        "path_sweep(circle(1), [[0, 0, 0], [0, 0, 10]], #{scale: 2})",
        &[[1.9, 0.0, 9.9]],
        &[[1.1, 0.0, 0.1]],
    );
    assert!(
        error("path_sweep(circle(1), [[0, 0, 0], [0, 0, 1]], #{method: \"nope\"})")
            .contains("method")
    );
}

#[test]
fn skin_methods_and_different_point_counts() {
    // A square at the bottom and a circle of many points on top.
    for method in ["direct", "distance", "tangent", "reindex", "fast_distance"] {
        for sampling in ["length", "segment"] {
            expect(
                &format!(
                    "skin([rect([4, 4]), circle(1, #{{segments: 24}})], [0, 10], #{{method: \"{method}\", sampling: \"{sampling}\", slices: 4}})"
                ),
                &[[1.9, 1.9, 0.01], [0.0, 0.0, 5.0], [0.9, 0.0, 9.99]],
                &[[1.5, 0.0, 9.99], [2.1, 0.0, 0.01], [0.0, 0.0, 10.1]],
            );
        }
    }
    // Three sections: narrow in the middle.
    expect(
        "skin([circle(3), circle(1), circle(3)], [0, 5, 10])",
        &[[2.9, 0.0, 0.01], [0.9, 0.0, 5.0], [2.9, 0.0, 9.99]],
        &[[1.5, 0.0, 5.0]],
    );
}

#[test]
fn every_named_texture_displaces_a_cylinder() {
    for name in [
        "ribs",
        "trunc_ribs",
        "wave_ribs",
        "diamonds",
        "pyramids",
        "trunc_pyramids",
        "dimpled_pyramids",
        "hills",
        "waves",
        "dots",
        "cones",
    ] {
        let src =
            format!("textured_cylinder(10, 20, \"{name}\", #{{tex_size: [4, 4], tex_depth: 1}})");
        let s = shape(&src);
        let tape = Tape::new(&s);
        let mut eval = PointEval::new();
        // Centred on z = 0; the core is solid and the texture rises out of it by at most
        // the depth.
        let ring = |r: f64, z: f64| {
            (0..720).map(move |k| {
                let a = k as f64 * std::f64::consts::TAU / 720.0;
                [r * a.cos(), r * a.sin(), z]
            })
        };
        for z in [-5.0, 0.3, 4.1] {
            assert!(
                ring(9.9, z).all(|p| eval.eval(&tape, p) < 0.0),
                "{name}: core"
            );
            assert!(
                ring(11.1, z).all(|p| eval.eval(&tape, p) > 0.0),
                "{name}: beyond"
            );
        }
        // Between, the texture is high at some places and low at others.
        let values: Vec<f64> = [-5.0, -3.7, 0.3, 1.1, 4.1]
            .into_iter()
            .flat_map(|z| ring(10.5, z))
            .map(|p| eval.eval(&tape, p))
            .collect();
        assert!(values.iter().any(|&v| v < 0.0), "{name}: never rises");
        assert!(values.iter().any(|&v| v > 0.0), "{name}: always high");
        assert!(eval.eval(&tape, [0.0, 0.0, 10.1]) > 0.0, "{name}: top");
    }
}

#[test]
fn texture_options_move_the_surface() {
    // Ribs run up the side; turned by tex_rot they run around it.
    let ribs_vary_along = |opts: &str| {
        let s = shape(&format!(
            "textured_cylinder(10, 20, \"ribs\", #{{tex_size: [4, 4], tex_depth: 1{opts}}})"
        ));
        let tape = Tape::new(&s);
        let mut eval = PointEval::new();
        let around: Vec<f64> = (0..200)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 200.0;
                eval.eval(&tape, [10.5 * a.cos(), 10.5 * a.sin(), 1.0])
            })
            .collect();
        let up: Vec<f64> = (0..200)
            .map(|k| eval.eval(&tape, [10.5, 0.0, -8.0 + k as f64 * 0.08]))
            .collect();
        let spread = |v: &[f64]| {
            v.iter().copied().fold(f64::MIN, f64::max) - v.iter().copied().fold(f64::MAX, f64::min)
        };
        (spread(&around), spread(&up))
    };
    let (around, up) = ribs_vary_along("");
    assert!(around > 0.5 && up < 1e-6, "ribs: {around} around, {up} up");
    let (around, up) = ribs_vary_along(", tex_rot: true");
    assert!(
        around < 1e-6 && up > 0.5,
        "turned ribs: {around} around, {up} up"
    );

    // tex_inset sinks the texture: true by its whole depth, a number by that many mm.
    expect(
        "textured_cylinder(10, 20, \"dots\", #{tex_depth: 1, tex_inset: true})",
        &[[8.9, 0.0, 0.0]],
        &[[10.1, 0.0, 0.0]],
    );
    expect(
        "textured_cylinder(10, 20, \"dots\", #{tex_depth: 1, tex_inset: 0.5})",
        &[[9.4, 0.0, 0.0]],
        &[[10.6, 0.0, 0.0]],
    );
    // counts: a whole number of tiles around and up. Four ribs around: the field repeats
    // every quarter turn, and not every eighth.
    let s = shape("textured_cylinder(10, 20, \"ribs\", #{counts: [4, 1], tex_depth: 1})");
    let tape = Tape::new(&s);
    let mut eval = PointEval::new();
    let at = |eval: &mut PointEval, deg: f64| {
        let a = deg.to_radians();
        eval.eval(&tape, [10.5 * a.cos(), 10.5 * a.sin(), 2.0])
    };
    let (a, b, c) = (
        at(&mut eval, 10.0),
        at(&mut eval, 100.0),
        at(&mut eval, 55.0),
    );
    assert!((a - b).abs() < 1e-6 && (a - c).abs() > 0.1, "{a} {b} {c}");
    assert!(
        error("textured_cylinder(10, 20, \"ribs\", #{counts: [4, 1], tex_size: [2, 2]})")
            .contains("not both")
    );
    assert!(error("textured_cylinder(10, 20, \"bumps\")").contains("bumps"));
}

#[test]
fn textured_sweeps_and_height_arrays() {
    // A textured square prism: the sides carry the texture, the core stays.
    expect(
        "textured_linear_sweep(rect([20, 20]), \"pyramids\", 10, #{tex_size: [5, 5], tex_depth: 1})",
        &[[9.9, 0.0, 5.0], [0.0, 0.0, 5.0]],
        &[[11.1, 0.0, 5.0], [0.0, 0.0, 10.1]],
    );
    expect(
        "textured_linear_sweep(circle(5), \"ribs\", 10, #{tex_size: [2, 2], tex_depth: 1, twist: 30, scale: 1.2})",
        &[[5.9, 0.0, 9.9]],
        &[[7.3, 0.0, 9.9]],
    );
    // A revolved profile (a ring at r = 8) with waves around it, part of a turn.
    expect(
        "textured_revolution(move(rect([2, 6]), [8, 0]), \"waves\", #{tex_size: [3, 3], tex_depth: 0.5, angle: 180})",
        &[[0.0, 8.0, 0.0]],
        &[[0.0, -8.0, 0.0], [9.6, 0.0, 0.0]],
    );
    // A height array: one tile of two rows, high on one side.
    let s = shape(
        "textured_cylinder(10, 20, [[0, 0, 1, 1], [0, 0, 1, 1]], #{counts: [8, 1], tex_depth: 1})",
    );
    let tape = Tape::new(&s);
    let mut eval = PointEval::new();
    let ring: Vec<f64> = (0..400)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 400.0;
            eval.eval(&tape, [10.5 * a.cos(), 10.5 * a.sin(), 0.0])
        })
        .collect();
    assert!(ring.iter().any(|&v| v < 0.0) && ring.iter().any(|&v| v > 0.0));
    assert!(error("textured_cylinder(10, 20, [[0, \"a\"]])").contains("row 0"));
}

#[test]
fn image_textures_come_from_the_scripts_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    // An 8 x 8 grayscale picture: the left half black, the right half white.
    let png_path = dir.path().join("half.png");
    {
        let file = std::fs::File::create(&png_path).expect("png file");
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), 8, 8);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().expect("header");
        let px: Vec<u8> = (0..64).map(|i| if i % 8 < 4 { 0 } else { 255 }).collect();
        w.write_image_data(&px).expect("pixels");
    }
    let script = dir.path().join("knob.rhai");
    std::fs::write(
        &script,
        "textured_cylinder(10, 20, image(\"half.png\"), #{counts: [6, 1], tex_depth: 1})",
    )
    .expect("script");
    let model = load_file(&script, &[]).unwrap_or_else(|e| panic!("{e}"));
    let tape = Tape::new(&model.shape);
    let mut eval = PointEval::new();
    let ring: Vec<f64> = (0..600)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 600.0;
            eval.eval(&tape, [10.5 * a.cos(), 10.5 * a.sin(), 0.0])
        })
        .collect();
    let high = ring.iter().filter(|&&v| v < 0.0).count();
    // Half of every tile is white (raised): about half of the ring is inside.
    assert!((200..400).contains(&high), "{high} of 600 raised");
    // Nothing outside the script's folder, and only files that are there.
    std::fs::write(&script, "textured_cylinder(10, 20, image(\"../half.png\"))").expect("script");
    let e = load_file(&script, &[]).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("image"), "{e}");
    std::fs::write(&script, "textured_cylinder(10, 20, image(\"missing.png\"))").expect("script");
    let e = load_file(&script, &[]).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("missing.png"), "{e}");
}

const NET: &str = "let net = [
    [[0, 0, 0], [0, 1, 1], [0, 2, 1], [0, 3, 1]],
    [[1, 0, 1], [1, 1, 2], [1, 2, 2], [1, 3, 1]],
    [[2, 0, 1], [2, 1, 2], [2, 2, 3], [2, 3, 2]],
    [[3, 0, 0], [3, 1, 1], [3, 2, 1], [3, 3, 2]],
];";

#[test]
fn bezier_surface_is_a_sheet_through_its_middle() {
    // Q(0.5, 0.5) of this net, by the Bernstein sum (weights 1/8, 3/8, 3/8, 1/8 each
    // way): rows of z weigh 7/8, 14/8, 18/8 and 8/8, so z = (7 + 42 + 54 + 8) / 64.
    let q = [1.5, 1.5, 111.0 / 64.0];
    for edges in ["round", "flat"] {
        expect(
            &format!("{NET} bezier_surface(net, 0.4, #{{edges: \"{edges}\"}})"),
            &[q, [q[0], q[1], q[2] + 0.1], [q[0], q[1], q[2] - 0.1]],
            &[[q[0], q[1], q[2] + 0.4], [q[0], q[1], q[2] - 0.4]],
        );
    }
    // A 2 x 3 net (any size): a bent strip through its corners.
    expect(
        "bezier_surface([[[0, 0, 0], [0, 5, 2], [0, 10, 0]], [[10, 0, 0], [10, 5, 2], [10, 10, 0]]], 0.5)",
        &[[5.0, 5.0, 1.0], [0.05, 0.05, 0.0]],
        &[[5.0, 5.0, 0.0], [5.0, 5.0, 2.0]],
    );
    assert!(error("bezier_surface([[[0, 0, 0]]], 0.5)").contains("bezier_surface"));
}

#[test]
fn bspline_surface_degrees_and_clamping() {
    // A flat 5 x 5 net at z = 0 over [0, 4]²: every degree is the plane z = 0 there; only
    // the clamped one reaches the net's border.
    let net = "let net = []; for i in 0..5 { let row = []; for j in 0..5 { row.push([i, j, 0]); } net.push(row); }";
    for degree in 1..=3 {
        expect(
            &format!("{net} bspline_surface(net, {degree}, 0.2, #{{clamped: true}})"),
            &[[2.0, 2.0, 0.0], [0.05, 2.0, 0.0], [3.95, 3.95, 0.0]],
            &[[2.0, 2.0, 0.2], [4.3, 2.0, 0.0]],
        );
    }
    // Unclamped, degree 3 starts at the first span's blend (1/6 + 4/6 + 1/6 of rows 0..2):
    // x = 1, so x = 0.5 is off the sheet.
    expect(
        &format!("{net} bspline_surface(net, 3, 0.2, #{{edges: \"flat\"}})"),
        &[[2.0, 2.0, 0.0]],
        &[[0.5, 2.0, 0.0]],
    );
    assert!(error(&format!("{net} bspline_surface(net, 4, 0.2)")).contains("degree"));
}

#[test]
fn coons_patch_keeps_its_boundary() {
    // The lecture's four curves, 10 mm across.
    let curves = "let c0 = |s| [10 * s, 0, 5 * sin(2 * PI * s)];
        let c1 = |s| [10 * s, 10, 5 * sin(PI * s)];
        let d0 = |t| [0, 10 * t, 0];
        let d1 = |t| [10, 10 * t, 0];";
    // On the edges the patch is the curves: P(0.25, 0) = (2.5, 0, 5) and P(0.5, 1) =
    // (5, 10, 5); inside, the bilinear blend at (0.5, 0.5) is (5, 5, 2.5).
    expect(
        &format!("{curves} coons_patch(c0, c1, d0, d1, 0.4)"),
        &[[2.5, 0.05, 5.0], [5.0, 9.95, 5.0], [5.0, 5.0, 2.5]],
        &[[5.0, 5.0, 3.3], [5.0, 5.0, 1.7]],
    );
    assert!(
        error("coons_patch(|s| [s, 0, 0], |s| [s, 1, 0], |t| [0, t, 0], |t| 5, 0.4)")
            .contains("coons_patch")
    );
}

/// A sweep an OpenSCAD user writes without `bounds(..)` finds its own region, tight around
/// it: the twist, the scale and the helix once left every interval unbounded.
#[test]
fn twisted_scaled_shifted_and_spiral_sweeps_find_their_region() {
    let cases = [
        ("linear_sweep(rect([10, 10]), 20, #{twist: 90})", 7.08, 20.0),
        ("linear_sweep(rect([10, 10]), 20, #{scale: 0.5})", 5.0, 20.0),
        (
            "linear_sweep(rect([10, 10]), 20, #{scale: [0.5, 2], twist: 45})",
            11.0,
            20.0,
        ),
        (
            "linear_sweep(circle(3), 10, #{shift: [4, 0], center: true})",
            7.0,
            5.0,
        ),
        ("spiral_sweep(circle(1), 20, 5, 3)", 6.0, 11.0),
        (
            "textured_linear_sweep(circle(5), \"ribs\", 10, #{tex_size: [2, 2], tex_depth: 1, scale: 1.2})",
            7.0,
            10.0,
        ),
    ];
    for (src, radius, top) in cases {
        let found = isoforge_field::find_bounds(&shape(src))
            .unwrap_or_else(|e| panic!("{src}: no region: {e}"));
        // Near the solid: the search is by intervals (a texture's are loose), and a can a
        // millimetre wider than the solid bounds the spiral.
        let slack = 0.75 * radius;
        for a in 0..2 {
            assert!(
                found.max[a] <= radius + slack && found.min[a] >= -radius - slack,
                "{src}: {found:?}"
            );
        }
        assert!(
            found.max[2] >= top - 1e-6 && found.max[2] <= top + slack,
            "{src}: {found:?}"
        );
    }
}
