//! What the protocol does with each line from the printer.

use std::time::Instant;

use super::reply::{HostAction, Reply};
use super::window::Sent;
use super::wire::{Carries, JobIndex, LineNo};
use super::{Event, PendingError, Phase, Protocol, ProtocolError};
use crate::dialect::{self, ErrorClass, ResendForm};
use crate::gcode;

impl Protocol {
    /// Feeds one line received from the printer.
    pub fn feed_line(&mut self, raw: &str, now: Instant) {
        if self.phase == Phase::Done {
            return;
        }
        let reply = Reply::parse(raw);
        let garbled = raw
            .chars()
            .any(|c| c == '\u{fffd}' || (c.is_control() && c != '\r'));
        if self.phase != Phase::Streaming {
            self.feed_while_connecting(reply, now);
            return;
        }
        if garbled {
            // A damaged line may have been an `ok` or a resend request: the count may be off.
            // It is still the printer answering: a probe it answered with a damaged line is
            // not one it left unanswered (three losses in a row on a noisy link, a line
            // lost, the answer damaged, the next probe lost, once ended a job).
            self.watchdog.alive(now);
            self.irregular = true;
            self.watchdog.suspect = true;
            if self.recovery.careful() {
                self.recovery.doubt = true;
            }
        }
        // The second line of a split fatal report (Prusa: `Error:0` then `: Extruder switched
        // off. MAXTEMP triggered !`).
        if let Some(pending) = &self.pending_error
            && !matches!(reply, Reply::Ok { .. } | Reply::Resend(..))
            && dialect::mentions_fatal(raw)
        {
            let message = format!("{} {}", pending.message, raw.trim());
            self.fail_printer_error(message);
            return;
        }
        if !matches!(reply, Reply::Resend(_, ResendForm::Rs)) {
            self.recovery.skip_bare_rs = false;
        }
        match &reply {
            // A refused line: an `ok` right after it is the refusal's, whether or not a
            // resend request comes between.
            Reply::Error(m)
                if matches!(dialect::classify_error(m), ErrorClass::RefusedLine { .. }) =>
            {
                self.recovery.refused(now)
            }
            // An `ok` after this line is not a refusal's.
            Reply::Error(_) | Reply::Fatal(_) | Reply::Start => {
                self.recovery.refusal_ok_next = None
            }
            _ => {}
        }
        match reply {
            Reply::Ok {
                line,
                buffer,
                temps,
            } => {
                if let Some(t) = &temps {
                    self.event(Event::Temperatures(t.clone()));
                }
                let numbered = match (line, buffer) {
                    (Some(l), Some(b)) => {
                        // ADVANCED_OK: the last line received and the free slots. An `ok`
                        // that says the oldest line in flight has not even arrived is not
                        // that line's (it answers a refusal).
                        self.window.advanced_ok(LineNo(l), b);
                        if self
                            .window
                            .front()
                            .and_then(|f| f.line())
                            .is_some_and(|front| front > LineNo(l))
                        {
                            self.recovery.refusal_ok_next = None;
                            self.watchdog.alive(now);
                            return;
                        }
                        None
                    }
                    (Some(l), None) => Some(LineNo(l)),
                    _ => None,
                };
                self.on_ok(temps.is_some(), numbered, now);
            }
            Reply::Resend(n, form) => self.on_resend_line(n, form, now),
            Reply::Error(message) => self.on_error(message, garbled, now),
            Reply::Fatal(message) if !garbled => self.fail_printer_error(message),
            Reply::Fatal(_) => {}
            Reply::Busy => self.watchdog.alive(now),
            Reply::Wait => {
                // Idle with nothing queued while the host counts lines in flight: their
                // `ok`s were lost, or the lines. Ask now.
                if !self.window.is_empty() && self.watchdog.probe_sent.is_none() {
                    self.irregular = true;
                    self.watchdog.suspect = true;
                    self.ask(now);
                }
            }
            Reply::Start => {
                let last = self.last_acked_words();
                self.fail(ProtocolError::PrinterReset { last });
            }
            Reply::UnknownCommand(cmd) => self.event(Event::Warning(format!(
                "the printer does not know the command {cmd:?}; continuing"
            ))),
            Reply::Temperatures(t) => {
                // During heating or homing the reports show the firmware at work.
                if self.window.front().is_some_and(|f| f.long) {
                    self.watchdog.alive(now);
                }
                self.event(Event::Temperatures(t));
            }
            Reply::Action(action) => self.on_action(action),
            Reply::Other(text) => {
                if !garbled && !text.is_empty() {
                    self.event(Event::Message(text));
                }
            }
        }
    }

    /// Before the job: banners, stray bytes after a reset (`\x80`), `SD card ok`, echo
    /// chatter and late answers to the connection's probes all pass without effect.
    ///
    /// The job starts only once `ok`s have stopped coming for `boot_wait`. An `ok` is not
    /// tagged with what it answers: Smoothieware's banner ends with one, and a probe damaged
    /// on the way is answered `Unknown command` and `ok` after it. Such an `ok` arriving
    /// after the opening `M110` would be taken for its answer, the first job line would go
    /// out before `M110` ran, and running `M110 N0` would set the count back under it: the
    /// printer then asks for line 1 again, which it has already executed.
    fn feed_while_connecting(&mut self, reply: Reply, now: Instant) {
        match reply {
            Reply::Ok { .. } => {
                if matches!(self.phase, Phase::Connecting { .. } | Phase::Booted { .. }) {
                    self.phase = Phase::Booted {
                        until: now + self.cfg.boot_wait,
                    };
                }
            }
            Reply::Start => {
                self.phase = Phase::Booted {
                    until: now + self.cfg.boot_wait,
                };
            }
            Reply::Fatal(message) => self.fail_printer_error(message),
            Reply::Error(message) if dialect::classify_error(&message) == ErrorClass::Fatal => {
                self.fail_printer_error(message)
            }
            Reply::Temperatures(t) => self.event(Event::Temperatures(t)),
            _ => {}
        }
    }

    fn fail_printer_error(&mut self, message: String) {
        let last = self.last_acked_words();
        self.fail(ProtocolError::PrinterError { message, last });
    }

    fn on_ok(&mut self, has_temps: bool, line: Option<LineNo>, now: Instant) {
        if let Some(n) = line {
            // Repetier names the line it took (`ok 773`); its refusals' `ok`s are bare.
            self.recovery.refusal_ok_next = None;
            let taken = self
                .window
                .position(|f| f.line() == Some(n))
                .map_or(0, |i| i + 1);
            if taken > 0 {
                self.watchdog
                    .on_ok(now, self.window.len() >= self.cfg.window);
                for f in self.window.take_front(taken) {
                    self.done_with(f.sent);
                }
                return;
            }
            if self
                .window
                .front()
                .and_then(|f| f.line())
                .is_some_and(|front| n < front)
            {
                // It names a line already done: not the `ok` of anything in flight.
                self.watchdog.alive(now);
                return;
            }
        }
        if self.recovery.take_refusal_ok(now, self.cfg.resend_settle) {
            // The `ok` Marlin prints with every resend request belongs to the refused line.
            self.watchdog.alive(now);
            return;
        }
        let pacing = self.window.len() >= self.cfg.window;
        self.watchdog.on_ok(now, pacing);
        if has_temps {
            // Only M105 answers with temperatures: everything through the first M105 in
            // flight executed. With none in flight it is a late answer to a probe sent
            // while connecting.
            let job = &self.job;
            let is_m105 = |c: Carries| match c {
                Carries::Job(JobIndex(i)) => {
                    job.get(i).is_some_and(|c| gcode::code(&c.text) == "M105")
                }
                _ => false,
            };
            if let Some(first) = self.window.position(|f| f.is_m105(is_m105)) {
                // Only through the first: probes behind it may still wait in the firmware's
                // buffer. Counted done with it, they made room that was not there: the host
                // overran a 128-byte receive buffer, and a line that lost bytes whose XOR
                // was zero passed its checksum as another command. A probe whose `ok` was
                // lost is forgotten by the watchdog once the printer has gone quiet.
                for f in self.window.take_front(first + 1) {
                    self.done_with(f.sent);
                }
            }
            return;
        }
        if let Some(f) = self.window.pop_front() {
            self.done_with(f.sent);
        }
    }

    /// An `ok` for what was sent.
    fn done_with(&mut self, sent: Sent) {
        match sent {
            Sent::Line(n, c) => {
                self.ack_through(n);
                if c == Carries::Probe {
                    self.watchdog.probe_answered();
                    // The answer confirms every line sent so far: the count is right again.
                    if self.window.is_empty() && self.wire.high() == Some(n) {
                        self.irregular = false;
                    }
                }
            }
            // The count is set; sending goes on from where it stood.
            Sent::Renumber(_) => {}
        }
    }

    fn on_resend_line(&mut self, n: u64, form: ResendForm, now: Instant) {
        self.irregular = true;
        self.watchdog.alive(now);
        match form {
            ResendForm::Skip => {
                // Repetier: a line it did not take (one behind a refused line, or one it
                // already has); its `ok` follows.
                self.recovery.refused(now);
                return;
            }
            ResendForm::Rs if self.recovery.skip_bare_rs => {
                // Teacup names the line it received after its real request: not a request.
                self.recovery.skip_bare_rs = false;
                return;
            }
            ResendForm::TeacupRs => self.recovery.skip_bare_rs = true,
            ResendForm::Resend | ResendForm::Rs => {}
        }
        // The request answers any error line of its burst.
        let burst_error = self.pending_error.take().map(|e| e.class);
        // Firmwares that ask with `rs` (RepRapFirmware, Smoothieware) print no `ok` after
        // a refusal: an `ok` right after their request is the resent line's. Taken for the
        // refusal's, it left the resent line waiting for a probe after every request.
        if form != ResendForm::Rs {
            self.recovery.refused(now);
        }
        self.on_resend(LineNo(n), burst_error, now);
    }

    /// The printer wants line `n` next; `burst_error` is the error line that came with the
    /// request, if any.
    pub(super) fn on_resend(&mut self, n: LineNo, burst_error: Option<ErrorClass>, now: Instant) {
        self.irregular = true;
        self.watchdog.alive(now);
        // A renumbering that was refused (damaged on the way) goes out again; the number
        // the firmware names then means nothing.
        let renumbering = self.window.iter().find_map(|f| match f.sent {
            Sent::Renumber(at) => Some(at),
            Sent::Line(..) => None,
        });
        // Lines sent after the renumbering (a step forward when its `ok` was lost) may have
        // been taken behind it: then the request is about them, and holding them back for
        // a renumbering that cannot go while they are in flight stalled the job for good.
        let sent_past = |at: LineNo| self.window.iter().any(|f| f.line().is_some_and(|l| l > at));
        if let Some(at) = renumbering
            && (n == at.next() || sent_past(at))
        {
            // The count is where the renumbering puts it (M110 itself is never refused for
            // its number): the request is about the lines after it, and is taken as such.
            self.window.drop_renumber();
        } else if let Some(at) = renumbering {
            self.window.drop_renumber();
            self.recovery.renumber = Some(at);
            // Sending again at once would have the refusal's flush cut it.
            self.recovery.settle_full = true;
            self.recovery.settle_until = Some(now + self.cfg.resend_settle);
            self.recovery.renumbers += 1;
            if self.recovery.renumbers > self.cfg.max_same_resend {
                self.fail(ProtocolError::ResendLoop {
                    line: at.0,
                    times: self.recovery.renumbers,
                    source_line: 0,
                });
            }
            return;
        }
        let Some(high) = self.wire.high() else {
            return;
        };
        if n.0 == 0 {
            // Line 0 is the opening M110: a firmware never asks for it (a refused M110
            // leaves its old count), and sending it again would reset the count mid-job.
            self.watchdog.suspect = true;
            self.event(Event::Warning(
                "the printer asked for line 0 (M110); not sent again".into(),
            ));
            return;
        }
        if n > high.next() {
            self.watchdog.suspect = true;
            self.event(Event::Warning(format!(
                "the printer asked for line {n}, which was never sent; ignored"
            )));
            return;
        }
        if n.0 + self.cfg.history < high.0 + 1 {
            self.fail(ProtocolError::ResendOutOfHistory {
                requested: n.0,
                oldest: (high.0 + 1).saturating_sub(self.cfg.history),
            });
            return;
        }
        if let Some(t) = self.recovery.target {
            self.careful_request(t, n, burst_error, now);
            return;
        }
        if n == high.next() {
            // Everything sent was received: nothing is lost; the `ok`s will follow.
            self.window.mark_all_received();
            return;
        }
        self.rewind(n, now);
    }

    /// A request while the refused line `t` is being sent again.
    fn careful_request(
        &mut self,
        t: LineNo,
        n: LineNo,
        burst_error: Option<ErrorClass>,
        now: Instant,
    ) {
        let Some(sent) = self.recovery.sent_since else {
            // Nothing went out again yet: the request comes from a line that was in flight
            // behind the refused one, unless the firmware lost more than it said.
            if n < t {
                self.rewind(n, now);
            } else {
                self.recovery.zombies = self.recovery.zombies.saturating_sub(1);
            }
            return;
        };
        if n == t && self.recovery.zombies > 0 {
            // A late refusal of a line that was behind the refused one.
            self.recovery.zombies -= 1;
            return;
        }
        // The line the firmware was reading when it refused, when only one line it could
        // refuse is out.
        let mut since: Vec<LineNo> = self
            .window
            .iter()
            .filter_map(|f| f.line())
            .filter(|&l| l >= t)
            .collect();
        let reading = (since.len() == 1).then(|| since.pop()).flatten();
        if let (Some(ErrorClass::RefusedLine { last_line: None }), Some(r)) =
            (&burst_error, reading)
            && n > r
        {
            // It refused the line it was reading without naming its count, and asks for a
            // later one: the count it keeps has drifted ahead. A request for an earlier line
            // is not a drift: that line's `ok` was a damaged or stray one (the count had
            // been doubted), and setting the count past it skipped it.
            self.count_drift(r, n);
            return;
        }
        if n == t {
            self.repeat_request(t, now);
        } else if n <= sent {
            self.rewind(n, now);
        } else if n == sent.next() {
            // Everything sent since the request arrived.
            self.window.mark_all_received();
        } else {
            // The firmware has every line before `n`: those sent since the request, and
            // lines it took before it asked, which only a firmware that asks for a line it
            // already has leaves behind. What it was sent again it refused as a repeat.
            self.window.drop_from(t);
            self.window.mark_all_received();
            self.recovery.target = None;
            self.next_send = self.next_send.max(n);
        }
    }

    /// The printer asked for the line it asked for before, after it went out again.
    fn repeat_request(&mut self, t: LineNo, now: Instant) {
        self.recovery.same += 1;
        if self.recovery.same >= self.cfg.max_same_resend {
            let source_line = self.wire.get(t).map_or(0, |c| self.source_line_of(c));
            self.fail(ProtocolError::ResendLoop {
                line: t.0,
                times: self.recovery.same,
                source_line,
            });
            return;
        }
        self.stats.resends += 1;
        self.event(Event::Resend { line: t.0 });
        self.window.drop_from(t);
        self.forget_lost_probe();
        self.next_send = t;
        self.recovery.sent_since = None;
        self.step_forward = false;
        // The resent line was cut or damaged again: maybe by the tail of a flushed line.
        // Give the link its full settle time.
        self.recovery.settle_full = true;
        self.recovery.settle_until = Some(now + self.cfg.resend_settle);
    }

    /// The firmware refused line `r` and asks for `n`: its count has drifted. Set it to
    /// `r - 1` and send `r` again.
    fn count_drift(&mut self, r: LineNo, n: LineNo) {
        self.recovery.renumbers += 1;
        if self.recovery.renumbers > self.cfg.max_same_resend {
            self.fail(ProtocolError::ResendLoop {
                line: r.0,
                times: self.recovery.renumbers,
                source_line: 0,
            });
            return;
        }
        self.event(Event::Warning(format!(
            "the printer refused line {r} and asked for line {n}, which it cannot have: its \
             line count is off; setting it again with M110"
        )));
        self.window.drop_from(r);
        self.forget_lost_probe();
        self.recovery.target = Some(r);
        self.recovery.sent_since = None;
        self.step_forward = false;
        self.recovery.renumber = Some(LineNo(r.0 - 1));
        self.next_send = r;
    }

    /// Goes back to line `n`, the first the firmware does not have.
    fn rewind(&mut self, n: LineNo, now: Instant) {
        self.stats.resends += 1;
        self.event(Event::Resend { line: n.0 });
        let behind = self
            .window
            .iter()
            .filter(|f| f.line().is_some_and(|l| l > n))
            .count() as u64;
        self.recovery.start(n, behind);
        self.window.drop_from(n);
        // What is still in flight is older than `n`: the firmware has it.
        self.window.mark_all_received();
        self.unack_from(n);
        self.next_send = n;
        self.recovery.settle_full = false;
        self.recovery.settle_until = (behind > 0).then_some(now + self.cfg.resend_settle);
        self.forget_lost_probe();
    }

    /// A probe that the firmware refused (or never got) is no longer awaited.
    fn forget_lost_probe(&mut self) {
        let in_flight = self
            .window
            .iter()
            .any(|f| matches!(f.sent, Sent::Line(_, Carries::Probe)));
        if !in_flight && !self.host_queue.contains(&Carries::Probe) {
            self.watchdog.probe_sent = None;
        }
    }

    fn on_error(&mut self, message: String, garbled: bool, now: Instant) {
        self.irregular = true;
        if garbled {
            // A damaged line is not evidence enough to stop a print: a damaged refusal is
            // repeated by the lines behind it or found by a probe.
            self.watchdog.suspect = true;
            return;
        }
        match dialect::classify_error(&message) {
            ErrorClass::Fatal => self.fail_printer_error(message),
            class => {
                self.pending_error = Some(PendingError {
                    message,
                    class,
                    at: now,
                })
            }
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
}
