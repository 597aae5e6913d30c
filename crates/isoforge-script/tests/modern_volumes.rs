//! The modern library's exact cases: each model meshed at depth 8 must be closed and
//! manifold (the project's checker) and its volume within 0.5% of the formula's.

use std::f64::consts::PI;
use std::path::Path;

use isoforge_mesh::{MeshSettings, check, mesh_shape};
use isoforge_script::load_script;

/// Meshes a script at a depth over its declared bounds: (closed and manifold, volume).
fn meshed(source: &str, depth: u8) -> (bool, f64) {
    let model = load_script(Path::new("volume_test.rhai"), source, &[])
        .unwrap_or_else(|e| panic!("{e}\n{source}"));
    let bounds = model.bounds.expect("the test script declares bounds");
    let mesh = mesh_shape(&model.shape, &MeshSettings::new(bounds, depth));
    let report = check(&mesh);
    (report.is_closed_manifold(), report.volume)
}

fn expect_volume(name: &str, source: &str, want: f64) {
    let (closed, volume) = meshed(source, 8);
    let error = (volume - want) / want;
    println!(
        "{name}: volume {volume:.3}, exact {want:.3}, error {:+.4}%",
        100.0 * error
    );
    assert!(closed, "{name}: not closed and manifold");
    assert!(
        error.abs() < 0.005,
        "{name}: volume {volume} vs exact {want} ({:+.3}%)",
        100.0 * error
    );
}

#[test]
fn shell_of_a_sphere_is_the_hollow_ball() {
    expect_volume(
        "shell(sphere(10), 1)",
        "bounds([-11, -11, -11], [11, 11, 11]); shell(sphere(10), 1)",
        4.0 / 3.0 * PI * (1000.0 - 729.0),
    );
}

#[test]
fn offset_of_a_box_is_the_rounded_box() {
    expect_volume(
        "offset(box([10, 10, 10]), 1)",
        "bounds([-7, -7, -7], [7, 7, 7]); offset(box([10, 10, 10]), 1)",
        1000.0 + 600.0 + 30.0 * PI + 4.0 * PI / 3.0,
    );
}

#[test]
fn hull_of_two_equal_spheres_is_a_capsule() {
    expect_volume(
        "hull of two spheres",
        "bounds([-6, -6, -6], [26, 6, 6]);
         hull([sphere(5), sphere(5).move([20, 0, 0])])",
        PI * 25.0 * 20.0 + 4.0 / 3.0 * PI * 125.0,
    );
}

/// OpenSCAD's rounded tetrahedron: the hull of four radius-4 balls at alternate corners
/// of a 100 mm cube is a regular tetrahedron (edge a = 100√2) grown by 4 mm, whose volume
/// Steiner's formula gives: V + S·r + M·r² + 4/3·π·r³, with M the sum over the six edges
/// of length × (π − dihedral angle) / 2.
#[test]
fn hull_of_four_spheres_is_steiners_rounded_tetrahedron() {
    let a = 100.0 * 2f64.sqrt();
    let r = 4.0;
    let volume = a.powi(3) / (6.0 * 2f64.sqrt());
    let area = 3f64.sqrt() * a * a;
    let dihedral = (1.0f64 / 3.0).acos();
    let mean = 6.0 * a * (PI - dihedral) / 2.0;
    let want = volume + area * r + mean * r * r + 4.0 / 3.0 * PI * r.powi(3);
    expect_volume(
        "hull of four spheres",
        "bounds([-5, -5, -5], [105, 105, 105]);
         hull([sphere(4), sphere(4).move([100, 100, 0]),
               sphere(4).move([0, 100, 100]), sphere(4).move([100, 0, 100])])",
        want,
    );
}

#[test]
fn one_metaball_at_threshold_one_is_its_sphere() {
    let want = 4.0 / 3.0 * PI * 6f64.powi(3);
    expect_volume(
        "metaballs, Blinn",
        "bounds([-8, -8, -8], [8, 8, 8]); metaballs([[0, 0, 0, 6]], 1)",
        want,
    );
    expect_volume(
        "metaballs, Wyvill",
        r#"bounds([-8, -8, -8], [8, 8, 8]); metaballs([[0, 0, 0, 6]], 1, #{falloff: "wyvill"})"#,
        want,
    );
}

#[test]
fn a_tube_round_a_circle_is_a_torus() {
    expect_volume(
        "curve_tube of a circle",
        "bounds([-13, -13, -3], [13, 13, 3]);
         curve_tube(|s| [10 * cos(s), 10 * sin(s), 0], |s, theta| 2, 0, 2 * PI)",
        2.0 * PI * PI * 10.0 * 4.0,
    );
}

#[test]
fn a_flat_height_field_with_a_thickness_is_a_slab() {
    expect_volume(
        "cartesian slab",
        "bounds([-5, -5, -3], [5, 5, 1]); cartesian(|x, y| 0, 2)",
        10.0 * 10.0 * 2.0,
    );
}

#[test]
fn a_constant_radius_function_is_a_sphere() {
    expect_volume(
        "spherical",
        "bounds([-6, -6, -6], [6, 6, 6]); spherical(|theta, phi| 5, [0, 0, 0])",
        4.0 / 3.0 * PI * 125.0,
    );
}
