//! `isoforge info`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge info`.
#[derive(Args, Debug)]
pub struct InfoArgs {}

/// Runs the command.
pub fn run(args: InfoArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
