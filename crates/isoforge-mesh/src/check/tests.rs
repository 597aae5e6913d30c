//! The checker against meshes whose answers are known by hand, and against stl_io's
//! watertightness test.

use proptest::prelude::*;

use super::*;
use crate::io::Welder;
use crate::samples::{cube, cuboid, merge, tetrahedron, uv_sphere};

/// Joins corners at equal positions, as an STL reader would.
fn weld(m: &Mesh) -> Mesh {
    let mut w = Welder::with_capacity(m.triangles.len());
    for &t in &m.triangles {
        w.triangle(t.map(|i| m.vertices[i as usize])).unwrap();
    }
    w.finish()
}

/// stl_io's verdict: every directed edge has its opposite and no face is tiny.
fn stl_io_valid(m: &Mesh) -> bool {
    let indexed = stl_io::IndexedMesh {
        vertices: m.vertices.iter().map(|&v| stl_io::Vertex::new(v)).collect(),
        faces: m
            .triangles
            .iter()
            .map(|&t| stl_io::IndexedTriangle {
                normal: stl_io::Normal::new(m.triangle_normal(t)),
                vertices: t.map(|i| i as usize),
            })
            .collect(),
    };
    indexed.validate().is_ok()
}

#[test]
fn cube_is_closed_with_exact_volume_and_area() {
    let r = check(&cube(10.0));
    assert!(r.is_closed_manifold(), "{:?}", r.problems());
    assert_eq!((r.triangles, r.vertices, r.components), (12, 8, 1));
    assert_eq!(r.volume, 1000.0);
    assert_eq!(r.area, 600.0);
    assert_eq!(r.bounds, Some([[0.0; 3], [10.0; 3]]));
    assert!(r.problems().is_empty());
    assert!(stl_io_valid(&cube(10.0)));
}

#[test]
fn tetrahedron_volume() {
    let r = check(&tetrahedron());
    assert!(r.is_closed_manifold());
    assert!((r.volume - 1.0 / 6.0).abs() < 1e-12);
    assert!((r.area - (1.5 + 3f64.sqrt() / 2.0)).abs() < 1e-9);
}

#[test]
fn two_cubes_sharing_an_edge_are_non_manifold() {
    let m = weld(&merge(
        cuboid([0.0; 3], [1.0; 3]),
        &cuboid([1.0, 1.0, 0.0], [2.0, 2.0, 1.0]),
    ));
    assert_eq!(m.vertices.len(), 14);
    let r = check(&m);
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.non_manifold_vertices, 2);
    assert_eq!(r.boundary_edges, 0);
    assert_eq!(r.components, 1);
    assert!(r.watertight && !r.manifold);
    assert_eq!(r.volume, 2.0);
}

#[test]
fn cubes_touching_at_a_corner_pinch_a_vertex() {
    let m = weld(&merge(
        cuboid([0.0; 3], [1.0; 3]),
        &cuboid([1.0; 3], [2.0; 3]),
    ));
    assert_eq!(m.vertices.len(), 15);
    let r = check(&m);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.components, 2);
    assert!(r.watertight && !r.manifold);
}

#[test]
fn open_box_has_a_four_edge_hole() {
    let mut m = cube(1.0);
    m.triangles.drain(2..4); // the z = max face
    let r = check(&m);
    assert_eq!(r.boundary_edges, 4);
    assert!(!r.watertight && r.manifold);
    assert_eq!(r.non_manifold_vertices, 0);
    assert!(r.problems()[0].contains("boundary"));
    assert!(!stl_io_valid(&m));
}

#[test]
fn flipped_triangle_is_inconsistent() {
    let mut m = cube(1.0);
    m.triangles[5].swap(1, 2);
    let r = check(&m);
    assert_eq!(r.inconsistent_edges, 3);
    assert!(r.watertight && !r.manifold);
    assert!(!stl_io_valid(&m));
}

#[test]
fn disjoint_cubes_are_two_components() {
    let m = merge(cube(1.0), &cuboid([3.0; 3], [5.0; 3]));
    let r = check(&m);
    assert!(r.is_closed_manifold());
    assert_eq!(r.components, 2);
    assert_eq!(r.volume, 9.0);
    assert!(stl_io_valid(&m));
}

#[test]
fn inside_out_cube_is_negative_and_warned() {
    let mut m = cube(2.0);
    for t in &mut m.triangles {
        t.swap(0, 1);
    }
    let r = check(&m);
    assert!(r.is_closed_manifold());
    assert_eq!(r.volume, -8.0);
    assert!(r.problems().iter().any(|p| p.contains("inward")));
}

#[test]
fn degenerate_and_bad_triangles_are_counted() {
    let mut m = cube(1.0);
    m.triangles.push([0, 0, 1]); // collapsed
    m.vertices.push([0.5, 0.0, 0.0]);
    m.triangles.push([0, 1, 8]); // zero area, distinct corners
    m.triangles.push([0, 1, 99]); // bad index
    let r = check(&m);
    assert_eq!(r.collapsed_triangles, 1);
    assert_eq!(r.degenerate_triangles, 2);
    assert_eq!(r.bad_indices, 1);
    assert!(!r.manifold && !r.watertight);
}

#[test]
fn empty_mesh_is_not_closed() {
    let r = check(&Mesh::default());
    assert!(!r.is_closed_manifold());
    assert_eq!(r.bounds, None);
}

#[test]
fn unused_vertices_are_reported_but_harmless() {
    let mut m = cube(1.0);
    m.vertices.push([9.0; 3]);
    let r = check(&m);
    assert_eq!(r.unused_vertices, 1);
    assert!(r.is_closed_manifold());
}

#[test]
fn sphere_volume_converges() {
    let m = uv_sphere(1.0, 200, 100);
    let r = check(&m);
    assert!(r.is_closed_manifold(), "{:?}", r.problems());
    assert_eq!(r.triangles, 2 * 200 * 99);
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    assert!(r.volume < exact && r.volume > exact * 0.99, "{}", r.volume);
    assert!(stl_io_valid(&m));
}

/// The same mesh gives the same volume and area to the last bit on one thread or many (a
/// CI run once saw them part in the last digit, under a reduce that split as threads stole).
#[test]
fn the_sums_do_not_depend_on_the_threads() {
    let m = uv_sphere(1.0, 300, 150);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| check(&m))
    };
    let one = on(1);
    for threads in [2, 3, 8] {
        for _ in 0..4 {
            let many = on(threads);
            assert_eq!(
                many.volume.to_bits(),
                one.volume.to_bits(),
                "{threads} threads"
            );
            assert_eq!(many.area.to_bits(), one.area.to_bits(), "{threads} threads");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Relabelling vertices, reordering triangles and rotating their corners changes
    /// nothing the checker reports.
    #[test]
    fn report_is_invariant_under_relabelling(
        slices in 3u32..12, stacks in 2u32..8, seed in any::<u64>(), flip in any::<bool>()
    ) {
        let mut m = uv_sphere(1.0, slices, stacks);
        if flip {
            m.triangles.swap_remove(0);
        }
        let before = check(&m);
        let n = m.vertices.len();
        // A permutation from a simple LCG.
        let mut perm: Vec<u32> = (0..n as u32).collect();
        let mut s = seed | 1;
        for i in (1..n).rev() {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            perm.swap(i, (s >> 33) as usize % (i + 1));
        }
        let mut vertices = vec![[0f32; 3]; n];
        for (old, &new) in perm.iter().enumerate() {
            vertices[new as usize] = m.vertices[old];
        }
        let mut triangles: Vec<[u32; 3]> = m
            .triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let t = t.map(|v| perm[v as usize]);
                match i % 3 { 0 => t, 1 => [t[1], t[2], t[0]], _ => [t[2], t[0], t[1]] }
            })
            .collect();
        triangles.reverse();
        let after = check(&Mesh { vertices, triangles });
        prop_assert_eq!(before.components, after.components);
        prop_assert_eq!(before.boundary_edges, after.boundary_edges);
        prop_assert_eq!(before.non_manifold_vertices, after.non_manifold_vertices);
        prop_assert_eq!(before.is_closed_manifold(), after.is_closed_manifold());
        prop_assert!((before.volume - after.volume).abs() < 1e-9);
        prop_assert!((before.area - after.area).abs() < 1e-9);
        prop_assert_eq!(before.is_closed_manifold(), !flip);
        if flip {
            prop_assert_eq!(before.boundary_edges, 3);
        }
    }

    /// Removing any one triangle of a closed mesh opens a three-edge hole.
    #[test]
    fn removing_a_triangle_opens_three_edges(slices in 3u32..10, stacks in 2u32..6, pick in any::<usize>()) {
        let mut m = uv_sphere(2.0, slices, stacks);
        let i = pick % m.triangles.len();
        m.triangles.remove(i);
        let r = check(&m);
        prop_assert_eq!(r.boundary_edges, 3);
        prop_assert!(!r.watertight);
        prop_assert!(r.manifold);
    }
}
