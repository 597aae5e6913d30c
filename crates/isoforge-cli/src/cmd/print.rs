//! `isoforge print`: stream G-code to a printer over a serial port.

use std::io::{BufRead, IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use isoforge_host::gcode;
use isoforge_host::journal::{self, JournalError, JournalRecord, Status};
use isoforge_host::protocol::{Config, Event};
use isoforge_host::state::MachineState;
use isoforge_host::streamer::{self, Control, Job, Progress, Update};
use isoforge_output::{Durability, Options, Streams, check_file};
use signal_hook::consts::SIGINT;

use crate::common::{Global, print_json, usage};

/// Arguments of `isoforge print`.
#[derive(Args, Debug)]
#[command(
    about = "Stream G-code to a printer over a serial port",
    after_help = "Streams a G-code file to a RepRap/Marlin-style printer: comments stripped, each \
line sent as `N<n> <command>*<checksum>` (lines over Marlin's 95 bytes are refused before \
printing starts), up to --window commands and --rx-buffer bytes in flight (or the firmware's own \
count with ADVANCED_OK), resend requests answered from a history, busy and heating waited through, \
silence probed with M105 and reported, a board reset (`start`) or `Error:` stopping the job.\n\n\
A progress bar shows percent, layer, Z, ETA and temperatures on a terminal. Ctrl-C pauses and asks \
to resume or cancel (cancel stops sending, then heaters off M104 S0/M140 S0 and motors off M84; \
--emergency sends M112 instead); when stdin is not a terminal Ctrl-C cancels, and SIGTERM or SIGHUP \
always cancel that way.\n\n\
The journal (FILE.journal unless --journal) records the last acknowledged line durably. After a \
crash, cable pull or reset, `--resume` re-heats to the last targets, restores G90/G91 and M82/M83, \
sets E with G92, lifts, homes X and Y, returns to the last position and continues from the first \
line not known to be executed (or, with --from-layer N, from a layer start); it prints what it will \
do first. A new print does not overwrite the journal of an unfinished job: it says how to \
resume, and --restart starts over.\n\nTry it without a printer:\n  isoforge fake-printer &   # prints /dev/pts/N\n  isoforge \
print part.gcode --port /dev/pts/N"
)]
pub struct PrintArgs {
    /// The G-code file.
    pub file: PathBuf,
    /// The printer's serial port (/dev/ttyUSB0, /dev/ttyACM0, or a fake printer's pty).
    #[arg(long, value_name = "PATH")]
    pub port: String,
    /// Baud rate.
    #[arg(long, value_name = "N", default_value_t = 115_200)]
    pub baud: u32,
    /// The job journal (default: FILE.journal beside the G-code).
    #[arg(long, value_name = "FILE")]
    pub journal: Option<PathBuf>,
    /// Keep no journal.
    #[arg(long, conflicts_with_all = ["journal", "resume"])]
    pub no_journal: bool,
    /// Continue an interrupted job from its journal.
    #[arg(long)]
    pub resume: bool,
    /// Start over from the first line although the journal holds an unfinished job (its
    /// journal is then replaced).
    #[arg(long, conflicts_with_all = ["resume", "from_layer", "no_journal"])]
    pub restart: bool,
    /// Resume from the start of this layer (`;LAYER:N`, else counted from the first
    /// extruding Z), restoring the state the file had there.
    #[arg(long, value_name = "N")]
    pub from_layer: Option<u32>,
    /// Commands in flight at most (1: ping-pong); stock Marlin has 4 slots.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub window: u16,
    /// Bytes in flight at most: the firmware's receive buffer minus one.
    #[arg(long, value_name = "N", default_value_t = 127, value_parser = clap::value_parser!(u16).range(96..=65535))]
    pub rx_buffer: u16,
    /// On cancel, stop the printer at once with M112 (it then needs a reset).
    #[arg(long)]
    pub emergency: bool,
    /// Seconds of silence before probing with M105 (commands that block, like G28 and
    /// M109, wait 300 s).
    #[arg(long, value_name = "SECONDS", default_value_t = 5.0)]
    pub timeout: f64,
}

/// Runs the command.
pub fn run(args: PrintArgs, global: &Global) -> Result<ExitCode> {
    if !(0.05..=3600.0).contains(&args.timeout) {
        return Err(usage(format!(
            "--timeout {}: expected 0.05 to 3600 seconds",
            args.timeout
        )));
    }
    let bytes = isoforge_output::read_input(&args.file)
        .with_context(|| format!("{}: cannot read", args.file.display()))?;
    let program = gcode::parse(&String::from_utf8_lossy(&bytes))
        .with_context(|| format!("{}", args.file.display()))?;
    if !global.quiet {
        // The host owns line numbering: an M110 of the file is left out, and said so.
        for d in &program.dropped {
            eprintln!(
                "warning: {}: line {}: `{}` not sent: {}",
                args.file.display(),
                d.line,
                d.text,
                d.why
            );
        }
    }
    let fingerprint = journal::fingerprint(&bytes);
    let journal_path = args
        .journal
        .clone()
        .unwrap_or_else(|| journal::default_path(&args.file));
    if !args.no_journal {
        // Before anything is sent: a journal that is the G-code itself (or a FIFO, a
        // read-only file, a missing folder) is refused now, not at the first write.
        check_file(
            &journal_path,
            Options {
                inputs: &[&args.file],
                durability: Durability::Sync,
                streams: Streams::Refuse,
            },
        )
        .context("the job journal")?;
    }

    let (start, prelude, state) = if args.resume || args.from_layer.is_some() {
        let record = if args.resume && !args.no_journal {
            Some(JournalRecord::load(&journal_path).with_context(|| {
                "--resume needs the journal of an earlier run (or use --from-layer N)".to_string()
            })?)
        } else {
            None
        };
        let plan = journal::plan_resume(&program, fingerprint, record.as_ref(), args.from_layer)
            .map_err(|e| journal_error(e, &args))?;
        if !global.quiet {
            eprint!("{}", plan.summary);
        }
        (plan.start, plan.prelude, plan.state)
    } else {
        (0, Vec::new(), MachineState::default())
    };

    // A fresh start must not replace what should be kept: the journal of an unfinished job
    // (it could still be resumed) or a file that is not a journal at all.
    if !args.no_journal && !args.resume && args.from_layer.is_none() {
        journal::check_can_start(&journal_path, args.restart)
            .map_err(|e| journal_error(e, &args))?;
    }

    let journal = (!args.no_journal).then(|| {
        let source_line = start
            .checked_sub(1)
            .and_then(|i| program.commands.get(i))
            .map_or(0, |c| c.source_line);
        let record = JournalRecord {
            gcode: args.file.display().to_string(),
            fingerprint,
            total: program.commands.len(),
            executed: start,
            source_line,
            layer: start
                .checked_sub(1)
                .and_then(|i| program.layer_of(i))
                .map(|l| l.number),
            state,
            status: Status::Running,
        };
        (journal_path.clone(), record)
    });

    let mut port = streamer::open_port(&args.port, args.baud)
        .with_context(|| format!("cannot open the serial port {}", args.port))?;
    let cfg = Config {
        window: usize::from(args.window),
        rx_buffer: usize::from(args.rx_buffer),
        timeout: Duration::from_secs_f64(args.timeout),
        ..Config::default()
    };

    let control = Control::new();
    // From here a signal must not just end the process: the printer would be left hot.
    let signals = crate::signals::take();

    let bar = if global.chatty() {
        let bar = ProgressBar::new(program.commands.len() as u64);
        if let Ok(style) = ProgressStyle::with_template("[{bar:30}] {percent:>3}% {msg}") {
            bar.set_style(style.progress_chars("=> "));
        }
        bar
    } else {
        ProgressBar::hidden()
    };
    let quiet = global.quiet || global.json;
    let say = |bar: &ProgressBar, text: &str| {
        if quiet {
        } else if bar.is_hidden() {
            eprintln!("{text}");
        } else {
            bar.println(text);
        }
    };

    let job = Job {
        program: &program,
        start,
        prelude,
        journal,
    };
    let interactive = std::io::stdin().is_terminal();
    let report = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            streamer::stream(&mut *port, job, cfg, &control, |u| match u {
                Update::Progress(p) => {
                    bar.set_position(p.executed as u64);
                    bar.set_message(describe(p));
                }
                Update::Event(Event::Warning(w)) => say(&bar, &format!("warning: {w}")),
                Update::Event(Event::Resend { .. }) => {}
                Update::Event(Event::Connected) => say(&bar, "printer connected"),
                Update::Event(Event::Paused(true)) => say(&bar, "the printer asked to pause"),
                Update::Event(Event::Paused(false)) => say(&bar, "the printer asked to resume"),
                Update::Event(_) => {}
            })
        });
        while !worker.is_finished() {
            let Some(signal) = signals.recv_timeout(Duration::from_millis(100)) else {
                continue;
            };
            // SIGTERM and SIGHUP (the terminal is gone) cancel at once, as Ctrl-C does
            // without a terminal to ask on.
            if signal != SIGINT || !interactive {
                let name = crate::signals::name(signal);
                say(
                    &bar,
                    &format!("interrupted by {name}: cancelling (heaters and motors off)"),
                );
                cancel(&control, args.emergency);
                continue;
            }
            control.pause();
            let answer = bar.suspend(|| {
                eprint!("\npaused: [r]esume or [c]ancel? ");
                let _ = std::io::stderr().flush();
                let mut line = String::new();
                match std::io::stdin().lock().read_line(&mut line) {
                    Ok(0) | Err(_) => "c".to_string(),
                    Ok(_) => line.trim().to_lowercase(),
                }
            });
            if answer.starts_with('r') {
                control.resume();
            } else {
                say(&bar, "cancelling: heaters and motors off");
                cancel(&control, args.emergency);
            }
        }
        worker.join()
    });
    let report = match report {
        Ok(r) => r,
        Err(_) => bail!("the streaming thread panicked"),
    };
    bar.finish_and_clear();

    let resume_hint = if args.no_journal {
        String::new()
    } else {
        format!(
            "; to continue: isoforge print {} --port {} --resume",
            args.file.display(),
            args.port
        )
    };
    let failure = match (&report.error, report.cancelled) {
        (Some(err), _) => Some(format!("{err}{resume_hint}")),
        (None, true) => Some(format!(
            "cancelled after {} of {} commands{resume_hint}",
            report.executed,
            program.commands.len()
        )),
        (None, false) => None,
    };
    if global.json {
        // One object, failure or not: the figures, and "error" when the job did not finish.
        let mut value = serde_json::json!({
            "lines_sent": report.lines_sent,
            "resends": report.resends,
            "seconds": report.seconds,
            "completed": report.completed,
            "cancelled": report.cancelled,
            "executed": report.executed,
            "commands": program.commands.len(),
        });
        if let Some(f) = &failure {
            value["error"] = f.clone().into();
            value["exit_code"] = 1.into();
        }
        print_json(&value);
    }
    if let Some(f) = failure {
        bail!("{f}");
    }
    if !quiet {
        eprintln!(
            "printed {} commands: {} lines sent, {} resends, {:.1} s",
            program.commands.len(),
            report.lines_sent,
            report.resends,
            report.seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// A journal error with the flags that deal with it.
fn journal_error(e: JournalError, args: &PrintArgs) -> anyhow::Error {
    let resume = format!(
        "isoforge print {} --port {} --resume",
        args.file.display(),
        args.port
    );
    match e {
        JournalError::Unfinished { .. } => {
            anyhow!("{e}; continue it with `{resume}`, or start over with --restart")
        }
        JournalError::NotAJournal { .. } => {
            anyhow!("{e}; give another --journal FILE, or remove it")
        }
        JournalError::ChangedFile { .. } | JournalError::Inconsistent { .. } => {
            anyhow!("{e}; resume with --from-layer N, or print from the start with --restart")
        }
        JournalError::NoSuchLayer { layer, .. } => anyhow!("--from-layer {layer}: {e}"),
        JournalError::NothingToResume => {
            anyhow!("--resume needs the job's journal (or --from-layer N)")
        }
        other => anyhow::Error::new(other),
    }
}

fn cancel(control: &Control, emergency: bool) {
    if emergency {
        control.emergency();
    } else {
        control.cancel();
    }
}

/// "layer 12 Z2.40 | T 200/200 B 60/60 | ETA 3m12s".
fn describe(p: &Progress) -> String {
    let mut parts = Vec::new();
    if p.paused {
        parts.push("PAUSED".to_string());
    }
    match (p.layer, p.z) {
        (Some(l), Some(z)) => parts.push(format!("layer {l} Z{z:.2}")),
        (Some(l), None) => parts.push(format!("layer {l}")),
        (None, Some(z)) => parts.push(format!("Z{z:.2}")),
        _ => {}
    }
    if let Some(t) = &p.temps {
        let mut s = Vec::new();
        for (i, r) in t.tools.iter().enumerate() {
            let name = if t.tools.len() > 1 {
                format!("T{i}")
            } else {
                "T".into()
            };
            s.push(format!(
                "{name} {:.0}/{:.0}",
                r.actual,
                r.target.unwrap_or(0.0)
            ));
        }
        if let Some(b) = t.bed {
            s.push(format!("B {:.0}/{:.0}", b.actual, b.target.unwrap_or(0.0)));
        }
        parts.push(s.join(" "));
    }
    if let Some(eta) = p.eta {
        let secs = eta.as_secs();
        parts.push(format!(
            "ETA {}h{:02}m{:02}s",
            secs / 3600,
            secs / 60 % 60,
            secs % 60
        ));
    }
    parts.join(" | ")
}
