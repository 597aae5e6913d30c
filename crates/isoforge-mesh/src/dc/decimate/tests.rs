//! The chunk seams: a mesh fed to the decimator a few hundred triangles at a time comes out
//! closed and manifold, collapsed where collapsing pays and whole where it does not.

use isoforge_field::Bounds;

use super::Decimator;
use crate::dc::MeshSettings;
use crate::dc::mesh_sampler_blocks;
use crate::dc::octree::BLOCK_SHIFT;
use crate::dc::tests::{FnSampler, assert_closed_manifold};
use crate::mesh::Mesh;
use crate::sink::MeshSink;

/// A cube of side 1.2 turned by 30° about z and 20° about x: flat faces across the
/// lattice, where collapses pay.
fn turned_cube(p: [f64; 3]) -> f64 {
    let (s1, c1) = 30f64.to_radians().sin_cos();
    let (s2, c2) = 20f64.to_radians().sin_cos();
    let (x, y) = (c1 * p[0] + s1 * p[1], -s1 * p[0] + c1 * p[1]);
    let (y, z) = (c2 * y + s2 * p[2], -s2 * y + c2 * p[2]);
    x.abs().max(y.abs()).max(z.abs()) - 0.6
}

fn sphere(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() - 1.0
}

fn sampler(f: fn([f64; 3]) -> f64, settings: &MeshSettings) -> FnSampler<fn([f64; 3]) -> f64> {
    let mut s = FnSampler::new(f);
    s.nan_grad = false;
    s.bounds = settings.bounds;
    s
}

/// The uniform mesh of `f` at depth 5 over [-1.5, 1.5]³, in the mesher's order.
fn uniform(f: fn([f64; 3]) -> f64) -> (Mesh, MeshSettings) {
    let mut settings = MeshSettings::new(Bounds::new([-1.5; 3], [1.5; 3]).unwrap(), 5);
    settings.tolerance = Some(0.0);
    let mesh = mesh_sampler_blocks(&sampler(f, &settings), &settings, BLOCK_SHIFT);
    (mesh, settings)
}

/// `mesh` through a decimator of chunks of `chunk` triangles, each vertex handed over
/// just before the first triangle that uses it (as the mesher streams them).
fn decimate(
    f: fn([f64; 3]) -> f64,
    mesh: &Mesh,
    settings: &MeshSettings,
    tolerance: f64,
    chunk: usize,
) -> Mesh {
    let s = sampler(f, settings);
    let mut out = Mesh::default();
    let mut d = Decimator::new(&s, tolerance, settings.cell(), &mut out).with_chunk(chunk);
    let mut index = vec![u32::MAX; mesh.vertices.len()];
    let mut next = 0u32;
    for t in &mesh.triangles {
        let mut ids = [0u32; 3];
        for (id, &v) in ids.iter_mut().zip(t) {
            if index[v as usize] == u32::MAX {
                index[v as usize] = next;
                next += 1;
                d.vertex(mesh.vertices[v as usize]).unwrap();
            }
            *id = index[v as usize];
        }
        d.triangle(ids, t.map(|v| mesh.vertices[v as usize]))
            .unwrap();
    }
    d.finish().unwrap();
    out
}

#[test]
fn collapses_go_on_chunk_after_chunk_where_they_pay() {
    let (mesh, settings) = uniform(turned_cube);
    let tolerance = 0.1 * settings.cell();
    let whole = decimate(turned_cube, &mesh, &settings, tolerance, usize::MAX);
    let chunked = decimate(turned_cube, &mesh, &settings, tolerance, 500);
    assert_closed_manifold(&whole, "turned cube, one chunk");
    assert_closed_manifold(&chunked, "turned cube, chunks of 500");
    assert!(
        mesh.triangles.len() > 5 * 500,
        "{} triangles",
        mesh.triangles.len()
    );
    // Every chunk collapsed, not just the first (which alone would leave over four fifths);
    // the seams between such small chunks hold back more than one chunk does.
    assert!(whole.triangles.len() * 20 < mesh.triangles.len());
    assert!(
        chunked.triangles.len() * 2 < mesh.triangles.len(),
        "{} of {}",
        chunked.triangles.len(),
        mesh.triangles.len()
    );
}

#[test]
fn after_a_chunk_that_does_not_pay_the_rest_goes_on_whole() {
    // At a tolerance far below the lattice's error nothing is flat and there is no crease:
    // no collapse to try, so the first chunk is written as it came and the rest passes
    // straight on, its triangles still joined to the first chunk's open fans.
    let (mesh, settings) = uniform(sphere);
    let out = decimate(sphere, &mesh, &settings, 1e-9, 300);
    assert!(
        mesh.triangles.len() > 10 * 300,
        "{} triangles",
        mesh.triangles.len()
    );
    assert_eq!(out.triangles.len(), mesh.triangles.len());
    assert_eq!(out.vertices.len(), mesh.vertices.len());
    assert_closed_manifold(&out, "sphere, chunks of 300");
}
