//! `isoforge render`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge render`.
#[derive(Args, Debug)]
pub struct RenderArgs {}

/// Runs the command.
pub fn run(args: RenderArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
