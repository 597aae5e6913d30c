//! End-to-end tests of the `isoforge` binary, one module per command. They run the binary
//! cargo built for this very test run (`CARGO_BIN_EXE_isoforge`), so `cargo test -p
//! isoforge-cli` always tests the current code, and they are one test binary so the
//! workspace is linked once.

mod bad_scripts;
mod browser;
mod calibration;
mod check;
mod dialects;
mod help;
mod info;
mod interop;
mod left_off;
mod max_depth;
mod mesh;
mod openscad;
mod outputs;
mod peers;
mod print;
mod render;
mod slice;
mod studio;
mod studio_browser;
mod studio_process;
mod sweep;
mod sweeps;
mod word;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `isoforge` binary of this build.
pub fn isoforge_bin() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_isoforge"))
}

/// The repository's `fixtures/` folder.
pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

/// Runs `isoforge` with arguments and returns what it did.
pub fn isoforge(args: &[&str]) -> Output {
    Command::new(isoforge_bin())
        .args(args)
        .output()
        .expect("isoforge runs")
}
