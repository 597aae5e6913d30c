//! The RepRap/Marlin host protocol as a state machine with no I/O.
//!
//! Lines from the printer go in with `Protocol::feed_line`; lines to send and events come
//! out of `Protocol::poll`; the clock is passed in, so every timeout is testable.
//!
//! How the machine keeps "each command executed exactly once, in order":
//! - The firmware's line counter is the truth. Marlin accepts line `N` only when it is its
//!   last line + 1, so sending a line again can never execute it twice; every
//!   `Resend: N` or `Error:... Last Line: K` tells exactly what the printer has received.
//! - `ok`s free buffer slots. An `ok` printed right after a `Resend`/line `Error` belongs to
//!   the rejected line; any other `ok` is the oldest command in flight being executed (Marlin
//!   executes in order).
//! - After a resend request, lines already in flight behind the rejected one each cause one
//!   more request for the same line ("zombies"); those are ignored, and sending waits a short
//!   settle time so the zombies cannot flush the resent line out of Marlin's receive buffer.
//! - When the accounting may be wrong (an `ok` lost or garbled), the printer goes quiet. A
//!   timeout then sends `M105`: its reply comes only after every command received before it
//!   has executed. Then the oldest unconfirmed line is sent again ("resync"): the printer
//!   either executes it (it never had it) or rejects it and names its last line.

mod reply;
mod temperature;

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use thiserror::Error;

pub(crate) use reply::{HostAction, Reply};
pub use temperature::{Reading, Temperatures};

use crate::gcode::{self, Command, GcodeError};

/// Flow-control and timing settings.
#[derive(Clone, Debug)]
pub struct Config {
    /// Commands in flight at most (Marlin's `BUFSIZE` is 4; 3 leaves one slot for the
    /// firmware's own use). 1 is plain ping-pong.
    pub window: usize,
    /// Bytes in flight at most: stock Marlin's receive ring is 128 bytes and drops what does
    /// not fit.
    pub rx_buffer: usize,
    /// Silence (no `ok`, resend or busy) after which `M105` is sent to provoke an answer.
    pub timeout: Duration,
    /// The same for commands that legitimately block: G28, G29, M109, M190, M400, G4.
    pub long_timeout: Duration,
    /// Shorter silence that triggers a probe when a garbled line means an `ok` may be lost.
    pub suspect_timeout: Duration,
    /// Unanswered probes before the job stops.
    pub max_probes: u32,
    /// How long to wait after a resend request for the rest of the in-flight lines to be
    /// rejected, before sending again.
    pub resend_settle: Duration,
    /// How far back (in lines) a resend request may reach.
    pub history: u64,
    /// Requests for the same line in a row before giving up.
    pub max_same_resend: u32,
    /// How long to wait for the printer to answer at all.
    pub connect_timeout: Duration,
    /// Commands sent when a job is cancelled: heaters and motors off.
    pub shutdown: Vec<String>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            window: 3,
            rx_buffer: 127,
            // Marlin prints `busy:` every 2 s while a command blocks (HOST_KEEPALIVE), so
            // 5 s of silence means something was lost.
            timeout: Duration::from_secs(5),
            long_timeout: Duration::from_secs(300),
            suspect_timeout: Duration::from_millis(500),
            max_probes: 3,
            resend_settle: Duration::from_millis(50),
            history: 1024,
            max_same_resend: 12,
            connect_timeout: Duration::from_secs(15),
            shutdown: vec!["M104 S0".into(), "M140 S0".into(), "M84".into()],
        }
    }
}

/// Why a job stopped before its end.
#[derive(Debug, Error)]
pub enum ProtocolError {
    /// Nothing came back from the printer at all.
    #[error("no answer from the printer within {seconds:.1} s (is it on, and at this baud rate?)")]
    NoConnection {
        /// How long the host waited.
        seconds: f64,
    },
    /// The printer went quiet mid-job.
    #[error(
        "the printer stopped answering: nothing for {seconds:.1} s and {probes} M105 probes went unanswered; {last}"
    )]
    NotAnswering {
        /// Seconds of silence.
        seconds: f64,
        /// Probes sent.
        probes: u32,
        /// The last acknowledged line, in words.
        last: String,
    },
    /// The board rebooted (`start`) mid-job: whatever it had buffered is gone.
    #[error("the printer reset (it sent `start`) in the middle of the job; {last}")]
    PrinterReset {
        /// The last acknowledged line, in words.
        last: String,
    },
    /// The firmware reported an error that is not a resend request.
    #[error("the printer reported an error: {message}; {last}")]
    PrinterError {
        /// The firmware's message.
        message: String,
        /// The last acknowledged line, in words.
        last: String,
    },
    /// The printer asked for a line the host no longer has.
    #[error(
        "the printer asked for line {requested}, which is no longer in the resend history (oldest kept: {oldest}); its line counter is out of step"
    )]
    ResendOutOfHistory {
        /// The requested line number.
        requested: u64,
        /// The oldest line number still kept.
        oldest: u64,
    },
    /// The printer keeps rejecting the same line.
    #[error(
        "the printer asked for line {line} {times} times in a row; the link is too noisy or the line is refused (file line {source_line})"
    )]
    ResendLoop {
        /// The line number.
        line: u64,
        /// How many times.
        times: u32,
        /// The source line of that command (0 for host-made lines).
        source_line: usize,
    },
    /// A command could not be framed.
    #[error(transparent)]
    Frame(#[from] GcodeError),
}

/// Something the driver should know about.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// The printer answered; the job starts.
    Connected,
    /// The first `executed` job commands are known to be executed.
    Progress {
        /// Count of executed job commands (job indices `0..executed`).
        executed: usize,
    },
    /// A temperature report.
    Temperatures(Temperatures),
    /// The printer asked to resend from this line.
    Resend {
        /// The line number.
        line: u64,
    },
    /// Something odd but survivable (unknown command, garbled line, probe).
    Warning(String),
    /// Firmware chatter (echo lines).
    Message(String),
    /// The firmware asked to pause (true) or resume (false).
    Paused(bool),
    /// The job is over: every command executed, or the cancel sequence done.
    Finished {
        /// True when the job was cancelled rather than completed.
        cancelled: bool,
    },
}

/// What the driver must do next.
#[derive(Debug)]
pub(crate) enum Output {
    /// Write this line (newline included) to the port.
    Send(String),
    /// Report this.
    Event(Event),
    /// The job failed; nothing more will be sent.
    Failed(ProtocolError),
}

/// Counters for the summary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Stats {
    /// Numbered lines written (first sends and resends).
    pub lines_sent: u64,
    /// Bytes written.
    pub bytes_sent: u64,
    /// Resend requests acted on.
    pub resends: u64,
    /// M105 probes sent after silences.
    pub probes: u64,
}

#[derive(Clone, Copy, Debug)]
struct Flight {
    line: u64,
    bytes: usize,
    /// Known to be in the firmware's command queue (no longer in its receive buffer).
    received: bool,
    long: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Connecting {
        since: Instant,
        next_probe: Instant,
    },
    /// Heard `start`: let the boot chatter and answers to earlier probes pass.
    Booted {
        until: Instant,
    },
    Streaming,
    Done,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Recovery {
    None,
    /// An M105 probe is out; waiting for its `ok`.
    Probing,
    /// The oldest unconfirmed line was sent again; waiting for the verdict.
    Resyncing {
        line: u64,
    },
}

/// The host side of the protocol for one job.
pub(crate) struct Protocol {
    cfg: Config,
    /// `lines[0]` is `M110 N0`; `lines[i]` is job command `i - 1`.
    lines: Vec<Command>,
    phase: Phase,
    next: u64,
    sent_high: Option<u64>,
    in_flight: VecDeque<Flight>,
    /// Highest line number known executed.
    acked: u64,
    expect_rejection_ok: bool,
    /// The next `ok` answers a command that is not ours (a damaged probe).
    foreign_ok: bool,
    /// A probe was sent since the last resync: `ok` counts may be off.
    probed: bool,
    rejection_at: Instant,
    merge_resend: Option<u64>,
    resend_target: Option<u64>,
    dup_budget: u64,
    sent_since_resend: bool,
    same_resend: u32,
    settle_until: Option<Instant>,
    /// Settle for the whole time, even when every expected rejection has come.
    settle_full: bool,
    /// ADVANCED_OK: (last line received, free slots).
    advanced: Option<(u64, u32)>,
    last_progress: Instant,
    recovery: Recovery,
    probes_outstanding: u32,
    probes_unanswered: u32,
    suspect: bool,
    paused: bool,
    cancelled: bool,
    emergency_sent: bool,
    /// Job commands that came from the job (the rest are a cancel sequence).
    original_len: usize,
    outputs: VecDeque<Output>,
    stats: Stats,
}

/// Commands that can block the firmware for minutes.
fn is_long(cmd: &str) -> bool {
    matches!(
        gcode::code(cmd).as_str(),
        "G28" | "G29" | "M109" | "M190" | "M400" | "G4" | "M303" | "M191"
    )
}

impl Protocol {
    /// A job of `commands` (already stripped of comments), starting to connect at `now`.
    pub fn new(commands: Vec<Command>, cfg: Config, now: Instant) -> Protocol {
        let mut lines = Vec::with_capacity(commands.len() + 1);
        lines.push(Command {
            text: "M110 N0".into(),
            source_line: 0,
        });
        lines.extend(commands);
        let original_len = lines.len() - 1;
        Protocol {
            original_len,
            cfg,
            lines,
            phase: Phase::Connecting {
                since: now,
                next_probe: now,
            },
            next: 0,
            sent_high: None,
            in_flight: VecDeque::new(),
            acked: 0,
            expect_rejection_ok: false,
            foreign_ok: false,
            probed: false,
            rejection_at: now,
            merge_resend: None,
            resend_target: None,
            dup_budget: 0,
            sent_since_resend: true,
            same_resend: 0,
            settle_until: None,
            settle_full: false,
            advanced: None,
            last_progress: now,
            recovery: Recovery::None,
            probes_outstanding: 0,
            probes_unanswered: 0,
            suspect: false,
            paused: false,
            cancelled: false,
            emergency_sent: false,
            outputs: VecDeque::new(),
            stats: Stats::default(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Job commands known executed.
    #[cfg(test)]
    pub fn executed(&self) -> usize {
        self.acked as usize
    }

    /// Job commands from the job itself; after a cancel, the ones past this are the
    /// shutdown sequence.
    pub fn original_len(&self) -> usize {
        self.original_len
    }

    /// The job command at `index`.
    pub fn command(&self, index: usize) -> Option<&Command> {
        self.lines.get(index + 1)
    }

    /// Stop sending new commands (those in flight still complete).
    pub fn pause(&mut self) {
        self.paused = true;
    }

    /// Carry on after [`pause`](Self::pause).
    pub fn resume(&mut self) {
        self.paused = false;
    }

    /// Abandon the job: no more job commands; send the shutdown commands (heaters and
    /// motors off), or with `emergency` an immediate `M112` and nothing else.
    pub fn cancel(&mut self, emergency: bool) {
        if self.phase == Phase::Done {
            return;
        }
        self.paused = false;
        if emergency {
            if !self.emergency_sent {
                self.emergency_sent = true;
                // Marlin's emergency parser acts on M112 as soon as it arrives, numbered or not.
                self.outputs.push_back(Output::Send("M112\n".into()));
                self.stats.bytes_sent += 5;
            }
            self.finish(true);
            return;
        }
        if self.cancelled {
            return;
        }
        self.cancelled = true;
        if !matches!(self.phase, Phase::Streaming) {
            self.finish(true);
            return;
        }
        // The printer expects `next` next: the shutdown commands take over from there.
        let keep = (self.next as usize).max(1);
        self.lines.truncate(keep);
        self.sent_high = self.sent_high.map(|h| h.min(keep as u64 - 1));
        self.original_len = self.original_len.min(keep - 1);
        for c in &self.cfg.shutdown {
            self.lines.push(Command {
                text: c.clone(),
                source_line: 0,
            });
        }
    }

    /// The earliest time `poll` has something to do without new input.
    pub fn next_deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Done => None,
            Phase::Connecting { next_probe, .. } => Some(next_probe),
            Phase::Booted { until } => Some(until),
            Phase::Streaming => {
                let idle = self.last_progress + self.current_timeout();
                Some(self.settle_until.map_or(idle, |s| s.min(idle)))
            }
        }
    }

    fn current_timeout(&self) -> Duration {
        let base = if self.in_flight.iter().any(|f| f.long) {
            self.cfg.long_timeout
        } else {
            self.cfg.timeout
        };
        if self.suspect && self.probes_unanswered == 0 {
            base.min(self.cfg.suspect_timeout)
        } else {
            base
        }
    }

    /// "last acknowledged: line 120 (file line 164)" for error messages.
    pub fn last_acked_words(&self) -> String {
        if self.acked == 0 {
            return "no job line was acknowledged yet".into();
        }
        let src = self
            .lines
            .get(self.acked as usize)
            .map_or(0, |c| c.source_line);
        if src == 0 {
            format!("last acknowledged: line {}", self.acked)
        } else {
            format!("last acknowledged: line {} (file line {src})", self.acked)
        }
    }

    fn fail(&mut self, err: ProtocolError) {
        if self.phase != Phase::Done {
            self.phase = Phase::Done;
            self.outputs.push_back(Output::Failed(err));
        }
    }

    fn finish(&mut self, cancelled: bool) {
        if self.phase != Phase::Done {
            self.phase = Phase::Done;
            self.outputs
                .push_back(Output::Event(Event::Finished { cancelled }));
        }
    }

    fn event(&mut self, e: Event) {
        self.outputs.push_back(Output::Event(e));
    }

    /// Marks lines up to `line` executed.
    fn ack_through(&mut self, line: u64) {
        if line > self.acked {
            self.acked = line.min(self.lines.len() as u64 - 1);
            if self.resend_target.is_some_and(|t| self.acked >= t) {
                self.same_resend = 0;
            }
            self.event(Event::Progress {
                executed: self.acked as usize,
            });
        }
    }

    /// Feeds one line received from the printer.
    pub fn feed_line(&mut self, raw: &str, now: Instant) {
        if self.phase == Phase::Done {
            return;
        }
        let reply = Reply::parse(raw);
        let garbled = raw
            .chars()
            .any(|c| c == '\u{fffd}' || (c.is_control() && c != '\r'));
        if garbled {
            // A damaged line may have been an `ok` or a resend: the counts may be off.
            self.suspect = true;
            self.event(Event::Warning(format!(
                "unreadable line from the printer: {:?}",
                raw.trim()
            )));
        }
        // Marlin prints a rejection's `ok` right after its `Resend:`; one that has not come
        // within the settle time is not coming.
        let after_rejection = std::mem::take(&mut self.expect_rejection_ok)
            && now.duration_since(self.rejection_at) < self.cfg.resend_settle;
        let merge = self.merge_resend.take();
        let after_foreign = std::mem::take(&mut self.foreign_ok);
        if matches!(
            reply,
            Reply::Ok { .. } | Reply::Resend(_) | Reply::LineError { .. } | Reply::Busy
        ) {
            // Alive: only total silence counts against the probes.
            self.probes_unanswered = 0;
        }
        match reply {
            Reply::Ok {
                line,
                buffer,
                temps,
                ..
            } => {
                self.last_progress = now;
                if let Some(t) = &temps {
                    self.event(Event::Temperatures(t.clone()));
                }
                if let (Some(l), Some(b)) = (line, buffer) {
                    self.on_advanced(l, b);
                }
                self.on_ok(temps.is_some(), after_rejection, after_foreign, now);
            }
            Reply::Resend(n) => {
                self.last_progress = now;
                if merge == Some(n) {
                    self.expect_rejection_ok = true;
                    self.rejection_at = now;
                } else {
                    self.on_resend(n, now);
                }
            }
            Reply::LineError { last_line, message } => {
                self.last_progress = now;
                self.event(Event::Warning(format!("printer: Error:{message}")));
                self.on_resend(last_line + 1, now);
                self.merge_resend = Some(last_line + 1);
            }
            Reply::Error(_) if garbled => {
                // A damaged line is not evidence enough to stop a print: a damaged rejection
                // is repeated by the lines behind it or found by the probe a silence
                // triggers, and a printer that really halted goes silent and is reported so.
            }
            Reply::Error(message) => {
                let last = self.last_acked_words();
                self.fail(ProtocolError::PrinterError { message, last });
            }
            Reply::Busy => self.last_progress = now,
            Reply::Wait => {}
            Reply::Start => self.on_start(now),
            Reply::UnknownCommand(cmd) => {
                let ours = self.in_flight.front().is_some_and(|f| {
                    self.lines[f.line as usize]
                        .text
                        .trim()
                        .eq_ignore_ascii_case(cmd.trim())
                });
                if ours {
                    self.event(Event::Warning(format!(
                        "the printer does not know the command {cmd:?}; continuing"
                    )));
                } else {
                    // Not the next job command: a probe damaged on the way. Its `ok`
                    // follows and must not be counted for a job line.
                    self.foreign_ok = true;
                }
            }
            Reply::Temperatures(t) => self.event(Event::Temperatures(t)),
            Reply::Action(action) => self.on_action(action),
            Reply::Other(text) => {
                if !garbled && !text.is_empty() {
                    self.event(Event::Message(text));
                }
            }
        }
    }

    fn on_start(&mut self, now: Instant) {
        match self.phase {
            Phase::Connecting { .. } => {
                // Marlin prints its configuration for a moment after `start` and may still
                // answer probes sent before: let that pass before line 0.
                self.phase = Phase::Booted {
                    until: now + Duration::from_millis(150),
                };
            }
            Phase::Booted { .. } => {}
            Phase::Streaming => {
                let last = self.last_acked_words();
                self.fail(ProtocolError::PrinterReset { last });
            }
            Phase::Done => {}
        }
    }

    fn on_action(&mut self, action: HostAction) {
        match action {
            HostAction::Pause => {
                self.paused = true;
                self.event(Event::Paused(true));
            }
            HostAction::Resume => {
                self.paused = false;
                self.event(Event::Paused(false));
            }
            HostAction::Cancel => {
                self.event(Event::Warning("the printer asked to cancel the job".into()));
                self.cancel(false);
            }
            HostAction::Other(what) => self.event(Event::Message(format!("//action:{what}"))),
        }
    }

    fn on_advanced(&mut self, line: u64, free: u32) {
        self.advanced = Some((line, free));
        for f in self.in_flight.iter_mut() {
            if f.line <= line {
                f.received = true;
            }
        }
    }

    fn on_ok(&mut self, has_temps: bool, after_rejection: bool, after_foreign: bool, now: Instant) {
        match self.phase {
            Phase::Connecting { .. } => {
                self.probes_outstanding = self.probes_outstanding.saturating_sub(1);
                self.phase = Phase::Booted { until: now };
                return;
            }
            Phase::Booted { .. } => {
                // An answer to a probe means the firmware reached its main loop: no need to
                // wait out the rest of the boot chatter.
                if self.probes_outstanding > 0 {
                    self.probes_outstanding -= 1;
                    self.phase = Phase::Booted { until: now };
                }
                return;
            }
            Phase::Done => return,
            Phase::Streaming => {}
        }
        if after_rejection {
            // The `ok` Marlin prints with every resend request belongs to the rejected line.
            // Had the firmware left it out, this would be a queued line's `ok` instead, and
            // the count would be one off: look sooner if the printer then goes quiet.
            if self.in_flight.iter().any(|f| f.received) {
                self.suspect = true;
            }
            return;
        }
        if after_foreign {
            // A damaged probe still went through the command queue: it answers like one.
            self.probes_outstanding = self.probes_outstanding.saturating_sub(1);
            if self.recovery == Recovery::Probing {
                self.after_probe();
            }
            return;
        }
        let front_is_m105 = self
            .in_flight
            .front()
            .is_some_and(|f| gcode::code(&self.lines[f.line as usize].text) == "M105");
        // Marlin puts temperatures only on M105's `ok`: with no M105 at the front, an
        // `ok T:...` answers a probe (perhaps a late one from connecting), not a job line.
        let is_probe_answer = (has_temps && !front_is_m105)
            || (self.probes_outstanding > 0 && self.in_flight.is_empty());
        if is_probe_answer {
            // Probes can be lost too, so any answer ends the probing.
            self.probes_outstanding = self.probes_outstanding.saturating_sub(1);
            self.probes_unanswered = 0;
            if self.recovery == Recovery::Probing {
                self.after_probe();
            }
            return;
        }
        if let Recovery::Resyncing { line } = self.recovery {
            // The printer took the resent line: it had not received it, so nothing after it.
            self.in_flight.clear();
            self.ack_through(line);
            self.next = line + 1;
            self.end_recovery();
            return;
        }
        if let Some(f) = self.in_flight.pop_front() {
            self.ack_through(f.line);
        }
    }

    /// The probe came back: every line the printer had received before it has executed.
    fn after_probe(&mut self) {
        while let Some(f) = self.in_flight.front().copied() {
            if !f.received {
                break;
            }
            self.in_flight.pop_front();
            self.ack_through(f.line);
        }
        let at_end = self.next as usize >= self.lines.len();
        let target = match self.in_flight.front() {
            Some(f) => Some(f.line),
            None if (self.suspect || self.probed) && at_end => self.sent_high,
            None => None,
        };
        match target {
            Some(line) => {
                let cmd = &self.lines[line as usize];
                match gcode::frame(line, &cmd.text, cmd.source_line) {
                    Ok(framed) => {
                        self.stats.lines_sent += 1;
                        self.stats.bytes_sent += framed.len() as u64;
                        self.outputs.push_back(Output::Send(framed));
                        self.recovery = Recovery::Resyncing { line };
                    }
                    Err(e) => self.fail(e.into()),
                }
            }
            None => self.end_recovery(),
        }
    }

    fn end_recovery(&mut self) {
        self.recovery = Recovery::None;
        self.suspect = false;
        self.probed = false;
        self.probes_unanswered = 0;
    }

    fn on_resend(&mut self, n: u64, now: Instant) {
        let Some(high) = self.sent_high else {
            return;
        };
        self.expect_rejection_ok = true;
        self.rejection_at = now;
        if n == 0 {
            // Marlin skips the line-number check for M110, so a second `N0 M110 N0` would be
            // accepted and reset its counter: lines after it could then run twice. Marlin
            // never asks for line 0 (a refused M110 leaves the old counter), so ignore it.
            self.suspect = true;
            self.event(Event::Warning(
                "the printer asked for line 0 (M110); not sent again".into(),
            ));
            return;
        }
        if n > high + 1 {
            self.suspect = true;
            self.event(Event::Warning(format!(
                "the printer asked for line {n}, which was never sent; ignored"
            )));
            return;
        }
        if n + self.cfg.history < high + 1 {
            self.fail(ProtocolError::ResendOutOfHistory {
                requested: n,
                oldest: (high + 1).saturating_sub(self.cfg.history),
            });
            return;
        }
        if let Recovery::Resyncing { .. } = self.recovery {
            // The verdict on the resync line: everything before `n` was received before the
            // probe, so it has executed.
            let before: Vec<u64> = self
                .in_flight
                .iter()
                .map(|f| f.line)
                .filter(|&l| l < n)
                .collect();
            if let Some(&last) = before.last() {
                self.ack_through(last);
            }
            self.ack_through(n.saturating_sub(1));
            self.in_flight.clear();
            self.next = n;
            self.dup_budget = 0;
            self.resend_target = Some(n);
            self.end_recovery();
            return;
        }
        if self.resend_target == Some(n) && !self.sent_since_resend {
            // Nothing was sent since the last request for this line: this one was caused by
            // bytes already on their way (a line in flight, or the tail of a cut line).
            self.dup_budget = self.dup_budget.saturating_sub(1);
            return;
        }
        if self.resend_target == Some(n) && self.dup_budget > 0 {
            // A line that was already in flight behind the rejected one.
            self.dup_budget -= 1;
            return;
        }
        if self.resend_target == Some(n) {
            self.same_resend += 1;
            if self.same_resend >= self.cfg.max_same_resend {
                let source_line = self.lines.get(n as usize).map_or(0, |c| c.source_line);
                self.fail(ProtocolError::ResendLoop {
                    line: n,
                    times: self.same_resend,
                    source_line,
                });
                return;
            }
        } else {
            self.resend_target = Some(n);
            self.same_resend = 1;
        }
        self.stats.resends += 1;
        self.event(Event::Resend { line: n });
        self.dup_budget = high.saturating_sub(n);
        self.in_flight.retain(|f| f.line < n);
        for f in self.in_flight.iter_mut() {
            f.received = true;
        }
        if self.acked >= n && n > 0 {
            // The printer's counter outranks our `ok` accounting.
            self.acked = n - 1;
            self.event(Event::Warning(format!(
                "the printer had not received line {n}, which was counted as done; recounting"
            )));
            self.event(Event::Progress {
                executed: self.acked as usize,
            });
        }
        self.next = n;
        self.sent_since_resend = false;
        // Wait for in-flight lines to be rejected before sending again: otherwise the flush
        // after each rejection can cut the resent line, and the cut tail provokes the next
        // rejection. A repeated request for the same line suggests exactly that.
        let repeated = self.same_resend >= 2;
        self.settle_full = repeated;
        self.settle_until =
            (self.dup_budget > 0 || repeated).then_some(now + self.cfg.resend_settle);
    }

    fn bytes_in_flight(&self) -> usize {
        self.in_flight
            .iter()
            .filter(|f| !f.received)
            .map(|f| f.bytes)
            .sum()
    }

    fn window_allows(&self, bytes: usize) -> bool {
        if self.in_flight.is_empty() {
            return true;
        }
        if self.in_flight.iter().any(|f| f.line == 0) {
            // Marlin applies M110's number when it executes it: a line sent before then
            // would be checked against the old counter.
            return false;
        }
        let room_for_bytes = self.bytes_in_flight() + bytes <= self.cfg.rx_buffer;
        let room_for_lines = match self.advanced {
            // ADVANCED_OK: follow the firmware's own count of free command slots.
            Some((_, free)) => {
                let unreceived = self.in_flight.iter().filter(|f| !f.received).count();
                unreceived < free as usize
            }
            None => self.in_flight.len() < self.cfg.window,
        };
        room_for_bytes && room_for_lines
    }

    /// The next thing to do: an event to report, a line to write, or `None` (wait for input
    /// or [`next_deadline`](Self::next_deadline)).
    pub fn poll(&mut self, now: Instant) -> Option<Output> {
        if let Some(o) = self.outputs.pop_front() {
            return Some(o);
        }
        match self.phase {
            Phase::Done => return None,
            Phase::Connecting { since, next_probe } => {
                if now.duration_since(since) >= self.cfg.connect_timeout {
                    self.fail(ProtocolError::NoConnection {
                        seconds: now.duration_since(since).as_secs_f64(),
                    });
                } else if now >= next_probe {
                    self.phase = Phase::Connecting {
                        since,
                        next_probe: now + Duration::from_secs(1),
                    };
                    self.probes_outstanding += 1;
                    self.stats.bytes_sent += 5;
                    return Some(Output::Send("M105\n".into()));
                }
                return self.outputs.pop_front();
            }
            Phase::Booted { until } => {
                if now < until {
                    return None;
                }
                self.phase = Phase::Streaming;
                self.probes_outstanding = 0;
                self.last_progress = now;
                self.event(Event::Connected);
                return self.outputs.pop_front();
            }
            Phase::Streaming => {}
        }
        if let Some(until) = self.settle_until
            && (now >= until || (self.dup_budget == 0 && !self.settle_full))
        {
            // Zombies that never answered were flushed from Marlin's buffer with the first
            // error; a resend that came without its `ok` counts as acknowledged.
            self.settle_until = None;
            self.dup_budget = 0;
        }
        if self.recovery == Recovery::None
            && self.settle_until.is_none()
            && (!self.paused || self.cancelled)
            && (self.next as usize) < self.lines.len()
        {
            let line = self.next;
            let cmd = &self.lines[line as usize];
            let framed = match gcode::frame(line, &cmd.text, cmd.source_line) {
                Ok(f) => f,
                Err(e) => {
                    self.fail(e.into());
                    return self.outputs.pop_front();
                }
            };
            if self.window_allows(framed.len()) {
                if self.in_flight.is_empty() {
                    self.last_progress = now;
                }
                self.in_flight.push_back(Flight {
                    line,
                    bytes: framed.len(),
                    received: false,
                    long: is_long(&cmd.text),
                });
                self.next += 1;
                self.sent_since_resend = true;
                self.sent_high = Some(self.sent_high.map_or(line, |h| h.max(line)));
                self.stats.lines_sent += 1;
                self.stats.bytes_sent += framed.len() as u64;
                return Some(Output::Send(framed));
            }
        }
        let at_end = self.next as usize >= self.lines.len();
        let quiet = self.in_flight.is_empty() && self.settle_until.is_none();
        if at_end && quiet && self.recovery == Recovery::None {
            if self.suspect || self.probed {
                // A garbled line was seen, or a probe (unnumbered, so unprotected) may have
                // been damaged into another command: confirm the last line really arrived
                // before calling the job done.
                self.send_probe(now);
                return self.outputs.pop_front();
            }
            self.finish(self.cancelled);
            return self.outputs.pop_front();
        }
        let waiting = !self.in_flight.is_empty() || self.recovery != Recovery::None;
        if waiting && now.duration_since(self.last_progress) >= self.current_timeout() {
            if self.probes_unanswered >= self.cfg.max_probes {
                let seconds = (self.probes_unanswered + 1) as f64 * self.cfg.timeout.as_secs_f64();
                let last = self.last_acked_words();
                self.fail(ProtocolError::NotAnswering {
                    seconds,
                    probes: self.probes_unanswered,
                    last,
                });
            } else {
                self.send_probe(now);
            }
        }
        self.outputs.pop_front()
    }

    fn send_probe(&mut self, now: Instant) {
        self.recovery = Recovery::Probing;
        self.probed = true;
        self.probes_outstanding += 1;
        self.probes_unanswered += 1;
        self.last_progress = now;
        self.stats.probes += 1;
        self.stats.bytes_sent += 5;
        self.event(Event::Warning(format!(
            "no answer from the printer; probing with M105 ({} of {})",
            self.probes_unanswered, self.cfg.max_probes
        )));
        self.outputs.push_back(Output::Send("M105\n".into()));
    }
}

#[cfg(test)]
mod tests;
