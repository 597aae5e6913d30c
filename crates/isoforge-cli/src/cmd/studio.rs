//! `isoforge studio`: the local web page to edit, preview, slice and print a model.

use std::net::IpAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;
use isoforge_studio::{Options, Studio, StudioError};

use crate::common::{Global, usage};

/// Arguments of `isoforge studio`.
#[derive(Args, Debug)]
#[command(
    about = "Serve a local web page to edit, preview, slice and print a model",
    after_help = "Serves the studio on 127.0.0.1 and prints its address on the first line of \
stdout; the address carries a random access token (requests without it are refused), so \
other users of the machine and other web pages in your browser cannot use it. Open it in a \
browser: edit the script (Ctrl+S saves), move the sliders of its param(..)s, turn the 3D \
view, export STL/3MF/G-code/SL1, slice and scrub the layers, and print to a serial port or \
to a fake printer the page starts. The studio reads and writes only the model's folder. \
Ctrl-C stops it (a running print is cancelled: heaters and motors off).\n\nExample:\n  \
isoforge studio fixtures/classic/heart.rhai"
)]
pub struct StudioArgs {
    /// The model script (.rhai or .vm), or a folder (its first model is opened). Default:
    /// the current folder.
    #[arg(value_name = "MODEL", default_value = ".")]
    pub model: PathBuf,
    /// Port to listen on (0: any free port).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub port: u16,
    /// Address to listen on. Anything but loopback needs --allow-remote.
    #[arg(long, value_name = "ADDR", default_value = "127.0.0.1")]
    pub host: IpAddr,
    /// Allow a non-loopback --host: anyone who reaches it and learns the token can drive
    /// the printer and write into the model's folder.
    #[arg(long)]
    pub allow_remote: bool,
}

/// Runs the command.
pub fn run(args: StudioArgs, global: &Global) -> Result<ExitCode> {
    let options = Options {
        model: args.model.clone(),
        host: args.host,
        port: args.port,
        allow_remote: args.allow_remote,
    };
    let studio = match Studio::bind(options) {
        Ok(s) => s,
        Err(e @ StudioError::RemoteRefused(_)) => return Err(usage(e.to_string())),
        Err(e) => return Err(e).context("isoforge studio"),
    };
    if !args.host.is_loopback() && !global.quiet {
        eprintln!(
            "warning: listening on {} (not loopback): anyone who reaches this address and \
             learns the token can use your printer and write into the model's folder",
            args.host
        );
    }
    println!("{}", studio.url());
    if !global.quiet && !global.json {
        eprintln!("isoforge studio: open the address above in a browser; Ctrl-C stops it");
    }
    // A signal stops the server the orderly way, so a running print is cancelled.
    let signals = crate::signals::take();
    let stop = studio.stop_handle();
    std::thread::Builder::new()
        .name("studio-signals".into())
        .spawn(move || {
            loop {
                if signals.recv_timeout(Duration::from_millis(200)).is_some() {
                    stop.stop();
                    return;
                }
            }
        })
        .context("cannot start the signal thread")?;
    studio.serve().context("isoforge studio")?;
    Ok(ExitCode::SUCCESS)
}
