//! Judged by a program we did not write: PrusaSlicer slices the same models (meshed by
//! isoforge) with the same basic settings, and its G-code is read by the same checker as
//! ours: the layer counts must agree, our retractions stay within half again PrusaSlicer's,
//! and the part's extruded volume within a fifth of PrusaSlicer's.
//!
//! `.ci/run` installs PrusaSlicer (tools/install-peers.sh) and sets `ISOFORGE_PEERS=1`, so
//! there a missing peer fails the test; elsewhere it is skipped with a note.

use std::path::Path;
use std::process::Command;

use crate::{fixtures, isoforge};
use isoforge_slice::check::{self, GcodeReport, features};

const PRUSA: &str = "prusa-slicer";

/// True when PrusaSlicer runs here; false (with a note) when it does not and peers are
/// optional; a failure when `ISOFORGE_PEERS` asks for them.
fn prusa_present() -> bool {
    let ok = Command::new(PRUSA)
        .arg("--help")
        .output()
        .is_ok_and(|o| o.status.success());
    if !ok {
        assert!(
            std::env::var_os("ISOFORGE_PEERS").is_none(),
            "{PRUSA} is missing: run tools/install-peers.sh"
        );
        eprintln!("note: {PRUSA} not found, the peer comparison is skipped");
    }
    ok
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Our G-code of a calibration model and PrusaSlicer's of its mesh, both parsed.
fn both(name: &str, dir: &Path) -> (GcodeReport, GcodeReport) {
    let model = fixtures().join("slice").join(format!("{name}.rhai"));
    let stl = dir.join(format!("{name}.stl"));
    let ours = dir.join(format!("{name}.gcode"));
    let theirs = dir.join(format!("{name}.prusa.gcode"));
    for args in [
        vec!["mesh", path(&model), "-o", path(&stl), "-q"],
        vec!["slice", path(&model), "-o", path(&ours), "-q"],
    ] {
        let run = isoforge(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    // Our default profile's basics: 0.2 mm layers, two perimeters, 20% infill, a 0.4 mm
    // nozzle and 1.75 mm filament, a Marlin printer with a 220 mm bed.
    let run = Command::new(PRUSA)
        .args([
            "--export-gcode",
            "--layer-height",
            "0.2",
            "--first-layer-height",
            "0.2",
            "--perimeters",
            "2",
            "--fill-density",
            "20%",
            "--nozzle-diameter",
            "0.4",
            "--filament-diameter",
            "1.75",
            "--gcode-flavor",
            "marlin2",
            "--center",
            "110,110",
            path(&stl),
            "-o",
            path(&theirs),
        ])
        .output()
        .expect("prusa-slicer runs");
    assert!(
        run.status.success(),
        "{PRUSA}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let read = |p: &Path| check::parse(&std::fs::read_to_string(p).unwrap()).unwrap();
    (read(&ours), read(&theirs))
}

/// The part's volume: everything but skirt and brim, in either slicer's names.
fn part_volume(r: &GcodeReport) -> f64 {
    features::volume_where(r, 1.75, |x| {
        let f = x.feature.to_ascii_lowercase();
        !(f.contains("skirt") || f.contains("brim"))
    })
}

#[test]
fn cube_and_torus_agree_with_prusaslicer() {
    if !prusa_present() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for name in ["cube", "torus"] {
        let (ours, theirs) = both(name, dir.path());
        let (ro, rt) = (features::retractions(&ours), features::retractions(&theirs));
        let (vo, vt) = (part_volume(&ours), part_volume(&theirs));
        eprintln!(
            "{name}: layers {} / {}, retractions {ro} / {rt}, part volume {vo:.0} / {vt:.0} mm³ \
             (ours / PrusaSlicer)",
            ours.layers.len(),
            theirs.layers.len()
        );
        assert_eq!(
            ours.layers.len(),
            theirs.layers.len(),
            "{name}: layer counts"
        );
        assert!(rt > 0, "{name}: PrusaSlicer's retractions not seen");
        assert!(
            ro as f64 <= 1.5 * rt as f64,
            "{name}: {ro} retractions, PrusaSlicer {rt}"
        );
        assert!(
            (vo / vt - 1.0).abs() < 0.2,
            "{name}: part volume {vo:.0} mm³, PrusaSlicer {vt:.0} mm³"
        );
    }
}
