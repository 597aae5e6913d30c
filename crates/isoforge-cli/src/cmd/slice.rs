//! `isoforge slice`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge slice`.
#[derive(Args, Debug)]
pub struct SliceArgs {}

/// Runs the command.
pub fn run(args: SliceArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
