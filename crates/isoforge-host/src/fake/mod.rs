//! A fake Marlin-style printer on a pseudo-terminal, so the host can be tried and tested
//! without hardware.
//!
//! [`FakePrinter::spawn`] opens a pty pair, runs the `Firmware` model on a thread behind the
//! master end, and gives the slave's path for a host to open like any serial port. With a
//! baud rate, bytes cross the "wire" no faster than a real link would carry them (10 bits a
//! byte), in both directions. It speaks the [`Dialect`](crate::dialect::Dialect) of the
//! firmware family it is set to, and counts the faults it injects ([`FaultCounts`]).

mod faults;
mod firmware;

use std::collections::VecDeque;
use std::io::{self, BufWriter, Read, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use isoforge_output::{Options, OutputError, OutputFile};
use serialport::{SerialPort, TTYPort};
use thiserror::Error;

#[cfg(test)]
pub(crate) use faults::Rng;
pub use faults::{FAULTS_HELP, FaultCounts, Faults, FaultsError};
pub(crate) use firmware::Firmware;
pub use firmware::{EmergencyCounts, Executed, FirmwareConfig};

/// How to run the fake printer.
#[derive(Clone, Debug, Default)]
pub struct FakeConfig {
    /// The firmware model's settings and faults.
    pub firmware: FirmwareConfig,
    /// Limit the link to this baud rate's byte speed; `None` moves bytes instantly.
    pub baud: Option<u32>,
    /// Stop when the host closes the port (the CLI does); otherwise keep serving, so a host
    /// can reconnect (tests of `--resume` do).
    pub exit_on_disconnect: bool,
    /// Record every executed command in this file (`<line>\t<command>`, `-` for
    /// unnumbered), then `# emergency <counts>` (what `M112`/`M108` did) and a last line
    /// `# faults <counts>`. Written through
    /// `isoforge-output`: it appears whole when the printer stops (a FIFO or terminal gets
    /// each line as it runs).
    pub log: Option<PathBuf>,
}

/// The fake printer could not start.
#[derive(Debug, Error)]
pub enum FakeError {
    /// The pseudo-terminal could not be opened.
    #[error("cannot open a pseudo-terminal: {0}")]
    Pty(#[from] serialport::Error),
    /// The log file could not be created.
    #[error("{source}")]
    Log {
        /// The file.
        path: String,
        /// Why (the message names the file).
        source: OutputError,
    },
}

/// A running fake printer.
pub struct FakePrinter {
    path: String,
    stop: Arc<AtomicBool>,
    executed: Arc<Mutex<Vec<Executed>>>,
    counts: Arc<Mutex<FaultCounts>>,
    emergency: Arc<Mutex<EmergencyCounts>>,
    thread: Option<JoinHandle<io::Result<()>>>,
}

impl FakePrinter {
    /// Starts the fake printer on a new pseudo-terminal.
    pub fn spawn(cfg: FakeConfig) -> Result<FakePrinter, FakeError> {
        let (master, slave) = TTYPort::pair()?;
        let path = slave.name().ok_or_else(|| {
            serialport::Error::new(serialport::ErrorKind::Unknown, "pty has no name")
        })?;
        let log = match &cfg.log {
            Some(p) => Some(BufWriter::new(
                OutputFile::prepare(p, Options::default()).map_err(|source| FakeError::Log {
                    path: p.display().to_string(),
                    source,
                })?,
            )),
            None => None,
        };
        let stop = Arc::new(AtomicBool::new(false));
        let executed = Arc::new(Mutex::new(Vec::new()));
        let counts = Arc::new(Mutex::new(FaultCounts::default()));
        let emergency = Arc::new(Mutex::new(EmergencyCounts::default()));
        let link = Link {
            counts: counts.clone(),
            emergency: emergency.clone(),
            master,
            slave: Some(slave),
            firmware: Firmware::new(cfg.firmware.clone()),
            byte_time: cfg
                .baud
                .filter(|&b| b > 0)
                .map(|b| Duration::from_secs_f64(10.0 / f64::from(b))),
            exit_on_disconnect: cfg.exit_on_disconnect,
            log,
            stop: stop.clone(),
            executed: executed.clone(),
        };
        let thread = std::thread::Builder::new()
            .name("fake-printer".into())
            .spawn(move || link.run())
            .map_err(|e| serialport::Error::new(serialport::ErrorKind::Unknown, e.to_string()))?;
        Ok(FakePrinter {
            path,
            stop,
            executed,
            counts,
            emergency,
            thread: Some(thread),
        })
    }

    /// The device path a host opens (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// Every command executed so far, in order.
    pub fn executed(&self) -> Vec<Executed> {
        self.executed
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// The faults injected so far.
    pub fn fault_counts(&self) -> FaultCounts {
        *self.counts.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// What the emergency parser acted on so far (`M112` halts, `M108` ended waits).
    pub fn emergency_counts(&self) -> EmergencyCounts {
        *self
            .emergency
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// A handle that stops the printer from another thread (a signal handler), after which
    /// [`wait`](Self::wait) returns with the log written.
    pub fn stop_handle(&self) -> StopHandle {
        StopHandle(self.stop.clone())
    }

    /// True while the printer thread runs.
    pub fn is_running(&self) -> bool {
        self.thread.as_ref().is_some_and(|t| !t.is_finished())
    }

    /// Waits until the printer stops (the host disconnected, with `exit_on_disconnect`).
    pub fn wait(mut self) -> io::Result<()> {
        match self.thread.take() {
            Some(t) => t
                .join()
                .unwrap_or_else(|_| Err(io::Error::other("fake printer panicked"))),
            None => Ok(()),
        }
    }
}

impl Drop for FakePrinter {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Stops a fake printer from another thread.
#[derive(Clone, Debug)]
pub struct StopHandle(Arc<AtomicBool>);

impl StopHandle {
    /// Asks the printer to stop; it finishes within [`IDLE_WAKE`].
    pub fn stop(&self) {
        self.0.store(true, Ordering::Relaxed);
    }
}

/// The firmware model behind the pty master, with the wire's timing.
struct Link {
    master: TTYPort,
    /// The pair's own slave end, held so the pty stays usable until a host opens it; it is
    /// never read (a second reader would steal the host's bytes).
    slave: Option<TTYPort>,
    firmware: Firmware,
    byte_time: Option<Duration>,
    exit_on_disconnect: bool,
    log: Option<BufWriter<OutputFile>>,
    stop: Arc<AtomicBool>,
    executed: Arc<Mutex<Vec<Executed>>>,
    counts: Arc<Mutex<FaultCounts>>,
    emergency: Arc<Mutex<EmergencyCounts>>,
}

/// Longest the loop sleeps with nothing scheduled, so `stop` is noticed promptly.
const IDLE_WAKE: Duration = Duration::from_millis(20);

impl Link {
    /// Serves until stopped or disconnected, then puts the log in place: the commands that
    /// ran are worth keeping even when the link failed.
    fn run(mut self) -> io::Result<()> {
        let served = self.serve();
        let counts = self.firmware.fault_counts();
        *self.counts.lock().unwrap_or_else(PoisonError::into_inner) = counts;
        let emergency = self.firmware.emergency_counts();
        *self
            .emergency
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = emergency;
        let logged = match self.log.take() {
            Some(mut log) => writeln!(log, "# emergency {emergency}")
                .and_then(|()| writeln!(log, "# faults {counts}"))
                .and_then(|()| log.into_inner().map_err(io::IntoInnerError::into_error))
                .and_then(|out| out.commit().map_err(io::Error::from)),
            None => Ok(()),
        };
        served.and(logged)
    }

    fn serve(&mut self) -> io::Result<()> {
        // Bytes on their way to the firmware, each with the time its last bit arrives.
        let mut inbound: VecDeque<(Instant, Vec<u8>)> = VecDeque::new();
        let mut outbound: VecDeque<(Instant, Vec<u8>)> = VecDeque::new();
        let mut in_free = Instant::now();
        let mut out_free = Instant::now();
        let mut buf = [0u8; 4096];
        let mut write_now: Vec<u8> = Vec::new();
        while !self.stop.load(Ordering::Relaxed) {
            let now = Instant::now();
            while inbound.front().is_some_and(|(t, _)| *t <= now) {
                if let Some((_, bytes)) = inbound.pop_front() {
                    self.firmware.receive(&bytes);
                }
            }
            let mut busy = false;
            for _ in 0..64 {
                if !self.firmware.step(now) {
                    break;
                }
                busy = true;
            }
            self.record()?;
            while let Some(line) = self.firmware.take_output() {
                let mut bytes = line.into_bytes();
                bytes.push(b'\n');
                match self.byte_time {
                    None => write_now.extend_from_slice(&bytes),
                    Some(bt) => {
                        let done = out_free.max(now) + bt * bytes.len() as u32;
                        out_free = done;
                        outbound.push_back((done, bytes));
                    }
                }
            }
            while outbound.front().is_some_and(|(t, _)| *t <= now) {
                if let Some((_, bytes)) = outbound.pop_front() {
                    write_now.extend_from_slice(&bytes);
                }
            }
            if !write_now.is_empty() {
                match self.master.write_all(&write_now) {
                    Ok(()) => {}
                    Err(e) if is_disconnect(&e) && !self.exit_on_disconnect => {}
                    Err(e) if is_disconnect(&e) => return self.deliver_in_flight(inbound),
                    Err(e) => return Err(e),
                }
                write_now.clear();
            }
            let mut wake = now + IDLE_WAKE;
            if busy {
                wake = now;
            }
            for t in [
                self.firmware.next_deadline(),
                inbound.front().map(|(t, _)| *t),
                outbound.front().map(|(t, _)| *t),
            ]
            .into_iter()
            .flatten()
            {
                wake = wake.min(t);
            }
            let _ = self.master.set_timeout(wake.saturating_duration_since(now));
            match self.master.read(&mut buf) {
                Ok(0) => {}
                Ok(n) => {
                    if self.exit_on_disconnect {
                        // A host is here: from now on, its closing the port ends the session.
                        self.slave = None;
                    }
                    let bytes = &buf[..n];
                    match self.byte_time {
                        None => self.firmware.receive(bytes),
                        Some(bt) => {
                            // One chunk per line, due when its last byte has crossed the wire.
                            let at = Instant::now();
                            for piece in bytes.split_inclusive(|&b| b == b'\n') {
                                let done = in_free.max(at) + bt * piece.len() as u32;
                                in_free = done;
                                inbound.push_back((done, piece.to_vec()));
                            }
                        }
                    }
                }
                Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                Err(e) if is_disconnect(&e) => {
                    if self.exit_on_disconnect && self.slave.is_none() {
                        return self.deliver_in_flight(inbound);
                    }
                    // No host yet (or between hosts): wait for the next one.
                    std::thread::sleep(Duration::from_millis(5));
                }
                Err(e) => return Err(e),
            }
        }
        self.record()
    }

    /// The host hung up. What it wrote is still on the wire and reaches the printer (a real
    /// board gets the bytes after the host has closed the port: an `M112` sent just before
    /// closing still halts it), so those bytes are delivered and acted on, then recorded.
    fn deliver_in_flight(&mut self, inbound: VecDeque<(Instant, Vec<u8>)>) -> io::Result<()> {
        for (_, bytes) in inbound {
            self.firmware.receive(&bytes);
        }
        let now = Instant::now();
        // Bounded: the queue and the receive ring hold a few commands, not a job.
        for _ in 0..1024 {
            if !self.firmware.step(now) {
                break;
            }
        }
        self.record()
    }

    fn record(&mut self) -> io::Result<()> {
        *self.counts.lock().unwrap_or_else(PoisonError::into_inner) = self.firmware.fault_counts();
        *self
            .emergency
            .lock()
            .unwrap_or_else(PoisonError::into_inner) = self.firmware.emergency_counts();
        let new = self.firmware.take_executed();
        if new.is_empty() {
            return Ok(());
        }
        if let Some(log) = &mut self.log {
            for e in &new {
                match e.line {
                    Some(n) => writeln!(log, "{n}\t{}", e.command)?,
                    None => writeln!(log, "-\t{}", e.command)?,
                }
            }
            log.flush()?;
        }
        self.executed
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .extend(new);
        Ok(())
    }
}

/// EIO on the master means every slave descriptor is closed: the host went away.
fn is_disconnect(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::BrokenPipe | io::ErrorKind::UnexpectedEof
    ) || e.raw_os_error() == Some(5)
}
