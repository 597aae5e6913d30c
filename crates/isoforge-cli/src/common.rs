//! What every subcommand shares: global flags, model loading, progress bars, JSON output.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{Result, anyhow};
use clap::Args;
use isoforge_field::Bounds;
use isoforge_field::RegionError;
use isoforge_script::{Model, RuntimeCause, ScriptError};

/// A mistake in how the command was called (exit status 2, as clap's own errors), as opposed
/// to work that failed (exit status 1). Put in an error's chain; `main` looks for it.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// A usage error with this message.
pub fn usage(message: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(UsageError(message.into()))
}

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
        let bounds = self.bounds.as_deref().map(parse_bounds).transpose()?;
        let model = isoforge_script::load_file(&self.model, &params).map_err(with_flag_hint)?;
        let bounds = match bounds {
            Some(b) => b,
            None => match model.bounds {
                Some(b) => b,
                None => isoforge_field::find_bounds(&model.shape).map_err(|e| {
                    region_error(e).context(format!("{}: no region", self.model.display()))
                })?,
            },
        };
        // A region with nothing in it would give an empty mesh or blank layers: say so.
        isoforge_field::ensure_not_empty(&model.shape, &bounds)
            .map_err(|e| region_error(e).context(self.model.display().to_string()))?;
        Ok(LoadedModel { model, bounds })
    }
}

/// A script error, with the command-line flag named where the value came from one.
fn with_flag_hint(e: ScriptError) -> anyhow::Error {
    if let Some(RuntimeCause::ParamOutOfRange { name, value, .. }) = e.runtime_cause() {
        return anyhow!("{e} (given as --param {name}={value})");
    }
    match &e {
        ScriptError::UnknownParams { unknown, .. } => {
            // A misspelt --param is a mistake in the call, like an unknown flag.
            usage(format!("{e}; check --param {}", unknown.join(", --param ")))
        }
        ScriptError::VmParams { .. } => usage(format!("{e}; drop --param")),
        _ => anyhow::Error::new(e),
    }
}

/// A region error, with the flag that gives a region where one is missing.
fn region_error(e: RegionError) -> anyhow::Error {
    match e {
        RegionError::Unbounded { .. } => anyhow!(
            "{e}. Give it a region: bounds([x0, y0, z0], [x1, y1, z1]) in the script, or \
             --bounds X0,Y0,Z0,X1,Y1,Z1"
        ),
        _ => anyhow::Error::new(e),
    }
}

fn parse_param(text: &str) -> Result<(String, f64)> {
    let Some((name, value)) = text.split_once('=') else {
        return Err(usage(format!("--param {text:?}: expected NAME=VALUE")));
    };
    let value: f64 = value
        .trim()
        .parse()
        .map_err(|_| usage(format!("--param {text:?}: {value:?} is not a number")))?;
    Ok((name.trim().to_string(), value))
}

/// Parses `X0,Y0,Z0,X1,Y1,Z1`; a malformed text is a usage error.
pub fn parse_bounds(text: &str) -> Result<Bounds> {
    let expected = || {
        usage(format!(
            "--bounds {text:?}: expected six numbers X0,Y0,Z0,X1,Y1,Z1"
        ))
    };
    let nums = text
        .split(',')
        .map(|s| s.trim().parse::<f64>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| expected())?;
    if nums.len() != 6 {
        return Err(expected());
    }
    Bounds::new([nums[0], nums[1], nums[2]], [nums[3], nums[4], nums[5]]).ok_or_else(|| {
        usage(format!(
            "--bounds {text:?}: each minimum must be finite and below its maximum"
        ))
    })
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

/// Set once a command has printed its JSON object, so `main` does not print a second one
/// for an error that follows it (the command's object then carries the `"error"` itself).
static JSON_PRINTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Prints a JSON object on stdout.
pub fn print_json(value: &serde_json::Value) {
    JSON_PRINTED.store(true, std::sync::atomic::Ordering::Relaxed);
    // `println!` panics when stdout is a closed pipe (`| head`); a reader that went away
    // is not an error of ours.
    let _ = writeln!(std::io::stdout().lock(), "{value}");
}

/// Whether a JSON object went to stdout already.
pub fn json_printed() -> bool {
    JSON_PRINTED.load(std::sync::atomic::Ordering::Relaxed)
}
