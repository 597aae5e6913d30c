//! Every subcommand answers `--help`; an unknown one is a usage error.

use crate::isoforge;

#[test]
fn every_subcommand_has_help() {
    for sub in [
        "mesh",
        "render",
        "check",
        "info",
        "slice",
        "print",
        "fake-printer",
    ] {
        let out = isoforge(&[sub, "--help"]);
        assert!(out.status.success(), "{sub} --help failed");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("Usage"),
            "{sub}"
        );
    }
}

#[test]
fn unknown_subcommand_is_a_usage_error() {
    let out = isoforge(&["frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
}
