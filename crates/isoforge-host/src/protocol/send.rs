//! What the protocol sends, and when: connecting, streaming within the window, the end of
//! the job, and the watchdog's probes.

use std::time::Instant;

use super::window::{InFlight, Sent};
use super::wire::{Carries, LineNo};
use super::{
    Event, Output, Phase, Protocol, ProtocolError, is_heating_wait, is_long, watchdog::Watchdog,
};
use crate::dialect::ErrorClass;
use crate::gcode;

impl Protocol {
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
                        next_probe: now + self.cfg.connect_probe_every,
                    };
                    // Before the job starts the firmware's line count is unknown, so this
                    // question goes unnumbered.
                    let probe = "M105\n".to_string();
                    self.stats.bytes_sent += probe.len() as u64;
                    return Some(Output::Send(probe));
                }
            }
            Phase::Booted { until } => {
                if now >= until {
                    self.phase = Phase::Streaming;
                    self.watchdog = Watchdog::new(now);
                    self.event(Event::Connected);
                }
            }
            Phase::Streaming => self.stream(now),
        }
        self.outputs.pop_front()
    }

    fn stream(&mut self, now: Instant) {
        self.expire_pending_error(now);
        if self.phase != Phase::Streaming {
            return;
        }
        if !self.recovery.settling(now) && self.pending_error.is_none() {
            self.send_what_fits(now);
            if self.check_end() {
                self.send_what_fits(now);
            }
        }
        self.check_watchdog(now);
    }

    /// An error line whose burst brought no resend request.
    fn expire_pending_error(&mut self, now: Instant) {
        let Some(pending) = &self.pending_error else {
            return;
        };
        if now < pending.at + self.cfg.error_grace {
            return;
        }
        let Some(pending) = self.pending_error.take() else {
            return;
        };
        match pending.class {
            // `Last Line: N` says where the firmware stands: go on from N + 1.
            ErrorClass::RefusedLine { last_line: Some(k) } => {
                self.on_resend(LineNo(k + 1), Some(pending.class), now)
            }
            // A refused line, but which? The answer to a probe names it.
            ErrorClass::RefusedLine { last_line: None } => {
                self.watchdog.suspect = true;
                if !self.window.is_empty() {
                    self.request_probe(now);
                }
            }
            ErrorClass::Unknown | ErrorClass::Fatal => self.event(Event::Warning(format!(
                "the printer reported an error the host does not know: {:?}; continuing \
                 (a firmware that stops says so or goes silent)",
                pending.message
            ))),
        }
    }

    /// Sends lines while the window has room.
    fn send_what_fits(&mut self, now: Instant) {
        while self.phase == Phase::Streaming {
            if let Some(at) = self.recovery.renumber {
                self.send_renumber(at, now);
                return;
            }
            // The episode is over: once nothing is in flight, set the count again; only a
            // probe may go before that.
            let renumber_wait = self.recovery.renumber_after && !self.recovery.careful();
            if renumber_wait && self.window.is_empty() && self.next_send.0 > 0 {
                self.recovery.renumber_after = false;
                self.send_renumber(LineNo(self.next_send.0 - 1), now);
                return;
            }
            let high_next = self.wire.high().map_or(LineNo(0), LineNo::next);
            let resending = self.next_send < high_next;
            let (n, carries, new) = if resending {
                match self.wire.get(self.next_send) {
                    Some(c) => (self.next_send, c, false),
                    None => return,
                }
            } else if let Some(&c) = self.host_queue.front() {
                (self.wire.next_number(), c, true)
            } else if !self.job_frozen && !self.paused && self.next_job.0 < self.job.len() {
                (self.wire.next_number(), Carries::Job(self.next_job), true)
            } else {
                return;
            };
            // A probe asks where the printer stands, M108 ends a heating wait, and a line the
            // watchdog lets out asks too: none waits for room in the window.
            let goes_anyway = (new && matches!(carries, Carries::Probe | Carries::Interrupt))
                || self.step_forward;
            let careful_hold = self.recovery.careful() && self.recovery.sent_since.is_some();
            if (careful_hold || renumber_wait) && !goes_anyway {
                // The refused line goes alone until it is acknowledged.
                return;
            }
            let Some(text) = self.text_of(carries).map(str::to_string) else {
                return;
            };
            let framed = match gcode::frame(n.0, &text, self.source_line_of(carries)) {
                Ok(f) => f,
                Err(e) => {
                    self.fail(e.into());
                    return;
                }
            };
            if !goes_anyway
                && !self
                    .window
                    .allows(framed.len(), self.cfg.window, self.cfg.rx_buffer)
            {
                return;
            }
            if new {
                if self.host_queue.front() == Some(&carries) {
                    self.host_queue.pop_front();
                } else {
                    self.next_job.0 += 1;
                }
                self.wire.push(carries);
            }
            if self.recovery.careful() {
                self.recovery.sent_since = Some(self.recovery.sent_since.map_or(n, |s| s.max(n)));
            }
            self.step_forward = false;
            self.next_send = n.next();
            // Silence counts from the last line out too: the printer has this one to answer
            // (after a wait of the host's own, such as a settle, it is not the printer's).
            self.watchdog.last_progress = self.watchdog.last_progress.max(now);
            self.window.push(InFlight {
                sent: Sent::Line(n, carries),
                bytes: framed.len(),
                received: false,
                long: is_long(&text),
                barrier: carries == Carries::Reset || is_heating_wait(&text),
            });
            self.count_sent(&framed);
            if carries == Carries::Probe {
                self.stats.probes += 1;
                self.watchdog.probe_out(now);
                self.event(Event::Probe { line: n.0 });
            }
            self.outputs.push_back(Output::Send(framed));
        }
    }

    /// `N<at> M110 N<at>`: the firmware's count becomes `at`, alone on the wire.
    fn send_renumber(&mut self, at: LineNo, now: Instant) {
        if self.window.iter().any(|f| f.line().is_none_or(|l| l > at)) {
            return;
        }
        let text = format!("M110 N{at}");
        let framed = match gcode::frame(at.0, &text, 0) {
            Ok(f) => f,
            Err(e) => {
                self.fail(e.into());
                return;
            }
        };
        self.recovery.renumber = None;
        self.stats.renumbers += 1;
        self.watchdog.last_progress = self.watchdog.last_progress.max(now);
        self.window.push(InFlight {
            sent: Sent::Renumber(at),
            bytes: framed.len(),
            received: false,
            long: false,
            barrier: true,
        });
        self.count_sent(&framed);
        self.outputs.push_back(Output::Send(framed));
    }

    /// Finishes the job when everything is done; returns true when it queued a final probe.
    fn check_end(&mut self) -> bool {
        let all_numbered =
            (self.job_frozen || self.next_job.0 >= self.job.len()) && self.host_queue.is_empty();
        let nothing_out = self.window.is_empty()
            && self.wire.high().is_none_or(|h| self.next_send > h)
            && self.pending_error.is_none();
        if !(all_numbered && nothing_out) {
            return false;
        }
        if self.recovery.careful() {
            // The episode waits for one more line to be confirmed, and the job has none
            // left: a probe is that line.
            if !self.host_queue.contains(&Carries::Probe) {
                self.host_queue.push_back(Carries::Probe);
            }
            return true;
        }
        if self.recovery.renumber.is_some() || self.recovery.renumber_after {
            // The count is set again first (`send_what_fits`).
            return false;
        }
        if self.irregular && !self.cancelled {
            // Something could have put the `ok` count off: before calling the job done, a
            // numbered M105 confirms the last line executed (its answer comes after).
            self.irregular = false;
            self.host_queue.push_back(Carries::Probe);
            return true;
        }
        self.finish(self.cancelled);
        false
    }

    fn check_watchdog(&mut self, now: Instant) {
        if self.phase != Phase::Streaming || self.window.is_empty() {
            return;
        }
        if self.pending_error.is_some() {
            // An error line waits (a short grace) for its resend request, and is then taken
            // as that request. A line the watchdog let out meanwhile (a damaged reply makes
            // it ask at once) was followed by the error acted on late, as a fresh request:
            // lines already taken went again, and ran twice.
            return;
        }
        let long_front = self.window.front().is_some_and(|f| f.long);
        let silence = now.duration_since(self.watchdog.last_progress);
        let quiet = self
            .watchdog
            .quiet_after(self.cfg.quiet_floor, self.cfg.timeout, long_front);
        if let Some(Sent::Renumber(at)) = self.window.iter().map(|f| f.sent).last()
            && silence >= quiet
        {
            // No answer to a renumbering: it was lost or damaged into a line the firmware
            // drops without a word (Marlin 2 ignores a repeat of its last line number).
            // Nothing can pass it, so it goes again.
            self.window.drop_renumber();
            self.recovery.renumber = Some(at);
            self.recovery.renumbers += 1;
            if self.recovery.renumbers > self.cfg.max_same_resend {
                self.fail(ProtocolError::ResendLoop {
                    line: at.0,
                    times: self.recovery.renumbers,
                    source_line: 0,
                });
                return;
            }
            self.watchdog.alive(now);
            self.send_what_fits(now);
            return;
        }
        let limit = if long_front {
            self.cfg.long_timeout
        } else {
            self.cfg.timeout
        };
        let due = match self.watchdog.probe_sent {
            None => silence >= quiet,
            // The printer answered something after the probe went out, then went quiet: the
            // probe's own `ok` was taken for another line's (or lost), and waiting out the
            // whole timeout would stall the job for nothing (it cost 5 s per damaged line on
            // firmwares that print no `ok` after a refusal). Ask again at the quiet pace.
            Some(_) if !long_front && self.watchdog.heard_since_probe => silence >= quiet,
            Some(sent) => now.duration_since(sent) >= limit,
        };
        if !due {
            return;
        }
        if self.watchdog.probe_sent.is_some() {
            if self.watchdog.unanswered >= self.cfg.max_probes {
                let last = self.last_acked_words();
                self.fail(ProtocolError::NotAnswering {
                    seconds: silence.as_secs_f64(),
                    probes: self.watchdog.unanswered,
                    last,
                });
                return;
            }
            // The unanswered probe's `ok` may be what was lost; if it was the probe itself,
            // the firmware asks for it when the next line comes.
            self.window.drop_probes();
            self.host_queue.retain(|c| *c != Carries::Probe);
            self.watchdog.probe_sent = None;
        }
        self.ask(now);
    }

    /// Asks where the printer stands: a numbered `M105`, or, while numbered lines wait to go
    /// out again (a resend, or the lines behind it), the next of them, since a probe could
    /// not go before them. Taken, it says the lines before it arrived; refused, the request
    /// says where the firmware stands.
    pub(super) fn ask(&mut self, now: Instant) {
        let pending = self.wire.high().is_some_and(|h| self.next_send <= h);
        if pending {
            self.irregular = true;
            self.watchdog.unanswered += 1;
            self.watchdog.probe_out(now);
            self.step_forward = true;
            self.send_what_fits(now);
        } else {
            self.request_probe(now);
        }
    }

    /// Queues a numbered M105 (one at a time).
    pub(super) fn request_probe(&mut self, now: Instant) {
        if self.watchdog.probe_sent.is_some() {
            return;
        }
        self.irregular = true;
        self.watchdog.unanswered += 1;
        self.host_queue.push_front(Carries::Probe);
        // Counted from now even if lines that must go first hold it back a while.
        self.watchdog.probe_out(now);
        self.send_what_fits(now);
    }

    /// When the watchdog next has something to decide.
    pub(super) fn watchdog_deadline(&self) -> Instant {
        let long_front = self.window.front().is_some_and(|f| f.long);
        match self.watchdog.probe_sent {
            Some(_) if !long_front && self.watchdog.heard_since_probe => {
                self.watchdog.last_progress
                    + self
                        .watchdog
                        .quiet_after(self.cfg.quiet_floor, self.cfg.timeout, long_front)
            }
            Some(sent) => {
                sent + if long_front {
                    self.cfg.long_timeout
                } else {
                    self.cfg.timeout
                }
            }
            None => {
                self.watchdog.last_progress
                    + self
                        .watchdog
                        .quiet_after(self.cfg.quiet_floor, self.cfg.timeout, long_front)
            }
        }
    }
}
