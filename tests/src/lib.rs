//! End-to-end tests of the `isoforge` binary live in `tests/`; this library holds their
//! shared helpers.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default()
}

/// The `fixtures/` folder.
pub fn fixtures() -> PathBuf {
    workspace_root().join("fixtures")
}

/// The `isoforge` binary of this build. `cargo test --workspace` builds it before any test
/// runs (the CLI crate has integration tests of its own, so cargo builds its binary).
pub fn isoforge_bin() -> PathBuf {
    let exe = std::env::current_exe().expect("the test binary has a path");
    // target/<profile>/deps/<test> -> target/<profile>/isoforge
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("test binaries live in target/<profile>/deps");
    let bin = profile_dir.join(format!("isoforge{}", std::env::consts::EXE_SUFFIX));
    assert!(
        bin.exists(),
        "{} is missing: run `cargo test --workspace` (it builds the CLI first)",
        bin.display()
    );
    bin
}

/// Runs `isoforge` with arguments and returns what it did.
pub fn isoforge(args: &[&str]) -> Output {
    Command::new(isoforge_bin())
        .args(args)
        .output()
        .expect("isoforge runs")
}
