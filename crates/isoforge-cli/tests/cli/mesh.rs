//! End-to-end tests of `isoforge mesh`: every fixture meshes into a closed manifold file that
//! reads back and passes the checker; formats, defaults, usage errors and failed work.

use std::path::{Path, PathBuf};

use crate::{fixtures, isoforge};
use isoforge_mesh::{check, read_mesh};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Meshes a model to `out` with extra arguments, expects success, checks the file and the
/// JSON figures; returns the JSON.
pub(crate) fn mesh_ok(model: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["mesh", s(model), "-o", s(out), "--json"];
    args.extend_from_slice(extra);
    let run = isoforge(&args);
    assert!(
        run.status.success(),
        "{}: {}",
        model.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&run.stdout).expect("--json prints one JSON object");
    assert_eq!(json["watertight"], true, "{}", model.display());
    assert_eq!(json["manifold"], true, "{}", model.display());
    assert!(json["volume"].as_f64().unwrap_or(-1.0) > 0.0);
    assert!(json["seconds"].as_f64().is_some());
    assert!(json["bounds"].is_array());
    let mesh = read_mesh(out).expect("the output reads back");
    let report = check(&mesh);
    assert!(
        report.is_closed_manifold(),
        "{}: {:?}",
        out.display(),
        report.problems()
    );
    assert_eq!(
        json["triangles"].as_u64(),
        Some(mesh.triangles.len() as u64)
    );
    json
}

/// `isoforge check MESH --against MODEL --json`: expects success; returns the JSON (the
/// largest and mean distance from the model's surface, by its field).
fn check_against(mesh: &Path, model: &Path) -> serde_json::Value {
    let run = isoforge(&["check", s(mesh), "--against", s(model), "--json"]);
    assert!(
        run.status.success(),
        "{}: {}",
        model.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).expect("--json prints one JSON object")
}

/// A gyroid sheet 0.22 mm thick in a ball of 3, written into `dir`: a third of a cell at
/// depth 5 over its 20 mm region, resolved at depth 7.
fn thin_gyroid(dir: &Path) -> PathBuf {
    let model = dir.join("thin_gyroid.rhai");
    std::fs::write(
        &model,
        "let t = param(\"t\", 0.22, 0.1, 6.0);\n\
         bounds([-10, -10, -10], [10, 10, 10]);\n\
         intersection(gyroid(8, t), sphere(3))\n",
    )
    .expect("write the model");
    model
}

pub(crate) fn models(dir: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(fixtures().join(dir))
        .expect("fixtures folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_classic_and_bench_fixture_meshes_closed() {
    let dir = tempfile::tempdir().expect("tempdir");
    for model in models("classic").into_iter().chain(models("bench")) {
        let out = dir.path().join("out.stl");
        mesh_ok(&model, &out, &["--depth", "5"]);
    }
}

#[test]
fn sphere_volume_and_resolution() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sphere.stl");
    let sphere = fixtures().join("bench/sphere.rhai");
    let json = mesh_ok(&sphere, &out, &["--depth", "6"]);
    let vol = json["volume"].as_f64().unwrap_or(0.0);
    assert!((vol - 4.18879).abs() < 0.02 * 4.18879, "{vol}");
    // --resolution 0.05 over a 3 mm region: depth 6 (3/64 = 0.047), the same mesh.
    let json2 = mesh_ok(&sphere, &out, &["--resolution", "0.05", "--threads", "1"]);
    assert_eq!(json["triangles"], json2["triangles"]);
}

#[test]
fn formats_by_flag_and_by_extension() {
    let dir = tempfile::tempdir().expect("tempdir");
    let heart = fixtures().join("classic/heart.rhai");
    for (name, flag) in [
        ("a.obj", None),
        ("b.ply", None),
        ("c.3mf", None),
        ("d.stl", Some("stl-ascii")),
        ("e.mesh", Some("obj")),
    ] {
        let out = dir.path().join(name);
        let mut extra = vec!["--depth", "4"];
        if let Some(f) = flag {
            extra.extend(["--format", f]);
        }
        mesh_ok(&heart, &out, &extra);
        if flag == Some("stl-ascii") {
            let text = std::fs::read(&out).expect("file");
            assert!(text.starts_with(b"solid"), "ASCII STL");
        }
    }
}

#[test]
fn default_output_is_beside_the_model() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = dir.path().join("ball.rhai");
    std::fs::copy(fixtures().join("bench/sphere.rhai"), &model).expect("copy");
    let run = isoforge(&["mesh", s(&model), "--depth", "4", "--quiet"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(run.stdout.is_empty(), "--quiet prints nothing");
    let mesh = read_mesh(&dir.path().join("ball.stl")).expect("ball.stl written");
    assert!(check(&mesh).is_closed_manifold());
}

#[test]
fn vm_model_with_bounds() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("colonnade.stl");
    let model = fixtures().join("vm/colonnade.vm");
    mesh_ok(&model, &out, &["--depth", "6", "--bounds=-1,-1,-1,1,1,1"]);
}

#[test]
fn usage_errors_exit_2_and_write_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.stl");
    let sphere = fixtures().join("bench/sphere.rhai");
    for extra in [
        vec!["--depth", "40"],
        vec!["--format", "dwg"],
        vec!["--resolution", "-1"],
        vec!["--resolution", "0"],
        vec!["--resolution", "1e-12"],
        vec!["--depth", "4", "--resolution", "0.1"],
        vec!["--threads", "0"],
        vec!["--threads", "100000"],
        vec!["--depth", "many"],
        vec!["--depth", "6", "--max-depth", "5"],
        vec!["--max-depth", "17"],
        vec!["--max-depth", "9", "--tolerance", "0"],
    ] {
        let mut args = vec!["mesh", s(&sphere), "-o", s(&out)];
        args.extend_from_slice(&extra);
        let run = isoforge(&args);
        assert_eq!(run.status.code(), Some(2), "{extra:?}");
        assert!(!run.stderr.is_empty(), "{extra:?} says why");
        assert!(!out.exists(), "{extra:?} wrote a file");
    }
}

#[test]
fn a_mesh_too_large_for_the_machine_is_refused_at_once_with_the_estimate() {
    // gyroid_sphere at depth 16: about 8e4 blocks at depth 11, times 4^5: some 170 GB by
    // the estimate, more than any machine these tests run on has available.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.stl");
    let model = fixtures().join("bench/gyroid_sphere.rhai");
    let run = isoforge(&["mesh", s(&model), "-o", s(&out), "--depth", "16"]);
    assert_eq!(run.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&run.stderr);
    for word in [
        "depth 16",
        "GiB of memory",
        "available",
        "--no-memory-check",
    ] {
        assert!(stderr.contains(word), "{word:?} missing: {stderr}");
    }
    assert!(!out.exists());
    // The estimate is reported, and scales by 4 a level past the probe depth.
    let json = |depth: &str| -> serde_json::Value {
        let run = isoforge(&["mesh", s(&model), "-o", s(&out), "--depth", depth, "--json"]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        serde_json::from_slice(&run.stdout).expect("json")
    };
    let five = json("5");
    assert!(five["estimate"]["blocks"].as_f64().expect("blocks") >= 1.0);
    assert!(five["estimate"]["bytes"].as_f64().expect("bytes") > 0.0);
}

#[test]
fn failed_work_exits_1_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.stl");
    let bad = fixtures().join("bad");
    let mut cases: Vec<PathBuf> = std::fs::read_dir(&bad)
        .expect("bad fixtures")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    cases.sort();
    assert!(!cases.is_empty());
    for model in cases {
        let run = isoforge(&["mesh", s(&model), "-o", s(&out), "--depth", "4"]);
        assert_eq!(run.status.code(), Some(1), "{}", model.display());
        assert!(
            !run.stderr.is_empty(),
            "{} gave no message",
            model.display()
        );
        assert!(!out.exists(), "{} left a file", model.display());
    }
    // A region with nothing in it.
    let sphere = fixtures().join("bench/sphere.rhai");
    let run = isoforge(&[
        "mesh",
        s(&sphere),
        "-o",
        s(&out),
        "--bounds=5,5,5,6,6,6",
        "--depth",
        "4",
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("nothing"));
    assert!(!out.exists());
    // A missing model file.
    let run = isoforge(&["mesh", "no/such/model.rhai", "-o", s(&out)]);
    assert_eq!(run.status.code(), Some(1));
    assert!(!out.exists());
}

#[test]
fn every_fixture_is_closed_at_depths_6_8_and_9_with_the_default_tolerance() {
    // The merged (adaptive) output on every model the project ships, at the depths users
    // print at: closed, manifold and oriented as written and as read back.
    let dir = tempfile::tempdir().expect("tempdir");
    let all = models("classic")
        .into_iter()
        .chain(models("bench"))
        .chain(models("flat"));
    for model in all {
        for depth in ["6", "8", "9"] {
            let out = dir.path().join("out.stl");
            mesh_ok(&model, &out, &["--depth", depth]);
        }
    }
}

#[test]
fn tolerance_trades_triangles_for_distance() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("sphere.stl");
    let sphere = fixtures().join("bench/sphere.rhai");
    let triangles = |extra: &[&str]| {
        let mut args = vec!["--depth", "6"];
        args.extend_from_slice(extra);
        let json = mesh_ok(&sphere, &out, &args);
        (
            json["triangles"].as_u64().unwrap_or(0),
            json["tolerance"].as_f64(),
        )
    };
    let (uniform, t0) = triangles(&["--tolerance", "0"]);
    let (default, t_default) = triangles(&[]);
    let (coarse, t_coarse) = triangles(&["--tolerance", "0.02"]);
    assert_eq!(t0, Some(0.0));
    // The default: a tenth of the finest cell (3 mm / 64).
    assert!((t_default.unwrap_or(0.0) - 0.1 * 3.0 / 64.0).abs() < 1e-12);
    assert_eq!(t_coarse, Some(0.02));
    assert!(
        uniform > 2 * default && default > coarse,
        "{uniform} {default} {coarse}"
    );
    // The tolerance held, as `check --against` measures it.
    for (tolerance, flag) in [(0.1 * 3.0 / 64.0, None), (0.02, Some("0.02"))] {
        let mut args = vec!["--depth", "6"];
        if let Some(t) = flag {
            args.extend(["--tolerance", t]);
        }
        mesh_ok(&sphere, &out, &args);
        let json = check_against(&out, &sphere);
        let max = json["max_deviation"].as_f64().unwrap_or(f64::MAX);
        assert!(max <= tolerance, "max deviation {max} > {tolerance}");
    }
}

#[test]
fn hulls_of_boxes_and_imported_meshes_merge_and_hold_the_tolerance() {
    // Both fields' gradients on their flat faces were once the direction from the point
    // to its nearest point, which is rounding error where the point is on the surface (as
    // a crossing interpolated on a plane is): the hull below was 834 triangles at depth 8,
    // 1.71 tolerances off, and drilled_import 3,256 at depth 7, 3.27 off.
    let dir = tempfile::tempdir().expect("tempdir");
    let hull = dir.path().join("hull_boxes.rhai");
    std::fs::write(
        &hull,
        "bounds([-12, -12, -12], [32, 32, 32]);\n\
         hull([\n\
             box([10, 10, 10]).rotate_z(20),\n\
             box([6, 6, 6]).rotate_x(30).move([20, 15, 10]),\n\
             box([4, 8, 2]).move([5, 20, 18]),\n\
         ])\n",
    )
    .expect("write the model");
    let drilled = fixtures().join("modern/drilled_import.rhai");
    for (model, depth, most) in [(&hull, "8", 400), (&drilled, "7", 2_000)] {
        let out = dir.path().join("out.stl");
        let json = mesh_ok(model, &out, &["--depth", depth]);
        let triangles = json["triangles"].as_u64().unwrap_or(u64::MAX);
        assert!(triangles < most, "{model:?}: {triangles} triangles");
        let tolerance = json["tolerance"].as_f64().unwrap_or(0.0);
        let check = check_against(&out, model);
        let max = check["max_deviation"].as_f64().unwrap_or(f64::MAX);
        assert!(max <= tolerance, "{model:?}: {max} > {tolerance}");
        assert_eq!(check["closed_manifold"], serde_json::Value::Bool(true));
    }
}

#[test]
fn a_model_meshes_to_the_same_bytes_on_one_thread_or_several() {
    // Slabs are meshed in parallel and written in order, so the file may not depend on
    // how the work was shared out. Hulls of boxes once gave 834 or 872 triangles from run
    // to run (their gradients on the surface were rounding error), and a hull of two of
    // them 40 or 54 at depth 7 (its facets came in a set's order); an imported mesh, a
    // gyroid and a model with creases and a cone's tip take every stage of the pipeline.
    let dir = tempfile::tempdir().expect("tempdir");
    let hull = dir.path().join("hull_boxes.rhai");
    std::fs::write(
        &hull,
        "bounds([-12, -12, -12], [32, 32, 32]);\n\
         hull([box([10, 10, 10]).rotate_z(20), box([6, 6, 6]).rotate_x(30).move([20, 15, 10])])\n",
    )
    .expect("write the model");
    let models = [
        hull,
        fixtures().join("modern/drilled_import.rhai"),
        fixtures().join("bench/gyroid_sphere.rhai"),
        fixtures().join("classic/spaceship.rhai"),
    ];
    for model in &models {
        let mut files = Vec::new();
        for threads in ["1", "2", "3"] {
            let out = dir.path().join(format!("on_{threads}.stl"));
            let run = std::process::Command::new(crate::isoforge_bin())
                .args(["mesh", s(model), "--depth", "7", "-o", s(&out)])
                .env("RAYON_NUM_THREADS", threads)
                .output()
                .expect("isoforge runs");
            assert!(run.status.success(), "{model:?} on {threads} threads");
            files.push(std::fs::read(&out).expect("the output"));
        }
        assert!(files[0].len() > 84, "{model:?}: an empty mesh");
        assert!(
            files.iter().all(|f| *f == files[0]),
            "{model:?}: the files differ"
        );
    }
}

#[test]
fn box_like_models_take_few_triangles() {
    // Flat faces merge into large cells: an axis-aligned box at depth 9 (512 cells along
    // its region) is a few hundred triangles, not hundreds of thousands, and keeps its
    // volume.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("prism.stl");
    let json = mesh_ok(&fixtures().join("flat/prism.rhai"), &out, &["--depth", "9"]);
    let triangles = json["triangles"].as_u64().unwrap_or(u64::MAX);
    assert!(triangles < 2000, "{triangles} triangles");
    let vol = json["volume"].as_f64().unwrap_or(0.0);
    assert!((vol - 3000.0).abs() < 1.0, "{vol}");
    // Turned off the lattice, a cube's edges block the merge; the field-checked edge
    // collapses take what is left along them (16,224 triangles at depth 9 without them).
    let out = dir.path().join("turned_cube.stl");
    let json = mesh_ok(
        &fixtures().join("flat/turned_cube.rhai"),
        &out,
        &["--depth", "9"],
    );
    let triangles = json["triangles"].as_u64().unwrap_or(u64::MAX);
    assert!(triangles < 2000, "turned cube: {triangles} triangles");
    let vol = json["volume"].as_f64().unwrap_or(0.0);
    assert!((vol - 8.0).abs() < 0.01, "turned cube: {vol}");
}

#[test]
fn a_sheet_thinner_than_a_cell_takes_not_many_more_triangles_than_the_uniform_mesh() {
    // A gyroid sheet a third of a cell thick: every chord from one side of it to the other
    // has its middle inside, and splitting it leaves a half that crosses again. The
    // refiner split such chords down to its level cap: 3,972 triangles at the default
    // tolerance for the uniform mesh's 708, its largest distance no better (0.110 and
    // 0.109 mm).
    let dir = tempfile::tempdir().expect("tempdir");
    let model = thin_gyroid(dir.path());
    let out = dir.path().join("out.stl");
    let measured = |extra: &[&str]| {
        let mut args = vec!["--depth", "5"];
        args.extend_from_slice(extra);
        let json = mesh_ok(&model, &out, &args);
        let check = check_against(&out, &model);
        (
            json["triangles"].as_u64().unwrap_or(u64::MAX),
            check["max_deviation"].as_f64().unwrap_or(f64::MAX),
            check["mean_deviation"].as_f64().unwrap_or(f64::MAX),
        )
    };
    let (uniform, uniform_max, uniform_mean) = measured(&["--tolerance", "0"]);
    let (refined, max, mean) = measured(&[]);
    assert!(
        refined <= 2 * uniform,
        "{refined} triangles at the default tolerance, {uniform} uniform"
    );
    assert!(
        max <= 1.05 * uniform_max && mean <= uniform_mean,
        "largest {max} (uniform {uniform_max}), mean {mean} (uniform {uniform_mean})"
    );
}

#[test]
fn a_twisted_solid_needs_no_region_given() {
    // Intervals over a box far off the axis see every turn of a twisted slice, so nothing
    // far away was pruned: both models below were refused ("the model has no region",
    // "shape 1 of the hull is not bounded") until `twist` cut its field to the cylinder
    // that holds the solid.
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.stl");
    for (name, src, volume) in [
        ("twisted_box", "twist(box([4, 4, 10]), 10)\n", Some(160.0)),
        (
            "hull_of_a_twist",
            "hull([twist(capsule([2, -1, 0], [2, -3, 1], 1.5), 25), sphere(1)])\n",
            None,
        ),
    ] {
        let model = dir.path().join(format!("{name}.rhai"));
        std::fs::write(&model, src).expect("write the model");
        let json = mesh_ok(&model, &out, &["--depth", "6"]);
        if let Some(v) = volume {
            let got = json["volume"].as_f64().unwrap_or(0.0);
            assert!((got - v).abs() < 0.01 * v, "{name}: volume {got}");
        }
    }
}

#[test]
fn bad_tolerances_exit_2_and_write_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.stl");
    let sphere = fixtures().join("bench/sphere.rhai");
    for t in ["-1", "nan", "inf", "wide", "-0.5"] {
        let run = isoforge(&[
            "mesh",
            s(&sphere),
            "-o",
            s(&out),
            "--depth",
            "4",
            &format!("--tolerance={t}"),
        ]);
        assert_eq!(run.status.code(), Some(2), "--tolerance {t}");
        assert!(!run.stderr.is_empty(), "--tolerance {t} says why");
        assert!(!out.exists(), "--tolerance {t} wrote a file");
    }
}

#[test]
fn a_model_thinner_than_the_lattice_gets_a_note() {
    // A gyroid sheet a third of a cell thick at depth 5, resolved at depth 7: the triangles
    // that join its two sides are counted, and when they are many the user is told why the
    // mesh may be off and what to do.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = thin_gyroid(dir.path());
    let out = dir.path().join("out.stl");
    let run = |depth: &str| {
        let run = isoforge(&["mesh", s(&model), "-o", s(&out), "--depth", depth, "--json"]);
        assert!(run.status.success(), "depth {depth}");
        let json: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
        let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
        (
            json["thin_triangles"].as_u64().expect("thin_triangles"),
            json["triangles"].as_u64().unwrap_or(0),
            stderr,
        )
    };
    let (thin, triangles, stderr) = run("5");
    assert!(50 * thin >= triangles, "{thin} of {triangles} triangles");
    assert!(
        stderr.contains("note:") && stderr.contains("finer --depth"),
        "{stderr}"
    );
    let (thin, _, stderr) = run("7");
    assert_eq!(thin, 0);
    assert!(!stderr.contains("note:"), "{stderr}");
    // A smooth solid has none.
    let json = mesh_ok(
        &fixtures().join("bench/sphere.rhai"),
        &out,
        &["--depth", "6"],
    );
    assert_eq!(json["thin_triangles"].as_u64(), Some(0));
}

#[test]
fn a_blob_that_came_out_inside_out_is_turned_and_counted() {
    // A ball 1.3 cells wide holding one lattice corner, at a tolerance of 3 cells (the
    // hunts' sixth inside-out blob): the mesher's blob came out inside out, and is written
    // the right way out; ADMesh finds nothing to turn.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = dir.path().join("blob.rhai");
    std::fs::write(
        &model,
        "sqrt(x*x + y*y + (z + 0.25)*(z + 0.25)) - 0.19086255957192788\n",
    )
    .expect("write the model");
    let out = dir.path().join("blob.stl");
    let region = "--bounds=-1.078539274558991,-1.062396520040577,-1.2753661925260393,\
                  1.244777736262466,0.8,0.8";
    let json = mesh_ok(
        &model,
        &out,
        &[region, "--depth", "3", "--tolerance", "0.871"],
    );
    assert_eq!(json["parts_turned"].as_u64(), Some(1), "{json}");
    crate::sweeps::admesh_finds_nothing_to_fix(&out, "blob");
    // The same ball at depth 6 is meshed the right way out to begin with.
    let json = mesh_ok(&model, &out, &[region, "--depth", "6"]);
    assert_eq!(json["parts_turned"].as_u64(), Some(0), "{json}");
}

#[test]
fn each_step_of_a_sweep_gets_its_own_thin_note() {
    // The gyroid's sheet at 0.22 mm is a third of a cell at depth 5; at 6 mm the sheet
    // fills the ball.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = thin_gyroid(dir.path());
    let out = dir.path().join("g.stl");
    let args = [
        "mesh",
        s(&model),
        "-o",
        s(&out),
        "--depth",
        "5",
        "--param",
        "t=0.22..6:2",
        "--json",
    ];
    let run = isoforge(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    let thin: Vec<u64> = json["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .map(|step| step["thin_triangles"].as_u64().expect("thin_triangles"))
        .collect();
    assert_eq!(thin.len(), 2);
    assert!(thin[0] > 0 && thin[1] == 0, "{thin:?}");
    let stderr = String::from_utf8_lossy(&run.stderr);
    let notes: Vec<&str> = stderr.lines().filter(|l| l.starts_with("note:")).collect();
    let thin_notes: Vec<&&str> = notes
        .iter()
        .filter(|l| l.contains("finer --depth"))
        .collect();
    assert_eq!(thin_notes.len(), 1, "{stderr}");
    assert!(thin_notes[0].contains("g-000.stl"), "{stderr}");
    // (Either step may also miss its tolerance where the splits onto the surface had to
    // stop: notes of their own, `left_off.rs`.)
}
