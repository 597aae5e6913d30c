//! `isoforge fake-printer`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge fake-printer`.
#[derive(Args, Debug)]
pub struct FakePrinterArgs {}

/// Runs the command.
pub fn run(args: FakePrinterArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
