//! `isoforge mesh`.

use std::process::ExitCode;

use anyhow::{Result, bail};
use clap::Args;

use crate::common::Global;

/// Arguments of `isoforge mesh`.
#[derive(Args, Debug)]
pub struct MeshArgs {}

/// Runs the command.
pub fn run(args: MeshArgs, global: &Global) -> Result<ExitCode> {
    let _ = (args, global);
    bail!("not built yet")
}
