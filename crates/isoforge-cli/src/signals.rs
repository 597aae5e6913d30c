//! What SIGINT, SIGTERM and SIGHUP do.
//!
//! By default a signal ends the command as a failure: the temporary files of outputs not yet
//! committed are removed (`isoforge-output` keeps the list), a message says which signal, and
//! the exit status is 1. Whatever stood at the output paths is left as it was.
//!
//! A command that must stop in order takes the signals while it runs ([`take`]): `print`
//! cancels the job (heaters and motors off) or, for Ctrl-C on a terminal, pauses and asks;
//! `fake-printer` stops and writes its log. Signals are read on a thread of their own
//! (signal-hook's iterator), so what they trigger is ordinary code, not a signal handler.

use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Mutex, PoisonError};
use std::time::Duration;

use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

/// The command that takes the signals now, if any.
static TAKER: Mutex<Option<Sender<i32>>> = Mutex::new(None);

/// Starts listening for the signals. Called once, first thing in `main`.
pub fn install() -> std::io::Result<()> {
    let mut signals = Signals::new([SIGINT, SIGTERM, SIGHUP])?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                let taken = TAKER
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .as_ref()
                    .is_some_and(|tx| tx.send(signal).is_ok());
                if !taken {
                    end(signal);
                }
            }
        })?;
    Ok(())
}

/// Removes unfinished outputs and exits with status 1.
fn end(signal: i32) -> ! {
    let removed = isoforge_output::remove_temp_files();
    let what = if removed > 0 {
        "; the unfinished output was removed"
    } else {
        ""
    };
    eprintln!("error: interrupted by {}{what}", name(signal));
    std::process::exit(1);
}

/// The usual name of a signal.
pub fn name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "a signal",
    }
}

/// Signals go to this command while it lives, instead of ending the process.
pub struct Taken {
    receiver: Receiver<i32>,
}

impl Taken {
    /// The next signal, if one comes within `timeout`.
    pub fn recv_timeout(&self, timeout: Duration) -> Option<i32> {
        self.receiver.recv_timeout(timeout).ok()
    }
}

impl Drop for Taken {
    fn drop(&mut self) {
        *TAKER.lock().unwrap_or_else(PoisonError::into_inner) = None;
    }
}

/// Takes the signals until the returned value is dropped.
pub fn take() -> Taken {
    let (tx, receiver) = mpsc::channel();
    *TAKER.lock().unwrap_or_else(PoisonError::into_inner) = Some(tx);
    Taken { receiver }
}
