//! `isoforge check`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge check`.
#[derive(Args, Debug)]
pub struct CheckArgs {}

/// Runs the command.
pub fn run(args: CheckArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
