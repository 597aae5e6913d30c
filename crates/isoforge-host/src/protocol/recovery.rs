//! After a resend request: which requests to act on, when to send again, and putting the
//! firmware's line count right.
//!
//! - The lines in flight behind a refused one are refused too, each with its own request
//!   for the same line ("zombies"); those are not acted on, and sending waits a short settle
//!   time so they cannot flush the resent line out of the firmware's receive buffer.
//! - The refused line is then sent alone, and nothing follows it until it is acknowledged
//!   (if the printer goes quiet, the next line goes out to ask). When the firmware refuses
//!   the line it was just sent without naming its count, the refused line is known (the one
//!   in flight); a resend request for another line then means the firmware's count has
//!   drifted (OctoPrint's simulator counts the checksums of lines it refused for their
//!   number, and its checksum errors then name a line it never took), so the count is set
//!   again with `N<r-1> M110 N<r-1>` and the refused line `r` sent once more. A count the
//!   firmware names itself (`Last Line: N`, `expected line N`) is never doubted.
//! - Once the episode is over the count is set again (`N<n> M110 N<n>`, nothing in flight,
//!   so it is safe on every firmware) so that a drift from the refusals cannot misplace the
//!   next error.
//! - Lines are never given new numbers: a line the firmware may have taken keeps its number
//!   and its text, so sending it again can never run something else twice.

use std::time::{Duration, Instant};

use super::wire::LineNo;

#[derive(Debug)]
pub(crate) struct Recovery {
    /// The line the printer last asked for, until it is acknowledged.
    pub target: Option<LineNo>,
    /// Requests for `target` still expected from lines that were in flight behind it.
    pub zombies: u64,
    /// The highest line sent since the printer asked for `target`.
    pub sent_since: Option<LineNo>,
    /// Requests for the same line in a row.
    pub same: u32,
    /// Renumberings in a row without progress.
    pub renumbers: u32,
    /// Sending waits until then.
    pub settle_until: Option<Instant>,
    /// Settle for the whole time, even when every expected refusal has come.
    pub settle_full: bool,
    /// The last line from the printer was a refusal, at this time: an `ok` right after it
    /// belongs to it (Marlin, Prusa, Repetier and the virtual printer print one;
    /// Smoothieware and RepRapFirmware do not, and then the next line is something else).
    pub refusal_ok_next: Option<Instant>,
    /// Teacup: the bare `rs M` after its `rs N.. Expected ...` is not a request.
    pub skip_bare_rs: bool,
    /// Lines were refused behind the first: set the count again when the episode ends.
    pub renumber_after: bool,
    /// A renumbering waiting to go out: `N<n> M110 N<n>`.
    pub renumber: Option<LineNo>,
    /// A damaged line came while the refused line was out: the `ok` taken for it may have
    /// been a refusal's, so the episode goes on one more line before the count is trusted.
    pub doubt: bool,
}

impl Recovery {
    pub fn new() -> Recovery {
        Recovery {
            target: None,
            zombies: 0,
            sent_since: None,
            same: 0,
            renumbers: 0,
            settle_until: None,
            settle_full: false,
            refusal_ok_next: None,
            skip_bare_rs: false,
            renumber_after: false,
            renumber: None,
            doubt: false,
        }
    }

    /// A refusal came: an `ok` right after it, if the firmware prints one, belongs to it.
    pub fn refused(&mut self, now: Instant) {
        self.refusal_ok_next = Some(now);
    }

    /// True when an `ok` arriving now answers a refusal rather than a line: it comes next
    /// and at once (the firmware prints it with the request), so one that has not come
    /// within half the settle time is not coming (the refused line, sent again once the
    /// settle time is over, must not have its `ok` taken for the refusal's).
    pub fn take_refusal_ok(&mut self, now: Instant, settle: Duration) -> bool {
        self.refusal_ok_next
            .take()
            .is_some_and(|at| now.duration_since(at) < settle / 2)
    }

    /// True while sending must wait for refusals of the lines behind the refused one.
    pub fn settling(&mut self, now: Instant) -> bool {
        if let Some(until) = self.settle_until
            && (now >= until || (self.zombies == 0 && !self.settle_full))
        {
            // Zombies that never answered were flushed from the firmware's buffer with the
            // first refusal.
            self.settle_until = None;
        }
        self.settle_until.is_some()
    }

    /// Only the refused line may be in flight: it is sent alone until acknowledged.
    pub fn careful(&self) -> bool {
        self.target.is_some()
    }

    /// A new request for `n`, with `zombies` lines in flight behind it.
    pub fn start(&mut self, n: LineNo, zombies: u64) {
        self.doubt = false;
        self.target = Some(n);
        self.sent_since = None;
        self.same = 1;
        self.zombies = zombies;
        self.renumber_after = true;
    }

    /// Line `n` and everything before it executed: the episode is over if it was about `n`
    /// or an earlier line (the count is set again once nothing is in flight).
    pub fn acked_through(&mut self, n: LineNo) {
        match self.target {
            Some(t) if t <= n && std::mem::take(&mut self.doubt) => {
                // Not trusted yet: the next line goes alone too.
                self.target = Some(n.next());
                self.sent_since = None;
                self.zombies = 0;
            }
            Some(t) if t <= n => {
                self.target = None;
                self.zombies = 0;
                self.sent_since = None;
                self.same = 0;
                self.renumbers = 0;
            }
            _ => {}
        }
    }
}
