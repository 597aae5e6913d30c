//! The octree prunes the modern library's custom and many-term fields: meshing them at
//! depth 8 evaluates a small part of a dense grid's corners. (Counted by wrapping the
//! field in `isoforge_shapes::probe`, which leaves the pruning decisions unchanged.)

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;

use isoforge_mesh::{MeshSettings, check, mesh_shape};
use isoforge_script::load_file;
use isoforge_shapes::probe::probe;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/modern")
        .join(name)
}

/// Meshes a fixture through a probe; returns (points evaluated, boxes, dense corners).
fn counted(name: &str, depth: u8) -> (u64, u64, u64) {
    counted_at(&fixture(name), depth)
}

/// [`counted`] for a script anywhere.
fn counted_at(path: &Path, depth: u8) -> (u64, u64, u64) {
    let name = path.file_name().unwrap().to_string_lossy();
    let model = load_file(path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let bounds = model.bounds.expect("fixtures declare bounds");
    let (shape, counts) = probe(&model.shape);
    let mesh = mesh_shape(&shape, &MeshSettings::new(bounds, depth));
    assert!(check(&mesh).is_closed_manifold(), "{name}");
    // The lattice has 2^depth cells along the longest side.
    let cell = bounds.longest_side() / f64::from(1u32 << depth);
    let dense: u64 = bounds
        .size()
        .iter()
        .map(|s| (s / cell).round() as u64 + 1)
        .product();
    let points = counts.points.load(Ordering::Relaxed);
    let boxes = counts.boxes.load(Ordering::Relaxed);
    println!(
        "{name} at depth {depth}: {points} points and {boxes} boxes evaluated, a dense grid \
         has {dense} corners ({:.1}%)",
        100.0 * points as f64 / dense as f64
    );
    (points, boxes, dense)
}

#[test]
fn the_lava_lamp_is_pruned() {
    let (points, _, dense) = counted("lava_lamp.rhai", 8);
    // Blocks of 16³ cells near the surface are sampled whole (the mesher's design), so
    // a lamp full of balls is a good part of its region; without pruning it would be
    // all of it.
    assert!(points * 2 < dense, "{points} of {dense}");
}

#[test]
fn the_imported_mesh_is_pruned() {
    // The imported part (part.stl, 3,004 triangles) in a region 120 mm wide: the triangle
    // hierarchy's enclosures must let the octree skip the empty space around it. (In the
    // drilled fixture's own tight region nearly every 16-cell block meets the surface, so
    // there is little to skip.)
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(fixture("part.stl"), dir.path().join("part.stl")).unwrap();
    let script = dir.path().join("roomy_import.rhai");
    std::fs::write(
        &script,
        "bounds([-60, -60, -60], [60, 60, 60]);\n\
         difference(import_stl(\"part.stl\"), cylinder(3, 40))",
    )
    .unwrap();
    let (points, _, dense) = counted_at(&script, 8);
    assert!(points * 10 < dense, "{points} of {dense}");
}
