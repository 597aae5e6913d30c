//! Every subcommand answers `--help` (this file also makes `cargo test` build the binary
//! that the end-to-end tests in `tests/` run).

use std::process::Command;

#[test]
fn every_subcommand_has_help() {
    let bin = env!("CARGO_BIN_EXE_isoforge");
    for sub in [
        "mesh",
        "render",
        "check",
        "info",
        "slice",
        "print",
        "fake-printer",
    ] {
        let out = Command::new(bin).args([sub, "--help"]).output().unwrap();
        assert!(out.status.success(), "{sub} --help failed");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("Usage"),
            "{sub}"
        );
    }
}

#[test]
fn unknown_subcommand_is_a_usage_error() {
    let bin = env!("CARGO_BIN_EXE_isoforge");
    let out = Command::new(bin).arg("frobnicate").output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}
