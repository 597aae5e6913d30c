//! `isoforge print`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge print`.
#[derive(Args, Debug)]
pub struct PrintArgs {}

/// Runs the command.
pub fn run(args: PrintArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
