//! Every fixture under fixtures/modern/ meshes closed and manifold, judged twice: by the
//! project's checker and by a program we did not write, stl_io's `validate` (every
//! directed edge met by its reverse, so closed and consistently oriented, and no triangle
//! of zero area), on the binary STL file isoforge writes. Depths 6 and 7 here; 8 and 9 in an
//! ignored test for a release run (`cargo test --release -p isoforge-script --test
//! modern_fixtures -- --ignored`).

use std::path::{Path, PathBuf};

use isoforge_mesh::io::encode;
use isoforge_mesh::{MeshFormat, MeshSettings, check, mesh_shape};
use isoforge_script::load_file;

fn fixtures() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/modern");
    let mut all: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    all.sort();
    all
}

/// Meshes `path` at `depth`; the volume, after both checkers have passed the mesh.
fn closed_volume(path: &Path, depth: u8) -> f64 {
    let name = path.file_name().unwrap().to_string_lossy();
    let model = load_file(path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let bounds = model.bounds.expect("every fixture declares its bounds");
    let mesh = mesh_shape(&model.shape, &MeshSettings::new(bounds, depth));
    let report = check(&mesh);
    assert!(
        report.is_closed_manifold(),
        "{name} at depth {depth}: {}",
        report.problems().join("; ")
    );
    let mut stl = Vec::new();
    encode(&mesh, MeshFormat::Stl, &mut stl).unwrap();
    let indexed = stl_io::read_stl(&mut std::io::Cursor::new(stl)).unwrap();
    if let Err(e) = indexed.validate() {
        panic!("{name} at depth {depth}: stl_io says {e}");
    }
    assert_eq!(indexed.faces.len(), report.triangles, "{name}");
    println!(
        "{name} depth {depth}: {} triangles, volume {:.3}",
        report.triangles, report.volume
    );
    report.volume
}

/// Both depths' volumes agree within `tolerance` (relative): a fixture that meshed closed
/// but wrong (a part missing at one depth) would not.
fn closed_at(depths: [u8; 2], tolerance: f64) {
    let all = fixtures();
    assert!(
        all.len() >= 7,
        "fixtures/modern/ holds {} models",
        all.len()
    );
    for path in all {
        let [a, b] = depths.map(|d| closed_volume(&path, d));
        assert!(
            ((a - b) / b).abs() < tolerance,
            "{}: volume {a} at depth {} vs {b} at {}",
            path.display(),
            depths[0],
            depths[1]
        );
    }
}

#[test]
fn modern_fixtures_mesh_closed_at_depths_6_and_7() {
    // Measured: the largest change from depth 6 to 7 is the heart shell's 1.3%.
    closed_at([6, 7], 0.03);
}

#[test]
#[ignore = "minutes in a debug build: run with --release"]
fn modern_fixtures_mesh_closed_at_depths_8_and_9() {
    closed_at([8, 9], 0.01);
}

#[test]
fn the_independent_judge_refuses_open_and_flipped_meshes() {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/meshes");
    for bad in ["open_box.stl", "flipped_face.stl"] {
        let bytes = std::fs::read(meshes.join(bad)).unwrap();
        let indexed = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).unwrap();
        assert!(indexed.validate().is_err(), "stl_io passed {bad}");
    }
    let bytes = std::fs::read(meshes.join("cube_binary.stl")).unwrap();
    let indexed = stl_io::read_stl(&mut std::io::Cursor::new(bytes)).unwrap();
    indexed.validate().unwrap();
}
