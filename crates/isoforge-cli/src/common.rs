//! What every subcommand shares: global flags, model loading, progress bars, JSON output.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{Context as _, Result, bail};
use clap::Args;
use isoforge_field::Bounds;
use isoforge_script::Model;

/// Flags every subcommand takes.
#[derive(Args, Clone, Debug, Default)]
pub struct Global {
    /// Print nothing but errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Print one JSON object with the results on stdout, and nothing else there.
    #[arg(long, global = true)]
    pub json: bool,
}

impl Global {
    /// True when progress bars and chatter may be shown.
    pub fn chatty(&self) -> bool {
        !self.quiet && !self.json && std::io::stderr().is_terminal()
    }
}

/// The model a command works on, with parameter and region overrides.
#[derive(Args, Clone, Debug)]
pub struct ModelArgs {
    /// The model script (.rhai) or expression file (.vm).
    pub model: PathBuf,
    /// Set a script parameter: NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// The region: X0,Y0,Z0,X1,Y1,Z1 (overrides the script's bounds).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", allow_hyphen_values = true)]
    pub bounds: Option<String>,
}

/// A model with the region it is to be worked on.
pub struct LoadedModel {
    /// The script's result.
    pub model: Model,
    /// The region: --bounds, else the script's, else found by interval pruning.
    pub bounds: Bounds,
}

impl ModelArgs {
    /// Parses the overrides, runs the script and settles the region.
    pub fn load(&self) -> Result<LoadedModel> {
        let params = self
            .params
            .iter()
            .map(|p| parse_param(p))
            .collect::<Result<Vec<_>>>()?;
        let model = isoforge_script::load_file(&self.model, &params)?;
        let bounds = match &self.bounds {
            Some(text) => parse_bounds(text)?,
            None => match model.bounds {
                Some(b) => b,
                None => isoforge_field::find_bounds(&model.shape)
                    .map_err(region_hint)
                    .with_context(|| format!("{}: no region", self.model.display()))?,
            },
        };
        // A region with nothing in it would give an empty mesh or blank layers: say so.
        isoforge_field::ensure_not_empty(&model.shape, &bounds)
            .with_context(|| self.model.display().to_string())?;
        Ok(LoadedModel { model, bounds })
    }
}

/// The region error, with how to give a region where none could be found.
fn region_hint(e: isoforge_field::RegionError) -> anyhow::Error {
    match e {
        isoforge_field::RegionError::Unbounded { .. } => anyhow::anyhow!(
            "{e}. Give it a region: bounds([x0, y0, z0], [x1, y1, z1]) in the script, or \
             --bounds X0,Y0,Z0,X1,Y1,Z1"
        ),
        e => e.into(),
    }
}

fn parse_param(text: &str) -> Result<(String, f64)> {
    let Some((name, value)) = text.split_once('=') else {
        bail!("--param {text:?}: expected NAME=VALUE");
    };
    let value: f64 = value
        .trim()
        .parse()
        .with_context(|| format!("--param {text:?}: {value:?} is not a number"))?;
    Ok((name.trim().to_string(), value))
}

/// Parses `X0,Y0,Z0,X1,Y1,Z1`.
pub fn parse_bounds(text: &str) -> Result<Bounds> {
    let nums = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<Vec<_>, _>>()
        .with_context(|| format!("--bounds {text:?}: expected six numbers X0,Y0,Z0,X1,Y1,Z1"))?;
    if nums.len() != 6 {
        bail!("--bounds {text:?}: expected six numbers X0,Y0,Z0,X1,Y1,Z1");
    }
    Bounds::new([nums[0], nums[1], nums[2]], [nums[3], nums[4], nums[5]])
        .with_context(|| format!("--bounds {text:?}: each minimum must be below its maximum"))
}

/// A progress bar on a terminal; hidden when piped, `--quiet` or `--json`.
pub fn progress_bar(global: &Global, len: u64, message: &str) -> indicatif::ProgressBar {
    if !global.chatty() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg:>10} [{bar:40}] {percent:>3}% {elapsed_precise} eta {eta}",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(message.to_string());
    bar
}

/// Prints a JSON object on stdout.
pub fn print_json(value: &serde_json::Value) {
    // `println!` panics when stdout is a closed pipe (`| head`); a reader that went away
    // is not an error of ours.
    let _ = writeln!(std::io::stdout().lock(), "{value}");
}
