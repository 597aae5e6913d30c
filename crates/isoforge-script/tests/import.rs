//! `import_stl`: a meshed sphere imported and united with a cube matches the direct
//! model within a cell; the fence around the script's folder holds; bad files are errors
//! that name the path.

use std::f64::consts::PI;
use std::path::Path;

use isoforge_mesh::io::write_mesh;
use isoforge_mesh::{MeshFormat, MeshSettings, check, mesh_shape};
use isoforge_script::{load_file, load_script};

fn volume_of(model: &isoforge_script::Model, depth: u8) -> (bool, f64, f64) {
    let bounds = model.bounds.expect("bounds");
    let mesh = mesh_shape(&model.shape, &MeshSettings::new(bounds, depth));
    let r = check(&mesh);
    (r.is_closed_manifold(), r.volume, r.area)
}

#[test]
fn an_imported_sphere_united_with_a_cube_matches_the_direct_model() {
    let dir = tempfile::tempdir().expect("temp dir");
    // The sphere, meshed at depth 7 over [-6, 6]³ and written as binary STL.
    let ball = load_script(
        Path::new("ball.rhai"),
        "bounds([-6,-6,-6],[6,6,6]); sphere(5)",
        &[],
    )
    .expect("loads");
    let mesh = mesh_shape(&ball.shape, &MeshSettings::new(ball.bounds.expect("b"), 7));
    write_mesh(&mesh, &dir.path().join("ball.stl"), MeshFormat::Stl).expect("writes");
    let body = "union(PART, box([6, 6, 6]).move([5, 0, 0]))";
    let script = dir.path().join("drilled.rhai");
    std::fs::write(
        &script,
        format!(
            "bounds([-6, -6, -6], [9, 6, 6]);\n{}",
            body.replace("PART", "import_stl(\"ball.stl\")")
        ),
    )
    .expect("writes");
    let imported = load_file(&script, &[]).expect("imports");
    let direct = load_script(
        Path::new("direct.rhai"),
        &format!(
            "bounds([-6, -6, -6], [9, 6, 6]);\n{}",
            body.replace("PART", "sphere(5)")
        ),
        &[],
    )
    .expect("loads");
    let (closed_i, v_i, area) = volume_of(&imported, 8);
    let (closed_d, v_d, _) = volume_of(&direct, 8);
    assert!(closed_i && closed_d);
    // The STL is within one depth-7 cell of the sphere, so the volumes differ by less
    // than the surface area times that cell.
    let cell = 12.0 / 128.0;
    println!(
        "imported {v_i:.3}, direct {v_d:.3}, difference {:.3} (bound {:.3})",
        v_i - v_d,
        area * cell
    );
    assert!((v_i - v_d).abs() < area * cell, "{v_i} vs {v_d}");
    let sphere_part = 4.0 / 3.0 * PI * 125.0;
    assert!(v_d > sphere_part, "the cube adds volume");
    // Imported twice (by two spellings of the path): one shared node, so the union of
    // the two is that node alone (min(a, a) = a): x, y, z and the mesh.
    std::fs::write(
        &script,
        "bounds([-6, -6, -6], [9, 6, 6]);\nlet a = import_stl(\"ball.stl\");\nlet b = import_stl(\"./ball.stl\");\nunion(a, b)",
    )
    .expect("writes");
    let twice = load_file(&script, &[]).expect("imports");
    let mut ctx = isoforge_field::Context::new();
    ctx.import(&twice.shape);
    assert_eq!(ctx.len(), 4, "the mesh was imported once");
}

fn import_error(dir: &Path, call: &str) -> String {
    let script = dir.join("probe.rhai");
    std::fs::write(&script, format!("bounds([-1,-1,-1],[1,1,1]);\n{call}")).expect("writes");
    match load_file(&script, &[]) {
        Ok(_) => panic!("{call} was allowed"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn only_files_in_the_scripts_folder_can_be_read() {
    let outer = tempfile::tempdir().expect("temp dir");
    let inner = outer.path().join("models");
    std::fs::create_dir(&inner).expect("mkdir");
    std::fs::write(outer.path().join("secret.stl"), b"solid x\nendsolid x\n").expect("writes");
    for (call, words) in [
        (
            "import_stl(\"/etc/passwd\")",
            vec!["/etc/passwd", "absolute"],
        ),
        (
            "import_stl(\"../secret.stl\")",
            vec!["../secret.stl", "outside the script's folder"],
        ),
        (
            "import_stl(\"missing.stl\")",
            vec!["missing.stl", "cannot open"],
        ),
        ("import_stl(\".\")", vec!["not a regular file"]),
        ("import_stl(42)", vec!["must be a string"]),
    ] {
        let msg = import_error(&inner, call);
        for w in words {
            assert!(msg.contains(w), "{call}: {w:?} not in {msg}");
        }
        assert!(
            msg.contains("probe.rhai:2"),
            "{call}: the error has the script's line: {msg}"
        );
    }
    // A link inside the folder pointing out of it is refused too.
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(outer.path().join("secret.stl"), inner.join("link.stl"))
            .expect("symlink");
        let msg = import_error(&inner, "import_stl(\"link.stl\")");
        assert!(msg.contains("outside the script's folder"), "{msg}");
    }
}

#[test]
fn a_bad_mesh_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("junk.stl"), b"this is not a mesh at all").expect("writes");
    let msg = import_error(dir.path(), "import_stl(\"junk.stl\")");
    assert!(msg.contains("junk.stl"), "{msg}");
}
