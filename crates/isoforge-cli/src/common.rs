//! What every subcommand shares: global flags, model loading, progress bars, JSON output.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

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

/// A mesh or G-code file given where a model goes is a mistake in the call (2), said in
/// words that point to what does take it, not a script syntax error at byte 87.
fn refuse_non_model(path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let what = if isoforge_mesh::MeshFormat::from_extension(path).is_some() {
        "a mesh: a model is a .rhai script or a .vm file. `isoforge check` and `isoforge slice` \
         take meshes; to build on one, write import_stl(\"FILE\") in a script"
    } else if crate::cmd::check_gcode::GCODE_EXTENSIONS.contains(&ext.as_str()) {
        "G-code: a model is a .rhai script or a .vm file. `isoforge check` reads G-code and \
         `isoforge print` prints it"
    } else {
        return Ok(());
    };
    Err(usage(format!("{}: is {what}", path.display())))
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
    /// Set a script parameter: NAME=VALUE (repeatable). `render` and `mesh` also take a
    /// range, NAME=FROM..TO:STEPS, and make one picture or mesh per step.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// The region: X0,Y0,Z0,X1,Y1,Z1 (overrides the script's bounds).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Stop a script that runs longer than this (wall-clock seconds).
    #[arg(long, value_name = "SECONDS", default_value_t = isoforge_script::DEFAULT_MAX_SECONDS)]
    pub script_timeout: f64,
    /// Stop a script that makes isoforge grow by more than this (MiB; Linux).
    #[arg(long, value_name = "MIB", default_value_t = isoforge_script::DEFAULT_MAX_MEMORY_BYTES >> 20)]
    pub script_memory: u64,
}

/// A model with the region it is to be worked on.
pub struct LoadedModel {
    /// The script's result.
    pub model: Model,
    /// The region: --bounds, else the script's, else found by interval pruning.
    pub bounds: Bounds,
}

/// A parameter swept over a range: `--param t=0..1:30`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The parameter.
    pub name: String,
    /// Its values, first to last.
    pub values: Vec<f64>,
}

/// The most steps a range may have: a frame or mesh is written per step.
pub const MAX_STEPS: usize = 10_000;

/// One `--param`: a value, or a range of steps.
#[derive(Clone, Debug, PartialEq)]
enum ParamValue {
    One(f64),
    Range(Vec<f64>),
}

impl ModelArgs {
    /// Parses the overrides, runs the script and settles the region. A range among the
    /// parameters is a usage error here: only `render` and `mesh` sweep.
    pub fn load(&self) -> Result<LoadedModel> {
        if let Some(sweep) = self.sweep()? {
            return Err(usage(format!(
                "--param {}=..: a range of values is for `isoforge render` (with --frames or \
                 --gif) and `isoforge mesh`; give one value",
                sweep.name
            )));
        }
        self.load_values()
    }

    /// The parameter range, if one `--param` is a range (at most one may be).
    pub fn sweep(&self) -> Result<Option<Sweep>> {
        let mut found = None;
        for p in &self.params {
            if let (name, ParamValue::Range(values)) = parse_param(p)? {
                if found.is_some() {
                    return Err(usage(format!(
                        "--param {p:?}: only one parameter may be given a range"
                    )));
                }
                found = Some(Sweep { name, values });
            }
        }
        Ok(found)
    }

    /// The same model arguments with the swept parameter fixed at `value`.
    pub fn at_step(&self, sweep: &Sweep, value: f64) -> ModelArgs {
        let mut args = self.clone();
        for p in &mut args.params {
            if matches!(parse_param(p), Ok((name, ParamValue::Range(_))) if name == sweep.name) {
                // `{}` prints the shortest text that parses back to the same f64.
                *p = format!("{}={value}", sweep.name);
            }
        }
        args
    }

    /// Runs the script with single-valued parameters and settles the region.
    fn load_values(&self) -> Result<LoadedModel> {
        let params = self
            .params
            .iter()
            .map(|p| match parse_param(p)? {
                (name, ParamValue::One(v)) => Ok((name, v)),
                (name, ParamValue::Range(_)) => {
                    Err(usage(format!("--param {name}=..: expected one value")))
                }
            })
            .collect::<Result<Vec<_>>>()?;
        refuse_non_model(&self.model)?;
        let limits = self.limits()?;
        let bounds = self.bounds.as_deref().map(parse_bounds).transpose()?;
        let model = isoforge_script::load_file_with(&self.model, &params, &limits)
            .map_err(with_flag_hint)?;
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

    /// The script's budgets from `--script-timeout` and `--script-memory`.
    fn limits(&self) -> Result<isoforge_script::ScriptLimits> {
        if !(self.script_timeout.is_finite() && self.script_timeout > 0.0) {
            return Err(usage(format!(
                "--script-timeout {}: expected a positive number of seconds",
                self.script_timeout
            )));
        }
        if self.script_memory == 0 {
            return Err(usage(
                "--script-memory 0: expected at least 1 MiB".to_string(),
            ));
        }
        Ok(isoforge_script::ScriptLimits {
            max_seconds: self.script_timeout,
            max_memory_bytes: self.script_memory.saturating_mul(1 << 20),
        })
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

/// Parses `NAME=VALUE` or `NAME=FROM..TO:STEPS` (STEPS values from FROM to TO, both
/// included); a malformed text is a usage error.
fn parse_param(text: &str) -> Result<(String, ParamValue)> {
    let Some((name, value)) = text.split_once('=') else {
        return Err(usage(format!("--param {text:?}: expected NAME=VALUE")));
    };
    let name = name.trim().to_string();
    let number = |v: &str| -> Result<f64> {
        let n: f64 = v
            .trim()
            .parse()
            .map_err(|_| usage(format!("--param {text:?}: {v:?} is not a number")))?;
        if n.is_finite() {
            Ok(n)
        } else {
            Err(usage(format!(
                "--param {text:?}: {v:?} is not a finite number"
            )))
        }
    };
    let Some((from, rest)) = value.split_once("..") else {
        return Ok((name, ParamValue::One(number(value)?)));
    };
    let range_form = || {
        usage(format!(
            "--param {text:?}: a range is NAME=FROM..TO:STEPS, e.g. t=0..1:30"
        ))
    };
    let (to, steps) = rest.split_once(':').ok_or_else(range_form)?;
    let (from, to) = (number(from)?, number(to)?);
    let steps: usize = steps.trim().parse().map_err(|_| range_form())?;
    if steps == 0 || steps > MAX_STEPS {
        return Err(usage(format!(
            "--param {text:?}: the number of steps must be 1 to {MAX_STEPS}"
        )));
    }
    let values = (0..steps)
        .map(|i| {
            if steps == 1 {
                from
            } else {
                from + (to - from) * i as f64 / (steps - 1) as f64
            }
        })
        .collect();
    Ok((name, ParamValue::Range(values)))
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
