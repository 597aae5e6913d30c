//! `isoforge fake-printer`: a simulated Marlin-style printer on a pseudo-terminal.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Args;
use isoforge_host::dialect::Dialect;
use isoforge_host::fake::{FakeConfig, FakePrinter, Faults, FirmwareConfig};

use crate::common::{Global, usage};

/// Arguments of `isoforge fake-printer`.
#[derive(Args, Debug)]
#[command(
    about = "Run a simulated Marlin-style printer on a pseudo-terminal",
    after_help = "Starts a simulated Marlin-style printer on a pseudo-terminal and prints its device \
path on the first line of stdout; point `isoforge print --port PATH` (or any host) at it. It \
checks line numbers and checksums as Marlin does, has 4 command slots and a 128-byte receive \
buffer (bytes beyond it are lost), answers `ok` after executing, heats with `echo:busy: \
processing` during M109/M190, and reports temperatures (M105, M155). It serves until the host \
disconnects or a signal (Ctrl-C, SIGTERM, SIGHUP) stops it; the --log file is written then, whole, \
ending with a `# faults ...` line counting the faults actually injected. --dialect sets whose words \
it speaks (banner, error texts, resend and ok forms). With --json the device path goes to stderr \
(`fake printer on PATH`) and stdout gets one JSON object when it stops: {\"port\", \"dialect\", \
\"executed\", \"faults\": {counts of each fault injected}}.\n\nExample:\n  isoforge fake-printer --faults corrupt=0.01,drop=0.005,seed=7 --log executed.tsv"
)]
pub struct FakePrinterArgs {
    /// Limit the link to this baud rate's byte speed (10 bits a byte); default: no limit.
    #[arg(long, value_name = "N")]
    pub baud: Option<u32>,
    /// Faults to inject, seeded and repeatable: comma-separated KEY=VALUE. Rates per line:
    /// corrupt=P (a byte host->printer), corrupt-reply=P (a byte printer->host), drop=P (a
    /// line lost), drop-ok=P, error=P (Error: without Resend), spurious-resend=P,
    /// no-resend-ok=P (Resend without ok), busy=P. One-shot events after N executed
    /// commands: reset-at=N, halt-at=N, silent-at=N. Modes: advanced-ok (ok N.. P.. B..).
    /// seed=N. Example: corrupt=0.01,drop=0.005,reset-at=5000,seed=7
    #[arg(long, value_name = "SPEC")]
    pub faults: Option<String>,
    /// Record every executed command to this file: `LINE<TAB>COMMAND` (`-` for unnumbered),
    /// written when the printer stops. An existing file that is not such a log is refused.
    #[arg(long, value_name = "FILE")]
    pub log: Option<PathBuf>,
    /// The firmware whose words it speaks: marlin, prusa, reprapfirmware, repetier, smoothie,
    /// klipper, octoprint-virtual.
    #[arg(long, value_name = "NAME", default_value = "marlin")]
    pub dialect: String,
    /// Real seconds per simulated second of heating (heating runs at 40 °C a second).
    #[arg(long, value_name = "SECONDS", default_value_t = 0.05)]
    pub heat_tick: f64,
}

/// Runs the command.
pub fn run(args: FakePrinterArgs, global: &Global) -> Result<ExitCode> {
    let faults = match &args.faults {
        Some(spec) => Faults::parse(spec).map_err(|e| usage(format!("--faults: {e}")))?,
        None => Faults::default(),
    };
    if !(0.0..=10.0).contains(&args.heat_tick) {
        return Err(usage(format!(
            "--heat-tick {}: expected 0 to 10 seconds",
            args.heat_tick
        )));
    }
    let dialect = Dialect::parse(&args.dialect).ok_or_else(|| {
        usage(format!(
            "--dialect {:?}: expected one of {}",
            args.dialect,
            Dialect::NAMES
        ))
    })?;
    if let Some(log) = &args.log {
        refuse_foreign_log(log)?;
    }
    let printer = FakePrinter::spawn(FakeConfig {
        firmware: FirmwareConfig {
            faults,
            heat_tick: Duration::from_secs_f64(args.heat_tick),
            dialect,
            ..FirmwareConfig::default()
        },
        baud: args.baud,
        exit_on_disconnect: true,
        log: args.log.clone(),
    })
    .context("fake printer")?;
    let mut out = std::io::stdout();
    if global.json {
        // stdout holds the one JSON object; the path a host needs goes to stderr.
        eprintln!("fake printer on {}", printer.path());
    } else {
        writeln!(out, "{}", printer.path())?;
        out.flush()?;
    }
    if !global.quiet && !global.json {
        eprintln!(
            "fake printer on {}; try: isoforge print FILE.gcode --port {}",
            printer.path(),
            printer.path()
        );
    }
    // A signal stops the printer the way a disconnect does, so the log is written.
    let signals = crate::signals::take();
    let stop = printer.stop_handle();
    while printer.is_running() {
        if let Some(signal) = signals.recv_timeout(Duration::from_millis(100)) {
            if !global.quiet && !global.json {
                eprintln!("fake printer: {}, stopping", crate::signals::name(signal));
            }
            stop.stop();
        }
    }
    // The printer thread has ended here, so every injected fault is counted.
    let summary = serde_json::json!({
        "port": printer.path(),
        "dialect": args.dialect,
        "executed": printer.executed().len(),
        "faults": printer.fault_counts(),
        "emergency": printer.emergency_counts(),
    });
    printer.wait().context("fake printer")?;
    if global.json {
        writeln!(out, "{summary}")?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The fake printer has no input file, so it cannot see that `--log` names the G-code a host
/// is printing. It refuses instead to replace a file that is not one of its own logs: a
/// non-empty regular file whose first line is neither `LINE<TAB>COMMAND` nor `# faults ...`.
fn refuse_foreign_log(path: &Path) -> Result<()> {
    // Only regular files: opening a FIFO to look would wait for a writer.
    let is_file = std::fs::metadata(path).is_ok_and(|m| m.is_file());
    if !is_file {
        return Ok(());
    }
    let file = std::fs::File::open(path).with_context(|| format!("--log {}", path.display()))?;
    let mut first = Vec::new();
    BufReader::new(file.take(4096))
        .read_until(b'\n', &mut first)
        .with_context(|| format!("--log {}", path.display()))?;
    let text = String::from_utf8_lossy(&first);
    let line = text.trim_end_matches(['\n', '\r']);
    let ours = line
        .split_once('\t')
        .is_some_and(|(n, _)| n == "-" || (!n.is_empty() && n.bytes().all(|b| b.is_ascii_digit())));
    // A log of a session that executed nothing holds only its `# emergency` and `# faults`
    // lines.
    let ours = ours || line.starts_with("# faults") || line.starts_with("# emergency");
    if first.is_empty() || ours {
        return Ok(());
    }
    let shown: String = line.chars().take(60).collect();
    bail!(
        "--log {}: the file exists and is not a fake-printer log (it starts {shown:?}); \
         refusing to replace it, give a new file",
        path.display()
    )
}
