//! A plain `isoforge mesh` run's own word on its tolerance: the places the splits onto the
//! surface had to leave off it, measured, reported in `--json` as `left_off` and, when one
//! misses the tolerance, in a note naming the place and `--max-depth`. Judged against
//! `check --against`, which measures the whole mesh.

use std::path::Path;

use crate::max_depth::{checked, s};
use crate::{fixtures, isoforge};

/// `isoforge mesh MODEL --depth 7 -o OUT ARGS...`: stdout, stderr, asserting exit 0.
fn mesh(model: &Path, out: &Path, extra: &[&str]) -> (Vec<u8>, String) {
    let mut args = vec!["mesh", s(model), "--depth", "7", "-o", s(out)];
    args.extend_from_slice(extra);
    let run = isoforge(&args);
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(run.status.success(), "{extra:?}: {stderr}");
    (run.stdout, stderr)
}

#[test]
fn a_plain_run_names_a_place_where_its_mesh_misses_the_tolerance() {
    // curve_cyl at depth 7: where its cylinders meet the cap, wedges thinner than the
    // lattice, 2.2 tolerances off by `check`.
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("classic/curve_cyl.rhai");
    let out = dir.path().join("cc.stl");
    let (stdout, stderr) = mesh(&model, &out, &["--json"]);
    let j: serde_json::Value = serde_json::from_slice(&stdout).expect("JSON");
    let tolerance = j["tolerance"].as_f64().expect("tolerance");
    let left = &j["left_off"];
    let largest = left["max_distance"].as_f64().expect("max_distance");
    assert!(largest > tolerance, "{j}");
    assert_eq!(left["tolerance_missed"].as_bool(), Some(true), "{j}");
    assert!(left["places"].as_u64() >= Some(1), "{j}");
    assert_eq!(left["places"].as_u64(), left["measured"].as_u64(), "{j}");
    assert!(
        stderr.contains("misses the tolerance") && stderr.contains("--max-depth 9"),
        "{stderr}"
    );

    // `check` measures the whole mesh: it misses, by at least as much as the place says
    // (the place is a point of the mesh), and the place is on the mesh's bounds' side.
    let (c, _) = checked(&out, &model, tolerance);
    assert_eq!(c["tolerance_held"].as_bool(), Some(false), "{c}");
    let whole = c["max_deviation"].as_f64().expect("max_deviation");
    assert!(largest <= whole + 1e-9, "place {largest} > mesh {whole}");
    let at: Vec<f64> = left["max_distance_at"]
        .as_array()
        .expect("max_distance_at")
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let bounds = j["bounds"].as_array().expect("bounds");
    for a in 0..3 {
        let (lo, hi) = (
            bounds[0][a].as_f64().unwrap(),
            bounds[1][a].as_f64().unwrap(),
        );
        assert!((lo..=hi).contains(&at[a]), "{at:?} outside {bounds:?}");
    }

    // --quiet keeps the note to itself; --max-depth measures the whole mesh instead.
    let (_, quiet) = mesh(&model, &out, &["--quiet"]);
    assert_eq!(quiet, "");
    let (stdout, _) = mesh(&model, &out, &["--json", "--max-depth", "7"]);
    let m: serde_json::Value = serde_json::from_slice(&stdout).expect("JSON");
    assert!(m.get("left_off").is_none(), "{m}");
    assert!(m["max_deviation"].as_f64() >= Some(largest - 1e-9), "{m}");
}

#[test]
fn a_mesh_that_holds_has_no_place_beyond_and_no_note() {
    let dir = tempfile::tempdir().expect("tempdir");
    let model = fixtures().join("bench/sphere.rhai");
    let out = dir.path().join("sphere.stl");
    let (stdout, stderr) = mesh(&model, &out, &["--json"]);
    let j: serde_json::Value = serde_json::from_slice(&stdout).expect("JSON");
    assert_eq!(
        j["left_off"]["tolerance_missed"].as_bool(),
        Some(false),
        "{j}"
    );
    assert!(!stderr.contains("misses the tolerance"), "{stderr}");
    let tolerance = j["tolerance"].as_f64().expect("tolerance");
    let (c, _) = checked(&out, &model, tolerance);
    assert_eq!(c["tolerance_held"].as_bool(), Some(true), "{c}");
}
