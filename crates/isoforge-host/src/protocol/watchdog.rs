//! When silence means something was lost, and when it means the printer is gone.
//!
//! A lost `ok` leaves the host counting one line too many in flight; once as many are lost
//! as the window holds, nothing more goes out and the printer, done with everything, goes
//! quiet. Waiting for the full timeout (5 s) each time made a link that loses 1% of its
//! `ok`s crawl. So the watchdog learns the printer's pace (the usual gap between `ok`s) and
//! probes once the printer has been quiet for several such gaps ([`QUIET_GAPS`]), never
//! sooner than `Config::quiet_floor`: a numbered `M105`, whose answer says that everything
//! before it has executed. A firmware's `wait` (idle, nothing queued) or a damaged reply
//! probes at the floor. Probes that go unanswered for `Config::timeout` each (or
//! `long_timeout` while a long command such as homing or heating runs) end the job.

use std::time::{Duration, Instant};

/// Quiet gaps, in units of the usual gap between `ok`s, before a probe. Pauses in a healthy
/// stream are a few gaps long (a move that outlasts its neighbours, a busy host thread); a
/// lost `ok` is a silence with no end.
pub(crate) const QUIET_GAPS: f64 = 10.0;

/// How much each new gap moves the estimate (an exponential moving average).
const GAP_WEIGHT: f64 = 0.05;

#[derive(Debug)]
pub(crate) struct Watchdog {
    /// The last sign the printer is working on our lines (`ok`, resend request, busy).
    pub last_progress: Instant,
    last_ok: Option<Instant>,
    /// The usual gap between `ok`s, seconds.
    gap: Option<f64>,
    /// When the outstanding probe went out (set with [`Watchdog::probe_out`]).
    pub probe_sent: Option<Instant>,
    /// The printer said something since the outstanding probe went out. Kept as a flag, not
    /// read off the clock: a reply read in the same instant the probe was written (one loop
    /// of the streamer) is later than it, and comparing times would call it earlier.
    pub heard_since_probe: bool,
    /// Probes in a row with no sign of life in between.
    pub unanswered: u32,
    /// Something suggests an `ok` was lost or damaged: probe at the floor.
    pub suspect: bool,
}

impl Watchdog {
    pub fn new(now: Instant) -> Watchdog {
        Watchdog {
            last_progress: now,
            last_ok: None,
            gap: None,
            probe_sent: None,
            heard_since_probe: false,
            unanswered: 0,
            suspect: false,
        }
    }

    /// An `ok` arrived; `pacing` when lines were waiting on it (its gap measures the printer,
    /// not the file running dry).
    pub fn on_ok(&mut self, now: Instant, pacing: bool) {
        if pacing && let Some(prev) = self.last_ok {
            let g = now.duration_since(prev).as_secs_f64();
            self.gap = Some(match self.gap {
                Some(avg) => avg + GAP_WEIGHT * (g - avg),
                None => g,
            });
        }
        self.last_ok = Some(now);
        self.alive(now);
    }

    /// A sign of life that is not an `ok`.
    pub fn alive(&mut self, now: Instant) {
        self.last_progress = now;
        self.unanswered = 0;
        self.heard_since_probe = true;
    }

    /// A probe (a numbered `M105`, or a line sent to find out where the printer stands) has
    /// just gone out.
    pub fn probe_out(&mut self, now: Instant) {
        self.probe_sent = Some(now);
        self.heard_since_probe = false;
    }

    /// The probe was answered (its line acknowledged).
    pub fn probe_answered(&mut self) {
        self.probe_sent = None;
        self.suspect = false;
    }

    /// Silence after which a lost `ok` is assumed.
    pub fn quiet_after(&self, floor: Duration, timeout: Duration, long_front: bool) -> Duration {
        if long_front {
            return timeout;
        }
        if self.suspect {
            return floor;
        }
        match self.gap {
            Some(g) => Duration::from_secs_f64(g * QUIET_GAPS).clamp(floor, timeout.max(floor)),
            None => timeout.min(floor * 4),
        }
    }
}
