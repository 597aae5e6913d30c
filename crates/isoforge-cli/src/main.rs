//! `isoforge`: from a model script to a watertight mesh, layer images, G-code, and a print.
//!
//! Exit status: 0 done, 1 the work failed (message on stderr), 2 a usage error.

mod cmd;
mod common;
mod machine;
mod signals;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::common::Global;

/// Turn math into printed objects.
#[derive(Parser)]
#[command(name = "isoforge", version, about, long_about = None)]
struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Mesh a model into a closed, manifold triangle mesh (STL, OBJ, PLY, 3MF).
    Mesh(cmd::mesh::MeshArgs),
    /// Draw a shaded picture of a model.
    Render(cmd::render::RenderArgs),
    /// Check a mesh file: closed, manifold, oriented; volume, area, bounds.
    Check(cmd::check::CheckArgs),
    /// Show a model's bounds, node count, tape length and parameters.
    Info(cmd::info::InfoArgs),
    /// Slice a model or mesh into G-code, SL1, SVX or layer PNGs.
    Slice(cmd::slice::SliceArgs),
    /// Stream G-code to a printer over a serial port.
    Print(cmd::print::PrintArgs),
    /// Run a simulated Marlin-style printer on a pseudo-terminal.
    FakePrinter(cmd::fake_printer::FakePrinterArgs),
    /// Serve a local web page to edit, preview, slice and print a model.
    Studio(cmd::studio::StudioArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    let global = cli.global;
    if let Err(e) = signals::install()
        && !global.quiet
    {
        eprintln!("warning: signals will end isoforge without cleaning up: {e}");
    }
    // A script's print() is chatter: `--quiet` silences it (it goes to stderr, never stdout).
    isoforge_script::echo_prints(!global.quiet);
    let result = match cli.command {
        Command::Mesh(args) => cmd::mesh::run(args, &global),
        Command::Render(args) => cmd::render::run(args, &global),
        Command::Check(args) => cmd::check::run(args, &global),
        Command::Info(args) => cmd::info::run(args, &global),
        Command::Slice(args) => cmd::slice::run(args, &global),
        Command::Print(args) => cmd::print::run(args, &global),
        Command::FakePrinter(args) => cmd::fake_printer::run(args, &global),
        Command::Studio(args) => cmd::studio::run(args, &global),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            let message = error_message(&err);
            let code = exit_code(&err);
            if global.json && !common::json_printed() {
                common::print_json(&serde_json::json!({ "error": message, "exit_code": code }));
            }
            eprintln!("error: {message}");
            ExitCode::from(code)
        }
    }
}

/// A command line clap could not parse: clap's own message and exit status (2; 0 for
/// `--help` and `--version`), and with `--json` anywhere in it, the one JSON object too.
fn usage_error(e: clap::Error) -> ExitCode {
    let code = e.exit_code();
    let wants_json = std::env::args_os().any(|a| a == "--json");
    if wants_json && code != 0 {
        let text = e.render().to_string();
        let first = text.lines().next().unwrap_or("usage error");
        let message = first.strip_prefix("error: ").unwrap_or(first);
        common::print_json(&serde_json::json!({ "error": message, "exit_code": code }));
    }
    let _ = e.print();
    ExitCode::from(u8::try_from(code).unwrap_or(2))
}

/// The error and its causes, joined with ": ", leaving out a cause whose text the message
/// already holds (an error that prints its source and also returns it as `source()` would
/// otherwise say the same thing twice).
fn error_message(err: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if message.contains(&text) {
            continue;
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    message
}

/// 2 for a usage error anywhere in the chain (see [`common::UsageError`]), else 1.
fn exit_code(err: &anyhow::Error) -> u8 {
    let usage = err
        .chain()
        .any(|cause| cause.downcast_ref::<common::UsageError>().is_some());
    if usage { 2 } else { 1 }
}
