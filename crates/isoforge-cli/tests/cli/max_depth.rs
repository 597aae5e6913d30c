//! `isoforge mesh --max-depth`: a mesh that misses its tolerance, measured by the field as it
//! is written, is made again one level finer with the same tolerance in millimetres, and the
//! one written holds it by `check --against` and is one ADMesh finds nothing to fix in.

use std::path::Path;

use crate::{fixtures, isoforge};

pub(crate) fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// `isoforge mesh MODEL -o OUT --json ARGS...`: its report and stderr, asserting exit 0.
fn mesh_json(model: &Path, out: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let mut args = vec!["mesh", s(model), "-o", s(out), "--json"];
    args.extend_from_slice(extra);
    let run = isoforge(&args);
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(run.status.success(), "{extra:?}: {stderr}");
    let j = serde_json::from_slice(&run.stdout).expect("JSON");
    (j, stderr)
}

/// `check OUT --against MODEL --tolerance T --json`: the report and the exit status.
pub(crate) fn checked(
    out: &Path,
    model: &Path,
    tolerance: f64,
) -> (serde_json::Value, Option<i32>) {
    let t = tolerance.to_string();
    let run = isoforge(&[
        "check",
        s(out),
        "--against",
        s(model),
        "--tolerance",
        &t,
        "--json",
    ]);
    (
        serde_json::from_slice(&run.stdout).expect("JSON"),
        run.status.code(),
    )
}

#[test]
fn a_model_that_misses_its_tolerance_is_meshed_finer_until_it_holds() {
    // curve_cyl at depth 7: where its two cylinders meet the cap, a wedge thinner than
    // the lattice is cut off, 2.2 tolerances off; at depth 10 the same millimetres hold.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/curve_cyl.rhai");
    let plain = dir.path().join("plain.stl");
    let (first, _) = mesh_json(&model, &plain, &["--depth", "7"]);
    let tolerance = first["tolerance"].as_f64().expect("tolerance");
    // The fault first: at depth 7 the mesh misses, by `check`'s measure.
    let (j, status) = checked(&plain, &model, tolerance);
    assert_eq!(
        (j["tolerance_held"].as_bool(), status),
        (Some(false), Some(1)),
        "{j}"
    );

    let out = dir.path().join("held.stl");
    let (made, _) = mesh_json(&model, &out, &["--depth", "7", "--max-depth", "10"]);
    assert_eq!(made["tolerance"].as_f64(), Some(tolerance), "{made}");
    let depths = made["depths"].as_array().expect("depths");
    let tried: Vec<u64> = depths
        .iter()
        .map(|d| d["depth"].as_u64().unwrap())
        .collect();
    assert_eq!(tried, [7, 8, 9, 10], "{made}");
    // The first mesh measured is the plain run's, and it missed.
    assert_eq!(depths[0]["triangles"], first["triangles"], "{made}");
    assert!(
        depths[0]["max_deviation"].as_f64().unwrap() > tolerance,
        "{made}"
    );
    assert_eq!(
        (made["depth"].as_u64(), made["tolerance_held"].as_bool()),
        (Some(10), Some(true))
    );
    let measured = made["max_deviation"].as_f64().expect("max_deviation");
    assert!(measured <= tolerance, "{made}");

    // Judged apart: `check` reads the file back and finds the tolerance held, and by the
    // same distance; ADMesh finds one part and nothing to fix.
    let (j, status) = checked(&out, &model, tolerance);
    assert_eq!(
        (j["tolerance_held"].as_bool(), status),
        (Some(true), Some(0)),
        "{j}"
    );
    assert_eq!(j["triangles"], made["triangles"], "{j}");
    let by_check = j["max_deviation"].as_f64().expect("max_deviation");
    assert!((by_check - measured).abs() <= 1e-9, "{by_check} {measured}");
    crate::sweeps::admesh_finds_nothing_to_fix_in_parts(&out, "curve_cyl", 1);
}

#[test]
fn a_mesh_that_will_be_dropped_stops_at_its_first_miss() {
    // sinus_bugs at depth 6: its bugs' legs are thinner than the lattice, and the first
    // chunk of triangles measured already misses.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/sinus_bugs.rhai");
    let plain = dir.path().join("plain.stl");
    let (at6, _) = mesh_json(&model, &plain, &["--depth", "6"]);
    let tolerance = at6["tolerance"].as_f64().expect("tolerance");
    // The fault first: depth 6's whole mesh misses, by `check`.
    let (j, _) = checked(&plain, &model, tolerance);
    assert_eq!(j["tolerance_held"].as_bool(), Some(false), "{j}");

    let out = dir.path().join("out.stl");
    let (made, stderr) = mesh_json(&model, &out, &["--depth", "6", "--max-depth", "7"]);
    let depths = made["depths"].as_array().expect("depths");
    assert_eq!(depths.len(), 2, "{made}");
    let first = &depths[0];
    assert_eq!(first["stopped"].as_bool(), Some(true), "{made}");
    assert!(first["max_deviation"].as_f64() > Some(tolerance), "{made}");
    assert!(
        first["triangles"].as_u64() <= at6["triangles"].as_u64(),
        "{made}"
    );
    assert!(stderr.contains("depth 6: the mesh is"), "{stderr}");
    assert!(stderr.contains("stopped after"), "{stderr}");
    // The mesh kept is depth 7's, the same bytes as a plain run with that tolerance, and
    // nothing of the stopped one is left beside it.
    assert_eq!(made["depth"].as_u64(), Some(7), "{made}");
    let again = dir.path().join("again.stl");
    let t = tolerance.to_string();
    mesh_json(&model, &again, &["--depth", "7", "--tolerance", &t]);
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["again.stl", "out.stl", "plain.stl"]);
}

#[test]
fn a_model_that_holds_at_once_is_meshed_once_and_the_same() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("bench/sphere.rhai");
    let (plain, measured) = (dir.path().join("a.stl"), dir.path().join("b.stl"));
    mesh_json(&model, &plain, &["--depth", "6"]);
    let (made, stderr) = mesh_json(&model, &measured, &["--depth", "6", "--max-depth", "9"]);
    assert_eq!(made["depths"].as_array().map(Vec::len), Some(1), "{made}");
    assert_eq!(made["tolerance_held"], true, "{made}");
    assert!(stderr.is_empty(), "{stderr}");
    // Measuring on the way changes nothing written.
    assert_eq!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&measured).unwrap()
    );
}

#[test]
fn the_deepest_allowed_mesh_is_kept_with_a_note_when_it_still_misses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/curve_cyl.rhai");
    let out = dir.path().join("out.stl");
    let run = isoforge(&[
        "mesh",
        s(&model),
        "-o",
        s(&out),
        "--depth",
        "7",
        "--max-depth",
        "8",
    ]);
    assert_eq!(run.status.code(), Some(0));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("depth 7: the mesh is up to"), "{stderr}");
    assert!(stderr.contains("meshing again at depth 8"), "{stderr}");
    assert!(stderr.contains("misses the tolerance"), "{stderr}");
    assert!(stderr.contains("even at depth 8"), "{stderr}");
    // What was written is the depth-8 mesh, and `check` agrees it misses.
    let (j, status) = checked(&out, &model, 0.009375);
    assert_eq!(
        (j["tolerance_held"].as_bool(), status),
        (Some(false), Some(1)),
        "{j}"
    );
    let (at8, _) = mesh_json(
        &model,
        &dir.path().join("at8.stl"),
        &["--depth", "8", "--tolerance", "0.009375"],
    );
    assert_eq!(j["triangles"], at8["triangles"], "{j}");
    // Nothing else is left in the folder: the dropped depth-7 mesh's file is gone.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

#[test]
fn a_pipe_is_refused_before_any_work() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("pipe.stl");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    let model = fixtures().join("bench/sphere.rhai");
    let run = isoforge(&["mesh", s(&model), "-o", s(&fifo), "--max-depth", "9"]);
    assert_eq!(run.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("not a regular file"), "{stderr}");
}

#[test]
fn each_step_of_a_parameter_range_finds_its_own_depth() {
    // spiky_ball's spikes sharpen with their number: at depth 6 two spikes need depth 7,
    // five need depth 8, for the same tolerance.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("modern/spiky_ball.rhai");
    let out = dir.path().join("ball.stl");
    let (j, _) = mesh_json(
        &model,
        &out,
        &[
            "--param",
            "spikes=2..5:2",
            "--depth",
            "6",
            "--max-depth",
            "8",
        ],
    );
    let steps = j["steps"].as_array().expect("steps");
    let found: Vec<(u64, bool)> = steps
        .iter()
        .map(|s| {
            (
                s["depth"].as_u64().unwrap(),
                s["tolerance_held"].as_bool().unwrap(),
            )
        })
        .collect();
    assert_eq!(found, [(7, true), (8, true)], "{j}");
    // The step that went deepest holds by `check` too, at depth 6's tolerance.
    let tolerance = 28.0 / 64.0 * 0.1;
    let (c, status) = checked(&dir.path().join("ball-001.stl"), &model, tolerance);
    assert_eq!(
        (c["tolerance_held"].as_bool(), status),
        (Some(true), Some(0)),
        "{c}"
    );
}
