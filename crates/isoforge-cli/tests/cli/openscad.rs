//! Our sweeps judged by OpenSCAD (installed by tools/install-peers.sh, which .ci/run
//! calls): OpenSCAD's own `linear_extrude` and `rotate_extrude` of the same profiles are
//! meshes whose vertices lie on the exact surfaces, so `isoforge check THEIRS --against
//! OURS` measures how far apart the two programs' solids are. It catches a twist turned
//! the other way, a scale applied at the wrong end, a revolve starting from another axis,
//! a profile placed differently. The volumes are compared too, with the exact one known.
//!
//! BOSL2's `skin`, `path_sweep` and textures are not here: BOSL2 is an OpenSCAD library
//! that no package registry this project installs from carries.

use std::path::Path;
use std::process::Command;

use crate::isoforge;
use crate::mesh::mesh_ok;

/// One model written twice: for OpenSCAD and for us, with the exact volume.
struct Pair {
    name: &'static str,
    scad: &'static str,
    rhai: &'static str,
    /// The same model with a convention turned around (the twist's sign, the angle's
    /// start), which must be far from OpenSCAD's: the comparison can see a mistake.
    wrong: &'static str,
    volume: f64,
}

const PAIRS: &[Pair] = &[
    Pair {
        name: "twisted, tapered square",
        scad: "linear_extrude(height=20, twist=90, slices=200, scale=0.5) \
               square([10, 10], center=true);",
        rhai: "linear_sweep(rect([10, 10]), 20, #{twist: 90, scale: 0.5})",
        wrong: "linear_sweep(rect([10, 10]), 20, #{twist: -90, scale: 0.5})",
        // Area · h · (1 + k + k²) / 3.
        volume: 100.0 * 20.0 * (1.0 + 0.5 + 0.25) / 3.0,
    },
    Pair {
        name: "twisted L",
        scad: "linear_extrude(height=15, twist=60, slices=150) \
               polygon([[0, 0], [10, 0], [10, 3], [3, 3], [3, 10], [0, 10]]);",
        rhai: "linear_sweep(polygon([[0, 0], [10, 0], [10, 3], [3, 3], [3, 10], [0, 10]]), \
               15, #{twist: 60})",
        wrong: "linear_sweep(polygon([[0, 0], [10, 0], [10, 3], [3, 3], [3, 10], [0, 10]]), \
                15, #{twist: 60, scale: 0.9})",
        volume: (30.0 + 21.0) * 15.0,
    },
    Pair {
        name: "three quarters of a ring",
        scad: "rotate_extrude(angle=270, $fn=360) translate([8, 0]) square([2, 6]);",
        rhai: "revolve(move(rect([2, 6]), [9, 3]), #{angle: 270})",
        wrong: "rotate_z(revolve(move(rect([2, 6]), [9, 3]), #{angle: 270}), 90)",
        volume: 0.75 * std::f64::consts::PI * (100.0 - 64.0) * 6.0,
    },
];

/// How far OpenSCAD's facets may be from our surface, mm: their vertices are on it, and
/// between the slices (200 over 20 mm, a 0.45° turn each) and the 360 steps around, the
/// flat facets stray by under 0.02 mm (measured: 0.019, 0.016, 0.0004).
const FACETS_OFF: f64 = 0.05;

fn openscad_stl(dir: &Path, name: &str, source: &str) -> std::path::PathBuf {
    let scad = dir.join(format!("{name}.scad"));
    let stl = dir.join(format!("{name}.stl"));
    std::fs::write(&scad, source).expect("write .scad");
    let run = Command::new("openscad")
        .arg("-o")
        .arg(&stl)
        .arg(&scad)
        .output()
        .unwrap_or_else(|e| {
            panic!(
                "openscad did not run ({e}): tools/install-peers.sh installs it, .ci/run calls it"
            )
        });
    assert!(
        run.status.success() && stl.exists(),
        "openscad {}: {}",
        scad.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    stl
}

/// `isoforge check MESH --against MODEL --json`.
fn against(mesh: &Path, model: &Path) -> serde_json::Value {
    let run = isoforge(&[
        "check",
        mesh.to_str().expect("utf-8"),
        "--against",
        model.to_str().expect("utf-8"),
        "--json",
    ]);
    assert!(
        run.status.success(),
        "check {}: {}",
        mesh.display(),
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).expect("--json prints one JSON object")
}

#[test]
fn openscad_extrusions_lie_on_our_sweeps() {
    let dir = tempfile::tempdir().expect("tempdir");
    for (i, pair) in PAIRS.iter().enumerate() {
        let name = pair.name;
        let theirs = openscad_stl(dir.path(), &format!("pair{i}"), pair.scad);
        let ours = dir.path().join(format!("pair{i}.rhai"));
        let wrong = dir.path().join(format!("pair{i}-wrong.rhai"));
        std::fs::write(&ours, pair.rhai).expect("write .rhai");
        std::fs::write(&wrong, pair.wrong).expect("write .rhai");

        // The comparison can fail: with a convention turned, OpenSCAD's solid is far off.
        let off = against(&theirs, &wrong)["max_deviation"]
            .as_f64()
            .unwrap_or(0.0);
        assert!(off > 0.5, "{name}: the wrong model is only {off} mm off");

        let report = against(&theirs, &ours);
        assert_eq!(report["closed_manifold"], true, "{name}: OpenSCAD's mesh");
        let max = report["max_deviation"].as_f64().unwrap_or(f64::INFINITY);
        assert!(
            max <= FACETS_OFF,
            "{name}: OpenSCAD's facets {max} mm from ours"
        );

        // Volumes: OpenSCAD's polyhedron and our mesh of the field, against the exact one.
        let their_volume = report["volume"].as_f64().unwrap_or(0.0);
        let mesh = dir.path().join(format!("pair{i}-ours.stl"));
        let our_volume = mesh_ok(&ours, &mesh, &["--depth", "7"])["volume"]
            .as_f64()
            .unwrap_or(0.0);
        let rel = |v: f64| (v - pair.volume).abs() / pair.volume;
        assert!(rel(their_volume) < 5e-3, "{name}: OpenSCAD {their_volume}");
        assert!(
            rel(our_volume) < 2e-3,
            "{name}: ours {our_volume}, exact {}",
            pair.volume
        );
    }
}
