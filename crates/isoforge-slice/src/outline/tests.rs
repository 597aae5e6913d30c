//! Field outlines against exact sections, and field against mesh outlines. (Unit tests:
//! outlines are an internal stage; the shapes with known sections are shared with the
//! integration tests.)

#[path = "../../tests/common/mod.rs"]
mod common;

use common::{Known, cube, sphere, torus};
use isoforge_mesh::{MeshSettings, mesh_shape};

use super::{FieldSlicer, MeshSlicer};
use crate::geom::{contours_area, distance_to_contours, signed_area};

fn field(k: &Known) -> FieldSlicer {
    FieldSlicer::new(&k.shape, k.bounds, 0.05, 0.005)
}

#[test]
fn sphere_sections_have_the_exact_area_and_lie_on_the_surface() {
    let k = sphere(10.0);
    let f = field(&k);
    for z in [-9.5, -6.0, 0.0, 3.3, 8.9] {
        let o = f.outline(z, (z - 0.1, z + 0.1));
        assert_eq!(o.len(), 1, "z {z}");
        assert!(
            signed_area(&o[0]) > 0.0,
            "outer contour must be counter-clockwise"
        );
        let exact = (k.area)(z);
        // Douglas-Peucker cuts chords at most `tolerance` inside the curve: the area may
        // fall short by at most perimeter x tolerance.
        let perimeter = 2.0 * (std::f64::consts::PI * exact).sqrt() * std::f64::consts::PI.sqrt();
        let err = (contours_area(&o) - exact).abs();
        assert!(
            err <= perimeter * 0.005,
            "z {z}: {} vs {exact}",
            contours_area(&o)
        );
        for p in &o[0] {
            // Crossings are refined on the field: on the circle to far better than a cell.
            assert!((k.section)(p[0], p[1], z).abs() < 0.006, "{p:?}");
        }
    }
}

#[test]
fn torus_section_has_a_clockwise_hole() {
    let k = torus(15.0, 5.0);
    let f = field(&k);
    let o = f.outline(0.0, (-0.1, 0.1));
    assert_eq!(o.len(), 2);
    let mut areas: Vec<f64> = o.iter().map(|c| signed_area(c)).collect();
    areas.sort_by(f64::total_cmp);
    assert!(areas[0] < 0.0 && areas[1] > 0.0, "{areas:?}");
    assert!((contours_area(&o) / (k.area)(0.0) - 1.0).abs() < 1e-3);
}

#[test]
fn cube_keeps_its_corners_and_empty_planes_are_empty() {
    let k = cube(20.0);
    let f = field(&k);
    let o = f.outline(2.0, (1.9, 2.1));
    assert_eq!(o.len(), 1);
    assert!(
        (contours_area(&o) - 400.0).abs() < 0.5,
        "{}",
        contours_area(&o)
    );
    assert!(f.outline(10.5, (10.4, 10.6)).is_empty());
    let (z0, z1) = f.z_extent(0.05).unwrap();
    assert!(
        (z0 + 10.0).abs() < 1e-4 && (z1 - 10.0).abs() < 1e-4,
        "{z0} {z1}"
    );
}

#[test]
fn a_model_cut_by_its_bounds_is_capped() {
    let k = sphere(10.0);
    let b = isoforge_field::Bounds::new([-11.0, -11.0, -11.0], [5.0, 11.0, 11.0]).unwrap();
    let f = FieldSlicer::new(&k.shape, b, 0.05, 0.005);
    let o = f.outline(0.0, (-0.1, 0.1));
    assert_eq!(o.len(), 1);
    // The disc of radius 10 minus the part beyond x = 5.
    let seg = 100.0 * (0.5f64).acos() - 5.0 * (75.0f64).sqrt();
    let want = std::f64::consts::PI * 100.0 - seg;
    assert!(
        (contours_area(&o) / want - 1.0).abs() < 1e-3,
        "{} vs {want}",
        contours_area(&o)
    );
}

/// The field path and the mesh path give the same polygons within the mesh's cell size.
#[test]
fn field_and_mesh_outlines_agree() {
    for k in [sphere(10.0), torus(15.0, 5.0)] {
        let depth = 7;
        let mesh = mesh_shape(&k.shape, &MeshSettings::new(k.bounds, depth));
        let cell = k.bounds.longest_side() / f64::from(1u32 << depth);
        let f = field(&k);
        let m = MeshSlicer::new(&mesh, 0.005).unwrap();
        for z in [-3.1, 0.05, 2.7] {
            let a = f.outline(z, (z - 0.1, z + 0.1));
            let b = m.outline(z);
            assert_eq!(a.len(), b.len(), "z {z}");
            for p in a.iter().flatten() {
                assert!(
                    distance_to_contours(*p, &b) < cell,
                    "field point {p:?} far from the mesh outline"
                );
            }
            for p in b.iter().flatten() {
                assert!(
                    distance_to_contours(*p, &a) < cell,
                    "mesh point {p:?} far from the field outline"
                );
            }
            let (aa, ab) = (contours_area(&a), contours_area(&b));
            assert!((aa / ab - 1.0).abs() < 0.01, "z {z}: {aa} vs {ab}");
        }
    }
}
