//! The RepRap/Marlin host protocol as a state machine with no I/O.
//!
//! Lines from the printer go in with `Protocol::feed_line`; lines to send and events come
//! out of `Protocol::poll`; the clock is passed in, so every timeout is testable.
//!
//! How the machine keeps "each command executed exactly once, in order":
//! - Every line the host sends once the job has started is numbered and checksummed: the
//!   job's commands, and the host's own (`M110`, `M105` probes, `M108`, the shutdown of a
//!   cancelled job, `M112`). A firmware that checks numbers takes line `N` only as its last
//!   line + 1, so sending a line again cannot run it twice, and noise cannot turn a line
//!   into another command.
//! - The firmware's count is the truth: a resend request names the line to go on from
//!   (`recovery` says which requests to act on); an error that names the last line taken
//!   (`Last Line: 109`) and comes with no request is a request for the next after a short
//!   grace; `crate::dialect` knows every firmware's wording of refusals and fatal errors.
//! - `ok`s free buffer slots and confirm execution in order. One that follows a refusal
//!   belongs to it. When `ok`s are lost the count drifts and the printer goes quiet; the
//!   `watchdog` then sends a numbered `M105`, whose `ok T:...` comes only after everything
//!   before it executed. A job that saw anything irregular ends with such a probe, so it is
//!   never called done on a count that may be off, and no acknowledged line is ever sent
//!   again to find out.

mod recovery;
mod reply;
mod temperature;
mod watchdog;
mod window;
mod wire;

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use thiserror::Error;

use crate::dialect::ErrorClass;
use crate::gcode::{self, Command, GcodeError};
use recovery::Recovery;
pub use temperature::{Reading, Temperatures};
use watchdog::Watchdog;
use window::{Sent, Window};
use wire::{Carries, Wire};
pub use wire::{JobIndex, LineNo};

/// Flow-control and timing settings.
#[derive(Clone, Debug)]
pub struct Config {
    /// Commands in flight at most (Marlin's `BUFSIZE` is 4; 3 leaves one slot for the
    /// firmware's own use). 1 is plain ping-pong.
    pub window: usize,
    /// Bytes in flight at most: stock Marlin's receive ring is 128 bytes and drops what does
    /// not fit.
    pub rx_buffer: usize,
    /// Silence after which an unanswered probe is sent again; `max_probes` of them end the
    /// job.
    pub timeout: Duration,
    /// The same while a command that legitimately blocks runs: G28, G29, M109, M190, M400, G4.
    pub long_timeout: Duration,
    /// The shortest silence taken for a lost `ok` (see `watchdog`).
    pub quiet_floor: Duration,
    /// Unanswered probes before the job stops.
    pub max_probes: u32,
    /// How long to wait after a resend request for the rest of the in-flight lines to be
    /// refused, before sending again.
    pub resend_settle: Duration,
    /// How long an error line waits for the resend request of its burst before the host acts
    /// on the error alone.
    pub error_grace: Duration,
    /// How far back (in lines) a resend request may reach.
    pub history: u64,
    /// Requests for the same line in a row before giving up.
    pub max_same_resend: u32,
    /// How long to wait for the printer to answer at all.
    pub connect_timeout: Duration,
    /// How often to ask (`M105`) while waiting for the printer to answer.
    pub connect_probe_every: Duration,
    /// How long to let a freshly booted firmware's chatter pass after `start`.
    pub boot_wait: Duration,
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
            // A USB serial round trip is a few milliseconds (full-speed USB polls every
            // 1 ms, CDC drivers add up to 16 ms) and OctoPrint's Python simulator stalls up
            // to about 20 ms between lines; 50 ms is past both (docs/constants.md).
            quiet_floor: Duration::from_millis(50),
            // OctoPrint's default for consecutive timeouts while printing. With 3, a link
            // that loses 4 % of its lines loses a line and both probes after it about once
            // in 15,000 lines (0.04³), and the job stopped (a random fault mix found it).
            max_probes: 5,
            resend_settle: Duration::from_millis(50),
            // Firmwares print a refusal's error and resend request back to back; at 115200
            // baud the request's 15 bytes take 1.3 ms, USB adds up to 16 ms.
            error_grace: Duration::from_millis(150),
            history: 1024,
            max_same_resend: 12,
            connect_timeout: Duration::from_secs(15),
            connect_probe_every: Duration::from_secs(1),
            // Marlin prints its configuration for about 100 ms after `start` and may still
            // answer probes sent before.
            boot_wait: Duration::from_millis(150),
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
    /// The firmware stopped with a fatal error.
    #[error("the printer stopped with an error: {message}; {last}")]
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
    /// The printer keeps refusing the same line.
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
    /// The printer was quiet with lines in flight; a numbered `M105` asks where it is.
    Probe {
        /// The probe's line number.
        line: u64,
    },
    /// Something odd but survivable (unknown command, an error the host does not know).
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
    /// Numbered `M105` probes (each executes once, like any numbered line).
    pub probes: u64,
    /// `M110` renumberings after resend episodes.
    pub renumbers: u64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Connecting {
        since: Instant,
        next_probe: Instant,
    },
    /// Heard `start` or a first answer: let the boot chatter and late answers pass.
    Booted {
        until: Instant,
    },
    Streaming,
    Done,
}

/// An error line waiting for the resend request of its burst.
#[derive(Debug)]
struct PendingError {
    message: String,
    class: ErrorClass,
    at: Instant,
}

/// Commands that can block the firmware for minutes.
fn is_long(cmd: &str) -> bool {
    matches!(
        gcode::code(cmd).as_str(),
        "G28" | "G29" | "M109" | "M190" | "M191" | "M400" | "G4" | "M303" | "M600" | "M0" | "M1"
    )
}

/// Heating waits, which nothing is queued behind (a cancel ends them with M108).
fn is_heating_wait(cmd: &str) -> bool {
    matches!(gcode::code(cmd).as_str(), "M109" | "M190" | "M191")
}

/// The host side of the protocol for one job.
pub(crate) struct Protocol {
    cfg: Config,
    /// The job's commands.
    job: Vec<Command>,
    /// Job commands that are the job's own; fewer after a cancel.
    original_len: usize,
    /// The next job command to number.
    next_job: JobIndex,
    /// Job commands known executed.
    job_done: usize,
    /// No more job commands are numbered (cancelled).
    job_frozen: bool,
    wire: Wire,
    /// The next line to transmit: the next new number, or a refused line being sent again.
    next_send: LineNo,
    /// The highest line known executed.
    acked: Option<LineNo>,
    /// Host lines to number before the next job command.
    host_queue: VecDeque<Carries>,
    window: Window,
    recovery: Recovery,
    watchdog: Watchdog,
    pending_error: Option<PendingError>,
    phase: Phase,
    paused: bool,
    cancelled: bool,
    emergency_sent: bool,
    /// Something happened that could have put the `ok` count off: the job ends with a probe.
    irregular: bool,
    /// The watchdog lets the next numbered line out past the window to ask.
    step_forward: bool,
    outputs: VecDeque<Output>,
    stats: Stats,
}

impl Protocol {
    /// A job of `commands` (comments stripped, no `M110`), starting to connect at `now`.
    pub fn new(commands: Vec<Command>, cfg: Config, now: Instant) -> Protocol {
        Protocol {
            original_len: commands.len(),
            job: commands,
            next_job: JobIndex(0),
            job_done: 0,
            job_frozen: false,
            wire: Wire::default(),
            next_send: LineNo(0),
            acked: None,
            host_queue: VecDeque::from([Carries::Reset]),
            window: Window::default(),
            recovery: Recovery::new(),
            watchdog: Watchdog::new(now),
            pending_error: None,
            phase: Phase::Connecting {
                since: now,
                next_probe: now,
            },
            paused: false,
            cancelled: false,
            emergency_sent: false,
            irregular: false,
            step_forward: false,
            outputs: VecDeque::new(),
            stats: Stats::default(),
            cfg,
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Job commands known executed.
    #[cfg(test)]
    pub fn executed(&self) -> usize {
        self.job_done
    }

    /// The machine's state in one line, for test failure messages.
    #[cfg(test)]
    pub fn describe(&self) -> String {
        format!(
            "phase={:?} next_send={} high={:?} acked={:?} next_job={:?} queue={:?} window={:?} \
             recovery={:?} watchdog={:?} pending_error={:?} step_forward={} irregular={}",
            self.phase,
            self.next_send,
            self.wire.high(),
            self.acked,
            self.next_job,
            self.host_queue,
            self.window,
            self.recovery,
            self.watchdog,
            self.pending_error,
            self.step_forward,
            self.irregular
        )
    }

    /// Job commands that are the job's own (after a cancel, those numbered before it).
    pub fn original_len(&self) -> usize {
        self.original_len
    }

    /// The job command at `index`.
    pub fn command(&self, index: usize) -> Option<&Command> {
        self.job.get(index)
    }

    /// Stop sending new commands (those in flight still complete).
    pub fn pause(&mut self) {
        self.paused = true;
    }

    /// Carry on after [`pause`](Self::pause).
    pub fn resume(&mut self) {
        self.paused = false;
    }

    /// Abandon the job: no more job commands; end a heating wait in progress (`M108`), then
    /// the shutdown commands (heaters and motors off). With `emergency`: `M112` at once,
    /// then the shutdown commands without waiting (a firmware that honours `M112` has cut
    /// heaters and motors itself and ignores them; one that does not, obeys them).
    pub fn cancel(&mut self, emergency: bool) {
        if self.phase == Phase::Done {
            return;
        }
        self.paused = false;
        if emergency {
            if !self.emergency_sent {
                self.emergency_sent = true;
                self.send_emergency();
            }
            self.finish(true);
            return;
        }
        if self.cancelled {
            return;
        }
        self.cancelled = true;
        self.job_frozen = true;
        if !matches!(self.phase, Phase::Streaming) {
            self.finish(true);
            return;
        }
        self.original_len = self.original_len.min(self.next_job.0);
        if let Some(high) = self.wire.high()
            && self.next_send <= high
            && self.next_send.0 > 0
        {
            // Lines waiting to go out again are dropped, and the firmware's count is set to
            // where it stands, so the shutdown can follow whatever it took.
            let at = LineNo(self.next_send.0 - 1);
            self.wire.truncate_after(at);
            self.recovery.target = None;
            self.recovery.renumber = Some(at);
        }
        let heating = self.window.iter().any(
            |f| matches!(f.sent, Sent::Line(_, c) if self.text_of(c).is_some_and(is_heating_wait)),
        );
        if heating {
            self.host_queue.push_back(Carries::Interrupt);
        }
        for i in 0..self.cfg.shutdown.len() {
            self.host_queue.push_back(Carries::Shutdown(i));
        }
    }

    /// `M112`, numbered from where the firmware's count stands and sent at once whatever is
    /// in flight (an emergency parser acts on it as it arrives), then `M110` to that number
    /// and the shutdown after it, for a firmware that goes on.
    fn send_emergency(&mut self) {
        if let Some(high) = self.wire.high()
            && self.next_send <= high
            && self.next_send.0 > 0
        {
            // A refused line was about to go out again: the firmware never took it.
            self.wire.truncate_after(LineNo(self.next_send.0 - 1));
        }
        let k = self.wire.push(Carries::Emergency);
        let mut texts = vec![(k, "M112".to_string()), (k, format!("M110 N{k}"))];
        for (i, c) in self.cfg.shutdown.iter().enumerate() {
            texts.push((LineNo(k.0 + 1 + i as u64), c.clone()));
        }
        for (n, text) in texts {
            if let Ok(framed) = gcode::frame(n.0, &text, 0) {
                self.count_sent(&framed);
                self.outputs.push_back(Output::Send(framed));
            }
        }
    }

    /// The earliest time `poll` has something to do without new input.
    pub fn next_deadline(&self) -> Option<Instant> {
        match self.phase {
            Phase::Done => None,
            Phase::Connecting { next_probe, .. } => Some(next_probe),
            Phase::Booted { until } => Some(until),
            Phase::Streaming => {
                let mut at = self.watchdog_deadline();
                if let Some(s) = self.recovery.settle_until {
                    at = at.min(s);
                }
                if let Some(e) = &self.pending_error {
                    at = at.min(e.at + self.cfg.error_grace);
                }
                Some(at)
            }
        }
    }

    /// "last acknowledged: line 120 (file line 164)" for error messages.
    pub fn last_acked_words(&self) -> String {
        if self.job_done == 0 {
            return "no job line was acknowledged yet".into();
        }
        let src = self.job.get(self.job_done - 1).map_or(0, |c| c.source_line);
        if src == 0 {
            format!("last acknowledged: job command {}", self.job_done)
        } else {
            format!(
                "last acknowledged: job command {} (file line {src})",
                self.job_done
            )
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

    /// The command text a line carries.
    fn text_of(&self, c: Carries) -> Option<&str> {
        match c {
            Carries::Job(i) => self.job.get(i.0).map(|c| c.text.as_str()),
            Carries::Shutdown(i) => self.cfg.shutdown.get(i).map(String::as_str),
            other => other.host_text(),
        }
    }

    fn source_line_of(&self, c: Carries) -> usize {
        match c {
            Carries::Job(i) => self.job.get(i.0).map_or(0, |c| c.source_line),
            _ => 0,
        }
    }

    fn count_sent(&mut self, framed: &str) {
        self.stats.lines_sent += 1;
        self.stats.bytes_sent += framed.len() as u64;
    }

    /// Marks lines up to `n` executed.
    fn ack_through(&mut self, n: LineNo) {
        if self.acked.is_some_and(|a| a >= n) {
            return;
        }
        let from = self.acked.map_or(0, |a| a.0 + 1);
        let mut done = self.job_done;
        for l in from..=n.0 {
            if let Some(Carries::Job(i)) = self.wire.get(LineNo(l)) {
                done = done.max(i.0 + 1);
            }
        }
        self.acked = Some(n);
        self.recovery.acked_through(n);
        if done > self.job_done {
            self.job_done = done;
            self.event(Event::Progress { executed: done });
        }
    }

    /// The firmware's count is behind ours: lines from `n` on were not executed.
    fn unack_from(&mut self, n: LineNo) {
        if self.acked.is_none_or(|a| a < n) {
            return;
        }
        self.acked = n.0.checked_sub(1).map(LineNo);
        let done = (0..n.0)
            .rev()
            .find_map(|l| match self.wire.get(LineNo(l)) {
                Some(Carries::Job(i)) => Some(i.0 + 1),
                _ => None,
            })
            .unwrap_or(0);
        if done < self.job_done {
            self.job_done = done;
            self.event(Event::Warning(format!(
                "the printer had not received line {n}, which was counted as done; recounting"
            )));
            self.event(Event::Progress { executed: done });
        }
    }
}

mod feed;
mod send;

#[cfg(test)]
mod tests;
