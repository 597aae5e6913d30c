//! Finer where the mesh misses (`isoforge mesh`, `cmd/mesh/finer.rs`): a mesh that misses
//! its tolerance is made again with the blocks around its misses sampled on a finer lattice,
//! the tolerance the same in millimetres, round after round. With `--max-depth` every mesh
//! is measured whole; without `--depth` or `--resolution` the first mesh's places tell.
//! The mesh written holds its tolerance by `check --against`, and ADMesh finds nothing to
//! fix in it.

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

/// The files left in a folder, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn a_model_that_misses_its_tolerance_is_refined_where_it_misses_until_it_holds() {
    // curve_cyl at depth 7: where its two cylinders meet the cap, a wedge thinner than
    // the lattice is cut off, 2.2 tolerances off; two levels finer around it, it holds.
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
    let rounds = made["rounds"].as_array().expect("rounds");
    assert!(rounds.len() >= 2, "{made}");
    // The first mesh measured is the plain run's, and it missed.
    assert_eq!(rounds[0]["triangles"], first["triangles"], "{made}");
    assert_eq!(rounds[0]["levels"], 0, "{made}");
    assert!(
        rounds[0]["max_deviation"].as_f64() > Some(tolerance),
        "{made}"
    );
    assert!(rounds[0]["misses"].as_u64() > Some(0), "{made}");
    // The one kept is refined, on the depth-7 lattice, and holds.
    let refined = &made["refined"];
    assert_eq!(made["depth"].as_u64(), Some(7), "{made}");
    assert!(refined["levels"].as_u64() >= Some(1), "{made}");
    assert!(refined["finest_depth"].as_u64() <= Some(10), "{made}");
    assert_eq!(made["tolerance_held"].as_bool(), Some(true), "{made}");
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
    // The dropped rounds' files are gone.
    assert_eq!(names(dir.path()), ["held.stl", "plain.stl"]);
}

#[test]
fn only_the_blocks_around_the_misses_are_refined() {
    // sinus_bugs at depth 7: its legs and the ripples' crests are thinner than the
    // lattice in a few places (a tenth of its blocks).
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/sinus_bugs.rhai");
    let out = dir.path().join("out.stl");
    let (made, _) = mesh_json(&model, &out, &["--depth", "7", "--max-depth", "9"]);
    let refined = &made["refined"];
    let (blocks, of) = (
        refined["blocks"].as_u64().expect("blocks"),
        refined["of_blocks"].as_u64().expect("of_blocks"),
    );
    assert!(blocks > 0 && 4 * blocks < of, "{made}");
    assert_eq!(made["tolerance_held"].as_bool(), Some(true), "{made}");
    let tolerance = made["tolerance"].as_f64().expect("tolerance");
    let (j, _) = checked(&out, &model, tolerance);
    assert_eq!(j["tolerance_held"].as_bool(), Some(true), "{j}");
}

#[test]
fn a_model_that_holds_at_once_is_meshed_once_and_the_same() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("bench/sphere.rhai");
    let (plain, measured) = (dir.path().join("a.stl"), dir.path().join("b.stl"));
    mesh_json(&model, &plain, &["--depth", "6"]);
    let (made, stderr) = mesh_json(&model, &measured, &["--depth", "6", "--max-depth", "9"]);
    assert_eq!(made["rounds"].as_array().map(Vec::len), Some(1), "{made}");
    assert_eq!(made["tolerance_held"], true, "{made}");
    assert!(made.get("refined").is_none(), "{made}");
    assert!(stderr.is_empty(), "{stderr}");
    // Measuring on the way changes nothing written.
    assert_eq!(
        std::fs::read(&plain).unwrap(),
        std::fs::read(&measured).unwrap()
    );
}

#[test]
fn the_best_mesh_is_kept_with_a_note_when_it_still_misses() {
    // One level finer is not enough for curve_cyl's wedge at depth 7.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/curve_cyl.rhai");
    let out = dir.path().join("out.stl");
    let (made, stderr) = mesh_json(&model, &out, &["--depth", "7", "--max-depth", "8"]);
    assert!(stderr.contains("misses the tolerance"), "{stderr}");
    assert!(stderr.contains("1 level finer"), "{stderr}");
    let tolerance = made["tolerance"].as_f64().expect("tolerance");
    let rounds = made["rounds"].as_array().expect("rounds");
    let kept = made["max_deviation"].as_f64().expect("max_deviation");
    let best = rounds
        .iter()
        .filter_map(|r| r["max_deviation"].as_f64())
        .fold(f64::INFINITY, f64::min);
    assert_eq!(kept, best, "the nearest round is kept: {made}");
    assert!(
        kept < rounds[0]["max_deviation"].as_f64().unwrap(),
        "{made}"
    );
    // What was written is that mesh, and `check` agrees it misses.
    let (j, status) = checked(&out, &model, tolerance);
    assert_eq!(
        (j["tolerance_held"].as_bool(), status),
        (Some(false), Some(1)),
        "{j}"
    );
    assert_eq!(j["triangles"], made["triangles"], "{j}");
    assert_eq!(names(dir.path()), ["out.stl"]);
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
fn each_step_of_a_parameter_range_is_refined_on_its_own() {
    // spiky_ball's spikes sharpen with their number; at depth 6 both steps miss.
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
    for step in steps {
        assert_eq!(step["depth"].as_u64(), Some(6), "{j}");
        assert!(step["refined_levels"].as_u64() >= Some(1), "{j}");
        assert_eq!(step["tolerance_held"].as_bool(), Some(true), "{j}");
    }
    // The sharper one holds by `check` too, at depth 6's tolerance.
    let tolerance = 28.0 / 64.0 * 0.1;
    let (c, status) = checked(&dir.path().join("ball-001.stl"), &model, tolerance);
    assert_eq!(
        (c["tolerance_held"].as_bool(), status),
        (Some(true), Some(0)),
        "{c}"
    );
}

#[test]
fn a_run_without_a_lattice_given_is_refined_where_its_places_miss() {
    // The primitives example at depth 8: the cone's tip and a torus's inner rim are
    // thinner than the lattice, 2.1 tolerances off.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("../docs/examples/modern/primitives.rhai");
    let at8 = dir.path().join("at8.stl");
    let (plain, stderr) = mesh_json(&model, &at8, &["--depth", "8"]);
    let tolerance = plain["tolerance"].as_f64().expect("tolerance");
    // The fault first: the depth-8 lattice misses, its places say so, and `check` agrees.
    assert_eq!(plain["left_off"]["tolerance_missed"], true, "{plain}");
    assert!(stderr.contains("misses the tolerance"), "{stderr}");
    assert!(plain.get("refined").is_none(), "{plain}");
    let (c, _) = checked(&at8, &model, tolerance);
    assert_eq!(c["tolerance_held"].as_bool(), Some(false), "{c}");

    // Without --depth: the same lattice, refined where it missed, and measured.
    let out = dir.path().join("out.stl");
    let (made, stderr) = mesh_json(&model, &out, &[]);
    assert_eq!(made["depth"].as_u64(), Some(8), "{made}");
    assert_eq!(made["tolerance"].as_f64(), Some(tolerance), "{made}");
    assert!(made["refined"]["levels"].as_u64() >= Some(1), "{made}");
    assert_eq!(made["tolerance_held"].as_bool(), Some(true), "{made}");
    assert!(!stderr.contains("misses the tolerance"), "{stderr}");
    let (c, status) = checked(&out, &model, tolerance);
    assert_eq!(
        (c["tolerance_held"].as_bool(), status),
        (Some(true), Some(0)),
        "{c}"
    );
    crate::sweeps::admesh_finds_nothing_to_fix_in_parts(&out, "primitives", 7);
    assert_eq!(names(dir.path()), ["at8.stl", "out.stl"]);
}

#[test]
fn a_run_without_a_lattice_given_that_holds_is_the_plain_mesh() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("bench/sphere.rhai");
    let (default, at8) = (dir.path().join("a.stl"), dir.path().join("b.stl"));
    let (made, _) = mesh_json(&model, &default, &[]);
    mesh_json(&model, &at8, &["--depth", "8"]);
    assert!(made.get("refined").is_none(), "{made}");
    assert!(made.get("rounds").is_none(), "{made}");
    assert_eq!(
        std::fs::read(&default).unwrap(),
        std::fs::read(&at8).unwrap()
    );
}

#[test]
fn a_device_output_is_meshed_once_and_not_refined() {
    // A mesh sent to a device cannot be taken back for a refined one.
    let model = fixtures().join("../docs/examples/modern/primitives.rhai");
    let run = isoforge(&["mesh", s(&model), "-o", "/dev/null", "--json"]);
    assert_eq!(run.status.code(), Some(0));
    let j: serde_json::Value = serde_json::from_slice(&run.stdout).expect("JSON");
    assert!(j.get("refined").is_none(), "{j}");
    assert_eq!(j["left_off"]["tolerance_missed"], true, "{j}");
}

#[test]
fn where_a_finer_lattice_is_not_enough_the_refined_blocks_merge_as_finely() {
    // The spaceship's mast meets its hull's rippled underside beside a ripple sharper than
    // a cell: the fine leaves, merged as far as the depth-8 tolerance lets coarse ones,
    // leave chords across it. Three levels finer still miss; merged as the fine lattice's
    // tolerance allows, the same blocks hold.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/spaceship.rhai");
    let out = dir.path().join("out.stl");
    let (made, stderr) = mesh_json(&model, &out, &[]);
    let tolerance = made["tolerance"].as_f64().expect("tolerance");
    let rounds = made["rounds"].as_array().expect("rounds");
    let last = rounds.last().expect("a round");
    let before = &rounds[rounds.len() - 2];
    // The fault first: the round before at the finest level, merged as usual, missed.
    assert_eq!(before["tight_merges"], false, "{made}");
    assert_eq!(before["levels"], last["levels"], "{made}");
    assert!(before["max_deviation"].as_f64() > Some(tolerance), "{made}");
    // Then the same blocks merged as finely hold, and the mesh written is that one.
    assert_eq!(last["tight_merges"], true, "{made}");
    assert_eq!(made["refined"]["tight_merges"], true, "{made}");
    assert_eq!(made["tolerance_held"].as_bool(), Some(true), "{made}");
    assert!(stderr.is_empty(), "{stderr}");
    let (c, status) = checked(&out, &model, tolerance);
    assert_eq!(
        (c["tolerance_held"].as_bool(), status),
        (Some(true), Some(0)),
        "{c}"
    );
    crate::sweeps::admesh_finds_nothing_to_fix_but_needles(&out, "spaceship", 1);
    assert_eq!(names(dir.path()), ["out.stl"]);
}
