//! Sweeps meshed at depth 8 have the volumes their geometry says (within 0.5 %), and
//! mesh closed and manifold: the list of exact cases.

use std::f64::consts::{PI, TAU};

use glam::DVec3;
use isoforge_field::{Bounds, Shape};
use isoforge_mesh::{MeshSettings, check, mesh_shape};
use isoforge_shapes::profile::{circle, rect};
use isoforge_shapes::sweep::{
    LinearSweep, PathSweep, SkinOptions, SpiralSweep, linear_sweep, path_sweep, revolve, skin,
    spiral_sweep,
};

/// Meshes at depth 8 over a cube of half-side `half` around `centre`, checks the mesh and
/// returns its volume.
fn volume(s: &Shape, centre: [f64; 3], half: f64) -> f64 {
    let b = Bounds::new(centre.map(|c| c - half), centre.map(|c| c + half)).unwrap();
    let mesh = mesh_shape(s, &MeshSettings::new(b, 8));
    let report = check(&mesh);
    assert!(report.is_closed_manifold(), "{report:?}");
    report.volume
}

fn assert_close(what: &str, got: f64, want: f64) {
    let err = (got - want).abs() / want;
    println!(
        "{what}: {got:.4} vs {want:.4} ({:+.3} %)",
        100.0 * (got - want) / want
    );
    assert!(
        err < 0.005,
        "{what}: {got} vs {want} ({:.3} %)",
        err * 100.0
    );
}

#[test]
fn twisted_square_keeps_its_volume() {
    let sq = rect([10.0, 10.0], 0.0).unwrap();
    for twist in [0.0, 60.0, 180.0] {
        let s = linear_sweep(
            &sq,
            &LinearSweep {
                twist,
                ..LinearSweep::new(20.0)
            },
        )
        .unwrap();
        assert_close(
            &format!("twist {twist}"),
            volume(&s, [0.0, 0.0, 10.0], 11.0),
            2000.0,
        );
    }
}

#[test]
fn scaled_square_is_a_frustum() {
    let sq = rect([10.0, 10.0], 0.0).unwrap();
    let k: f64 = 0.5;
    let s = linear_sweep(
        &sq,
        &LinearSweep {
            scale: [k, k],
            twist: 45.0,
            ..LinearSweep::new(20.0)
        },
    )
    .unwrap();
    let want = 100.0 * 20.0 * (1.0 + k + k * k) / 3.0;
    assert_close("frustum", volume(&s, [0.0, 0.0, 10.0], 11.0), want);
}

#[test]
fn revolved_rectangle_is_an_annulus() {
    let r = rect([2.0, 4.0], 0.0)
        .unwrap()
        .translate([5.0, 0.0])
        .unwrap();
    let full = revolve(&r, 360.0).unwrap();
    let want = PI * (36.0 - 16.0) * 4.0;
    assert_close("annulus", volume(&full, [0.0, 0.0, 0.0], 6.5), want);
    let part = revolve(&r, 135.0).unwrap();
    assert_close(
        "135 degrees",
        volume(&part, [0.0, 0.0, 0.0], 6.5),
        want * 135.0 / 360.0,
    );
}

#[test]
fn spiral_volume_by_pappus() {
    // A 1 x 0.5 rectangle whose centroid is 5.5 from the axis, three turns.
    let prof = rect([1.0, 0.5], 0.0)
        .unwrap()
        .translate([0.5, 0.0])
        .unwrap();
    let s = spiral_sweep(
        &prof,
        &SpiralSweep {
            height: 6.0,
            radius: 5.0,
            turns: 3.0,
            taper: 0.0,
            internal: false,
        },
    )
    .unwrap();
    let want = 0.5 * TAU * 5.5 * 3.0;
    assert_close("spiral", volume(&s, [0.0, 0.0, 0.0], 6.5), want);
}

#[test]
fn skin_of_equal_circles_is_a_cylinder() {
    let c = circle(4.0).unwrap();
    let s = skin(&[c.clone(), c], &[0.0, 10.0], &SkinOptions::default()).unwrap();
    assert_close("skin", volume(&s, [0.0, 0.0, 5.0], 5.5), PI * 16.0 * 10.0);
}

#[test]
fn circle_along_a_circle_is_a_torus() {
    let c = circle(1.5).unwrap();
    let path: Vec<DVec3> = (0..720)
        .map(|i| {
            let a = i as f64 * TAU / 720.0;
            DVec3::new(6.0 * a.cos(), 6.0 * a.sin(), 0.0)
        })
        .collect();
    let s = path_sweep(
        &c,
        &path,
        &PathSweep {
            closed: true,
            ..PathSweep::default()
        },
    )
    .unwrap();
    let want = 2.0 * PI * PI * 6.0 * 1.5 * 1.5;
    assert_close("torus", volume(&s, [0.0, 0.0, 0.0], 8.0), want);
}

/// The triangle wave: 0 at whole numbers, 1 halfway between.
fn tri(x: f64) -> f64 {
    1.0 - (2.0 * (x - x.floor()) - 1.0).abs()
}

#[test]
fn textured_cylinders_have_their_integrated_volumes() {
    use isoforge_shapes::texture::{TextureOptions, Tile, named, textured_cylinder};
    // The side stands at R = r − inset + depth·T(u, v); over whole tiles around and up the
    // volume is π h E[R²], E the mean over one tile.
    let (r, h) = (10.0, 10.0);
    let volume_of = |name: &str, depth: f64, inset: f64, mean_t: f64, mean_t2: f64| {
        let tex = TextureOptions {
            tile: Tile::Counts([24, 4]),
            depth,
            inset,
            rotate: false,
        };
        let s = textured_cylinder(r, &named(name).unwrap(), &LinearSweep::new(h), &tex).unwrap();
        let base = r - inset;
        let want = PI * h * (base * base + 2.0 * base * depth * mean_t + depth * depth * mean_t2);
        assert_close(name, volume(&s, [0.0, 0.0, h / 2.0], r + depth + 0.5), want);
    };
    // Ribs, |2 frac(u) − 1|: mean 1/2, mean square 1/3.
    volume_of("ribs", 1.0, 0.0, 0.5, 1.0 / 3.0);
    // Diamonds, min(tri(u + v), tri(u − v)): the means by a fine midpoint rule.
    let n = 1000;
    let (mut m1, mut m2) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            let t = tri(u + v).min(tri(u - v));
            m1 += t;
            m2 += t * t;
        }
    }
    let cells = (n * n) as f64;
    volume_of("diamonds", 0.6, 0.3, m1 / cells, m2 / cells);
}
