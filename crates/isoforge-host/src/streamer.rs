//! Drives the protocol state machine over a serial port: connect, stream, report progress, pause,
//! resume, cancel, and keep the journal.

use std::collections::VecDeque;
use std::io;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::{Duration, Instant};

use serialport::{ClearBuffer, SerialPort};
use thiserror::Error;

use crate::gcode::{Command, Program};
use crate::journal::{Journal, JournalError, JournalRecord, Status};
use crate::protocol::{Config, Event, Output, Protocol, ProtocolError, Temperatures};
use crate::state::{self, MachineState};
use isoforge_gcode::Machine;

/// Longest the loop blocks in a read, so pause and cancel requests are seen promptly.
const CONTROL_POLL: Duration = Duration::from_millis(50);
/// How often progress is reported when nothing else happens (ETA and temperatures move).
const PROGRESS_EVERY: Duration = Duration::from_millis(200);

/// Requests from another thread (a Ctrl-C handler, a UI).
#[derive(Clone, Debug, Default)]
pub struct Control(Arc<AtomicU8>);

const RUN: u8 = 0;
const PAUSE: u8 = 1;
const CANCEL: u8 = 2;
const EMERGENCY: u8 = 3;

impl Control {
    /// A fresh control, in the running state.
    pub fn new() -> Control {
        Control::default()
    }

    /// Stop sending new commands (those in flight complete).
    pub fn pause(&self) {
        let _ = self
            .0
            .compare_exchange(RUN, PAUSE, Ordering::SeqCst, Ordering::SeqCst);
    }

    /// Carry on after a pause.
    pub fn resume(&self) {
        let _ = self
            .0
            .compare_exchange(PAUSE, RUN, Ordering::SeqCst, Ordering::SeqCst);
    }

    /// Cancel: stop sending, heaters off, motors off.
    pub fn cancel(&self) {
        self.0.fetch_max(CANCEL, Ordering::SeqCst);
    }

    /// Cancel with `M112` (emergency stop) instead of the orderly shutdown.
    pub fn emergency(&self) {
        self.0.store(EMERGENCY, Ordering::SeqCst);
    }

    fn get(&self) -> u8 {
        self.0.load(Ordering::SeqCst)
    }
}

/// A job to stream.
pub struct Job<'a> {
    /// The whole file's commands and layers.
    pub program: &'a Program,
    /// The first command of the file to send.
    pub start: usize,
    /// Commands sent before `start` (a resume's heat-up and moves).
    pub prelude: Vec<String>,
    /// The journal to keep, with its initial record.
    pub journal: Option<(PathBuf, JournalRecord)>,
}

/// Where the job is, for a progress display.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Progress {
    /// File commands known executed.
    pub executed: usize,
    /// File commands in all.
    pub total: usize,
    /// Percentage of the file done.
    pub percent: f64,
    /// The current layer.
    pub layer: Option<u32>,
    /// Its height.
    pub z: Option<f64>,
    /// Estimated time left, from the recent rate.
    pub eta: Option<Duration>,
    /// The last temperatures reported.
    pub temps: Option<Temperatures>,
    /// True while paused.
    pub paused: bool,
}

/// What the streamer tells its caller as it goes.
#[derive(Debug)]
pub enum Update<'a> {
    /// Progress moved (or time passed).
    Progress(&'a Progress),
    /// Something the protocol reported.
    Event(&'a Event),
}

/// How a job ended.
#[derive(Debug, Error)]
pub enum StreamError {
    /// The protocol stopped the job.
    #[error(transparent)]
    Protocol(#[from] ProtocolError),
    /// The port failed.
    #[error("serial port: {0}")]
    Port(#[from] io::Error),
    /// The journal could not be written.
    #[error(transparent)]
    Journal(#[from] JournalError),
}

/// The summary of a job.
#[derive(Debug)]
pub struct Report {
    /// Numbered lines written, resends included.
    pub lines_sent: u64,
    /// Resend requests acted on.
    pub resends: u64,
    /// Numbered `M105` probes sent (each executes once, like any numbered line).
    pub probes: u64,
    /// `M110` renumberings after resend episodes.
    pub renumbers: u64,
    /// Wall time, seconds.
    pub seconds: f64,
    /// Bytes written.
    pub bytes_sent: u64,
    /// True when every command of the file executed.
    pub completed: bool,
    /// True when the job was cancelled.
    pub cancelled: bool,
    /// File commands known executed.
    pub executed: usize,
    /// Why the job stopped early, if it did.
    pub error: Option<StreamError>,
}

/// Opens a serial port for printing (8N1, no flow control).
pub fn open_port(path: &str, baud: u32) -> Result<Box<dyn SerialPort>, serialport::Error> {
    serialport::new(path, baud).timeout(CONTROL_POLL).open()
}

struct Tracker<'a> {
    program: &'a Program,
    start: usize,
    prelude: usize,
    /// Job commands applied to `state`.
    applied: usize,
    machine: Machine,
    rate: VecDeque<(Instant, usize)>,
    progress: Progress,
}

impl<'a> Tracker<'a> {
    /// File commands executed when the first `job_executed` job commands are.
    fn file_executed(&self, job_executed: usize) -> usize {
        self.start + job_executed.saturating_sub(self.prelude)
    }

    fn advance(&mut self, job_executed: usize, job: &Protocol, now: Instant) {
        // A cancel sequence is not part of the job's state or progress.
        let job_executed = job_executed.min(job.original_len());
        if job_executed < self.applied {
            // The printer's counter moved us back: recompute from the file.
            let upto = self.file_executed(job_executed);
            self.machine = MachineState::replay(
                self.program.commands[..upto]
                    .iter()
                    .map(|c| c.text.as_str()),
            )
            .machine();
            self.applied = job_executed;
        }
        while self.applied < job_executed {
            if let Some(c) = job.command(self.applied) {
                state::apply(&mut self.machine, &c.text);
            }
            self.applied += 1;
        }
        let executed = self
            .file_executed(job_executed)
            .min(self.program.commands.len());
        let p = &mut self.progress;
        p.executed = executed;
        p.percent = if p.total == 0 {
            100.0
        } else {
            100.0 * executed as f64 / p.total as f64
        };
        if let Some(layer) = self.program.layer_of(executed.saturating_sub(1)) {
            p.layer = Some(layer.number);
            p.z = layer.z.or(self.machine.position[2]);
        } else {
            p.z = self.machine.position[2];
        }
        self.rate.push_back((now, executed));
        while self.rate.len() > 2
            && self
                .rate
                .front()
                .is_some_and(|(t, _)| now.duration_since(*t) > Duration::from_secs(30))
        {
            self.rate.pop_front();
        }
        p.eta = match (self.rate.front(), self.rate.back()) {
            (Some(&(t0, e0)), Some(&(t1, e1))) if e1 > e0 && t1 > t0 => {
                let per_cmd = t1.duration_since(t0).as_secs_f64() / (e1 - e0) as f64;
                Some(Duration::from_secs_f64(
                    per_cmd * (p.total - executed) as f64,
                ))
            }
            _ => None,
        };
    }
}

/// Streams a job over an open port until it completes, fails or is cancelled.
pub fn stream(
    port: &mut dyn SerialPort,
    job: Job<'_>,
    cfg: Config,
    control: &Control,
    mut on_update: impl FnMut(Update<'_>),
) -> Report {
    let started = Instant::now();
    let prelude_len = job.prelude.len();
    let mut commands: Vec<Command> = job
        .prelude
        .iter()
        .map(|t| Command {
            text: t.clone(),
            source_line: 0,
        })
        .collect();
    commands.extend(job.program.commands[job.start..].iter().cloned());
    let mut proto = Protocol::new(commands, cfg, started);
    let mut tracker = Tracker {
        program: job.program,
        start: job.start,
        prelude: prelude_len,
        applied: 0,
        machine: Machine::default(),
        rate: VecDeque::new(),
        progress: Progress {
            total: job.program.commands.len(),
            ..Progress::default()
        },
    };
    // The state the prelude restores is the state at `start`.
    tracker.machine = match &job.journal {
        Some((_, r)) if r.executed == job.start => r.state.machine(),
        _ => MachineState::replay(
            job.program.commands[..job.start]
                .iter()
                .map(|c| c.text.as_str()),
        )
        .machine(),
    };
    tracker.advance(0, &proto, started);
    let mut journal = None;
    let mut error: Option<StreamError> = None;
    if let Some((path, record)) = job.journal {
        match Journal::create(path, record) {
            Ok(j) => journal = Some(j),
            Err(e) => error = Some(e.into()),
        }
    }
    let mut finished: Option<bool> = None;
    let mut pending = Vec::new();
    let mut buf = [0u8; 4096];
    let mut last_progress = started;
    let mut seen_control = RUN;
    while error.is_none() && finished.is_none() {
        let now = Instant::now();
        let wanted = control.get();
        if wanted != seen_control {
            match wanted {
                PAUSE => proto.pause(),
                RUN => proto.resume(),
                CANCEL => proto.cancel(false),
                _ => proto.cancel(true),
            }
            seen_control = wanted;
            tracker.progress.paused = wanted == PAUSE;
            on_update(Update::Progress(&tracker.progress));
        }
        let mut out = Vec::new();
        while let Some(o) = proto.poll(now) {
            match o {
                Output::Send(line) => out.extend_from_slice(line.as_bytes()),
                Output::Event(e) => {
                    match &e {
                        Event::Progress { executed } => {
                            tracker.advance(*executed, &proto, now);
                            if let Some(j) = &mut journal {
                                let file_exec = tracker.progress.executed;
                                let src = file_exec
                                    .checked_sub(1)
                                    .and_then(|i| job.program.commands.get(i))
                                    .map_or(0, |c| c.source_line);
                                if let Err(err) = j.update(
                                    file_exec,
                                    src,
                                    tracker.progress.layer,
                                    &MachineState::of(&tracker.machine),
                                    now,
                                ) {
                                    error = Some(err.into());
                                }
                            }
                        }
                        Event::Temperatures(t) => tracker.progress.temps = Some(t.clone()),
                        Event::Paused(p) => tracker.progress.paused = *p,
                        Event::Finished { cancelled } => finished = Some(*cancelled),
                        _ => {}
                    }
                    on_update(Update::Event(&e));
                }
                Output::Failed(e) => error = Some(e.into()),
            }
        }
        if !out.is_empty() {
            port.set_timeout(Duration::from_secs(2)).ok();
            // No flush: on a tty it is tcdrain, which waits for the printer to read the
            // bytes and would turn windowed streaming back into ping-pong.
            if let Err(e) = port.write_all(&out) {
                error.get_or_insert(e.into());
            }
        }
        if now.duration_since(last_progress) >= PROGRESS_EVERY {
            last_progress = now;
            on_update(Update::Progress(&tracker.progress));
        }
        if error.is_some() || finished.is_some() {
            break;
        }
        let wait = proto
            .next_deadline()
            .map_or(CONTROL_POLL, |d| d.saturating_duration_since(now))
            .min(CONTROL_POLL);
        port.set_timeout(wait.max(Duration::from_micros(100))).ok();
        match port.read(&mut buf) {
            Ok(n) => {
                pending.extend_from_slice(&buf[..n]);
                let at = Instant::now();
                while let Some(nl) = pending.iter().position(|&b| b == b'\n') {
                    let line: Vec<u8> = pending.drain(..=nl).collect();
                    let text = String::from_utf8_lossy(&line[..line.len() - 1]);
                    proto.feed_line(&text, at);
                }
                if pending.len() > 4096 {
                    // No newline in 4 KiB: not a printer talking; keep the tail only.
                    pending.drain(..pending.len() - 256);
                }
            }
            Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => error = Some(e.into()),
        }
    }
    // Leave the port clean for whoever opens it next.
    let _ = port.flush();
    let _ = port.clear(ClearBuffer::Input);
    let stats = proto.stats();
    let completed = finished == Some(false) && error.is_none();
    let cancelled = finished == Some(true);
    if let Some(j) = &mut journal {
        let status = if completed {
            Status::Completed
        } else if cancelled {
            Status::Cancelled
        } else {
            Status::Failed
        };
        if let Err(e) = j.finish(status) {
            error.get_or_insert(e.into());
        }
    }
    tracker.progress.eta = None;
    on_update(Update::Progress(&tracker.progress));
    Report {
        lines_sent: stats.lines_sent,
        resends: stats.resends,
        probes: stats.probes,
        renumbers: stats.renumbers,
        seconds: started.elapsed().as_secs_f64(),
        bytes_sent: stats.bytes_sent,
        completed,
        cancelled,
        executed: tracker.progress.executed,
        error,
    }
}
