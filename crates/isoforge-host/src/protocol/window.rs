//! The lines in flight: sent, not yet known executed, in order.
//!
//! Flow control keeps the firmware's buffers from overflowing: at most `window` commands
//! and `rx_buffer` bytes not yet taken from its receive buffer (Marlin: 4 command slots and a
//! 128-byte receive ring that drops what does not fit). With ADVANCED_OK the firmware's own
//! count of free slots is followed instead.

use std::collections::VecDeque;

use super::wire::{Carries, LineNo};

/// What went out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sent {
    /// A numbered line.
    Line(LineNo, Carries),
    /// `N<n> M110 N<n>`: puts the firmware's count at `n` (see `recovery`).
    Renumber(LineNo),
}

/// One transmission in flight.
#[derive(Clone, Copy, Debug)]
pub(crate) struct InFlight {
    pub sent: Sent,
    /// Bytes on the wire, line ending included.
    pub bytes: usize,
    /// Known to have left the receive buffer (the firmware answered something after it).
    pub received: bool,
    /// A command that may keep the firmware busy for minutes (homing, heating, dwell).
    pub long: bool,
    /// Nothing may be queued behind it until it is done: a heating wait (so a cancel can end
    /// it with M108 and turn the heaters off before anything else runs) or a renumbering.
    pub barrier: bool,
}

impl InFlight {
    /// The line number, for a numbered line.
    pub fn line(&self) -> Option<LineNo> {
        match self.sent {
            Sent::Line(n, _) => Some(n),
            Sent::Renumber(_) => None,
        }
    }

    /// True for an `M105` (a probe, or one from the file): its `ok` carries temperatures.
    pub fn is_m105(&self, job_m105: impl Fn(Carries) -> bool) -> bool {
        match self.sent {
            Sent::Line(_, Carries::Probe) => true,
            Sent::Line(_, c) => job_m105(c),
            Sent::Renumber(_) => false,
        }
    }
}

/// The lines in flight.
#[derive(Debug, Default)]
pub(crate) struct Window {
    entries: VecDeque<InFlight>,
    /// ADVANCED_OK: free command slots the firmware last reported.
    free_slots: Option<u32>,
}

impl Window {
    pub fn push(&mut self, f: InFlight) {
        self.entries.push_back(f);
    }

    pub fn pop_front(&mut self) -> Option<InFlight> {
        self.entries.pop_front()
    }

    pub fn front(&self) -> Option<&InFlight> {
        self.entries.front()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn iter(&self) -> impl Iterator<Item = &InFlight> {
        self.entries.iter()
    }

    /// Bytes still in the firmware's receive buffer.
    pub fn unreceived_bytes(&self) -> usize {
        self.entries
            .iter()
            .filter(|f| !f.received)
            .map(|f| f.bytes)
            .sum()
    }

    /// True when a line of `bytes` may go out now.
    pub fn allows(&self, bytes: usize, window: usize, rx_buffer: usize) -> bool {
        if self.entries.is_empty() {
            return true;
        }
        if self.entries.iter().any(|f| f.barrier) {
            return false;
        }
        let room_for_bytes = self.unreceived_bytes() + bytes <= rx_buffer;
        let room_for_lines = match self.free_slots {
            Some(free) => {
                let unreceived = self.entries.iter().filter(|f| !f.received).count();
                unreceived < free as usize
            }
            None => self.entries.len() < window,
        };
        room_for_bytes && room_for_lines
    }

    /// Forgets what was sent from line `n` on (the firmware refused it) and returns how many
    /// numbered lines that was.
    pub fn drop_from(&mut self, n: LineNo) -> usize {
        let before = self.entries.len();
        self.entries.retain(|f| f.line().is_none_or(|l| l < n));
        before - self.entries.len()
    }

    /// Forgets the probes in flight: their answers are taken as lost (a probe still queued
    /// in the firmware answers later, and the newest probe's answer covers it).
    pub fn drop_probes(&mut self) {
        self.entries
            .retain(|f| !matches!(f.sent, Sent::Line(_, Carries::Probe)));
    }

    /// Forgets a renumbering in flight (the firmware refused it).
    pub fn drop_renumber(&mut self) {
        self.entries
            .retain(|f| !matches!(f.sent, Sent::Renumber(_)));
    }

    /// Everything still in flight has reached the firmware.
    pub fn mark_all_received(&mut self) {
        for f in &mut self.entries {
            f.received = true;
        }
    }

    /// ADVANCED_OK: the firmware has line `n` and everything before, and `free` slots.
    pub fn advanced_ok(&mut self, n: LineNo, free: u32) {
        self.free_slots = Some(free);
        for f in &mut self.entries {
            if f.line().is_some_and(|l| l <= n) {
                f.received = true;
            }
        }
    }

    /// The position of the first entry `pred` accepts.
    pub fn position(&self, pred: impl Fn(&InFlight) -> bool) -> Option<usize> {
        self.entries.iter().position(pred)
    }

    /// Removes the first `count` entries and returns them.
    pub fn take_front(&mut self, count: usize) -> Vec<InFlight> {
        self.entries
            .drain(..count.min(self.entries.len()))
            .collect()
    }
}
