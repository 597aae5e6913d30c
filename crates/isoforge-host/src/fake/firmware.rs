//! A Marlin-like firmware model with no I/O: bytes in, reply lines out, a clock passed in.
//!
//! It follows Marlin's `GCodeQueue` closely where the host protocol depends on it:
//! - a 128-byte receive ring; bytes that do not fit are lost, as on a real board;
//! - characters are pulled from the ring only while one of the 4 command slots is free;
//! - a numbered line is checked for its line number, then its checksum (the virtual
//!   printer's dialect checks the checksum first); a refused line gets its dialect's refusal
//!   (error text, resend request, `ok` or not), and Marlin's receive ring is drained first;
//! - `ok` is sent after a command executes; M105 answers `ok T:...`; M109/M190 block,
//!   reporting temperatures and busy while heating, until done or `M108`;
//! - M112 and M108 act as soon as their line arrives (Marlin's emergency parser).
//!
//! The words come from [`crate::dialect`]: banner, refusal texts, resend and `ok` forms,
//! busy and halt texts of the chosen firmware family. Commands are read by `isoforge-gcode`
//! and move the same machine model the host and the slicer's checker follow.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use isoforge_gcode::{Command, Machine, framing};

use super::faults::{FaultCounts, Faults, Rng};
use crate::dialect::{Dialect, Refusal};

/// Marlin's `RX_BUFFER_SIZE` default.
pub const RX_BUFFER: usize = 128;
/// Marlin's `BUFSIZE` default.
pub const COMMAND_SLOTS: usize = 4;

/// How long an idle firmware that says `wait` waits before saying it (Repetier: 1 s).
const WAIT_AFTER: Duration = Duration::from_secs(1);

/// Lines behind a refused one that Repetier answers with `skip` instead of a new refusal.
const REPETIER_SKIPS: u32 = 14;

/// One command the firmware executed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Executed {
    /// Its line number (`None` for unnumbered commands such as the host's connection probes).
    pub line: Option<u64>,
    /// The command, without line number and checksum.
    pub command: String,
}

/// What the emergency parser acted on, so a test (or a user) can see that a host's `M112`
/// or `M108` reached the printer and did what it is for, not only that the job stopped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct EmergencyCounts {
    /// `M112`s that halted the firmware.
    pub m112: u64,
    /// `M108`s that ended a heating wait (`M109`/`M190`).
    pub m108: u64,
}

impl std::fmt::Display for EmergencyCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "m112={} m108={}", self.m112, self.m108)
    }
}

/// Settings of the model.
#[derive(Clone, Debug)]
pub struct FirmwareConfig {
    /// What goes wrong.
    pub faults: Faults,
    /// Real time per simulated second of heating (zero: heating takes no time, but still
    /// reports temperatures and `busy` while it "waits").
    pub heat_tick: Duration,
    /// Degrees per simulated second.
    pub heat_rate: f64,
    /// Receive ring size.
    pub rx_buffer: usize,
    /// Command slots.
    pub slots: usize,
    /// The firmware family whose words it speaks.
    pub dialect: Dialect,
}

impl Default for FirmwareConfig {
    fn default() -> Self {
        FirmwareConfig {
            faults: Faults::default(),
            heat_tick: Duration::ZERO,
            heat_rate: 40.0,
            rx_buffer: RX_BUFFER,
            slots: COMMAND_SLOTS,
            dialect: Dialect::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct Heater {
    temp: f64,
    target: f64,
}

impl Heater {
    fn ambient() -> Heater {
        Heater {
            temp: 22.0,
            target: 0.0,
        }
    }

    fn approach(&mut self, step: f64) {
        let goal = if self.target > 0.0 { self.target } else { 22.0 };
        let d = goal - self.temp;
        self.temp += d.clamp(-step, step);
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Run {
    Running,
    /// Blocking in M109/M190 until the heater reaches its target.
    Heating {
        bed: bool,
        next_tick: Instant,
        ticks: u32,
    },
    Halted,
    Silent,
}

/// The firmware model.
pub struct Firmware {
    cfg: FirmwareConfig,
    rng: Rng,
    rx: VecDeque<u8>,
    line_buf: Vec<u8>,
    emergency_buf: Vec<u8>,
    queue: VecDeque<Executed>,
    last_n: u64,
    out: VecDeque<String>,
    executed: Vec<Executed>,
    executed_count: u64,
    run: Run,
    hotends: [Heater; 2],
    bed: Heater,
    machine: Machine,
    auto_report: Option<(Duration, Instant)>,
    lost_bytes: u64,
    /// Repetier: lines still answered with `skip` after a refusal.
    skips_left: u32,
    /// When the firmware last received or did anything (for `wait`).
    last_activity: Option<Instant>,
    /// The one-shot events fire once per firmware life, not again after the reset they cause.
    fired: bool,
    counts: FaultCounts,
    emergency: EmergencyCounts,
}

impl Firmware {
    /// A freshly booted firmware; its first output lines are its dialect's banner.
    pub fn new(cfg: FirmwareConfig) -> Firmware {
        let rng = Rng::new(cfg.faults.seed);
        let mut fw = Firmware {
            cfg,
            rng,
            rx: VecDeque::new(),
            line_buf: Vec::new(),
            emergency_buf: Vec::new(),
            queue: VecDeque::new(),
            last_n: 0,
            out: VecDeque::new(),
            executed: Vec::new(),
            executed_count: 0,
            run: Run::Running,
            hotends: [Heater::ambient(); 2],
            bed: Heater::ambient(),
            machine: Machine::default(),
            auto_report: None,
            lost_bytes: 0,
            skips_left: 0,
            last_activity: None,
            fired: false,
            counts: FaultCounts::default(),
            emergency: EmergencyCounts::default(),
        };
        fw.banner();
        fw
    }

    fn banner(&mut self) {
        for line in self.cfg.dialect.banner() {
            // The banner is the firmware's own; line noise may hit it like anything else.
            self.emit(line);
        }
    }

    /// Everything executed so far, in order.
    #[cfg(test)]
    pub fn executed(&self) -> &[Executed] {
        &self.executed
    }

    /// Takes the executed record, leaving it empty.
    pub fn take_executed(&mut self) -> Vec<Executed> {
        std::mem::take(&mut self.executed)
    }

    /// The faults injected so far.
    pub fn fault_counts(&self) -> FaultCounts {
        self.counts
    }

    /// What the emergency parser acted on so far.
    pub fn emergency_counts(&self) -> EmergencyCounts {
        self.emergency
    }

    /// Bytes lost because the receive ring was full.
    #[cfg(test)]
    pub fn lost_bytes(&self) -> u64 {
        self.lost_bytes
    }

    /// A one-line summary of the model's state, for test failure messages.
    #[cfg(test)]
    pub fn describe(&self) -> String {
        format!(
            "run={:?} last_n={} rx={}B line_buf={:?} queue={:?}",
            self.run,
            self.last_n,
            self.rx.len(),
            String::from_utf8_lossy(&self.line_buf),
            self.queue
        )
    }

    /// True once the firmware halted or went silent.
    pub fn is_dead(&self) -> bool {
        matches!(self.run, Run::Halted | Run::Silent)
    }

    /// Bytes arriving on the serial line.
    pub fn receive(&mut self, bytes: &[u8]) {
        if self.is_dead() {
            return;
        }
        self.last_activity = None;
        for &b in bytes {
            self.scan_emergency(b);
            if self.is_dead() {
                return;
            }
            if self.rx.len() >= self.cfg.rx_buffer {
                self.lost_bytes += 1;
            } else {
                self.rx.push_back(b);
            }
        }
    }

    /// Marlin's emergency parser sees bytes as they arrive, before the command queue: `M112`
    /// kills at once, `M108` ends a heating wait.
    fn scan_emergency(&mut self, b: u8) {
        if b == b'\n' || b == b'\r' {
            let text = String::from_utf8_lossy(&self.emergency_buf).to_string();
            self.emergency_buf.clear();
            let f = framing(&text);
            match Command::parse(f.body) {
                Ok(Some(c)) if c.code.is('M', 112) => {
                    for line in self.cfg.dialect.halt() {
                        self.out.push_back(line);
                    }
                    if self.run != Run::Halted {
                        self.emergency.m112 += 1;
                    }
                    self.run = Run::Halted;
                }
                Ok(Some(c)) if c.code.is('M', 108) => {
                    if let Run::Heating { .. } = self.run {
                        self.emergency.m108 += 1;
                        self.run = Run::Running;
                        self.ok(None);
                    }
                }
                _ => {}
            }
        } else if self.emergency_buf.len() < 128 {
            self.emergency_buf.push(b);
        }
    }

    /// The next reply line, without its line ending.
    pub fn take_output(&mut self) -> Option<String> {
        self.out.pop_front()
    }

    /// When the model next has something to do without new input.
    pub fn next_deadline(&self) -> Option<Instant> {
        match self.run {
            Run::Heating { next_tick, .. } => Some(next_tick),
            Run::Running => {
                let wait = self
                    .last_activity
                    .filter(|_| self.cfg.dialect.says_wait())
                    .map(|t| t + WAIT_AFTER);
                match (self.auto_report.map(|(_, at)| at), wait) {
                    (Some(a), Some(w)) => Some(a.min(w)),
                    (a, w) => a.or(w),
                }
            }
            _ => None,
        }
    }

    /// Does one unit of work: a heating tick, or reading lines into free slots and executing
    /// one command. Returns false when there is nothing to do now.
    pub fn step(&mut self, now: Instant) -> bool {
        match self.run {
            Run::Halted | Run::Silent => return false,
            Run::Heating {
                bed,
                next_tick,
                ticks,
            } => {
                if now < next_tick {
                    return false;
                }
                self.heat_tick(bed, ticks, now);
                return true;
            }
            Run::Running => {}
        }
        let mut worked = false;
        if let Some((every, at)) = self.auto_report
            && now >= at
        {
            let report = self.temperature_report();
            self.emit(&report);
            self.auto_report = Some((every, now + every));
            worked = true;
        }
        while self.queue.len() < self.cfg.slots {
            let Some(b) = self.rx.pop_front() else { break };
            worked = true;
            if b == b'\n' || b == b'\r' {
                let line = std::mem::take(&mut self.line_buf);
                self.process_line(line);
            } else if self.line_buf.len() < 256 {
                self.line_buf.push(b);
            }
        }
        if let Some(cmd) = self.queue.pop_front() {
            self.execute(cmd, now);
            worked = true;
        }
        if worked {
            self.last_activity = Some(now);
        } else if self.cfg.dialect.says_wait() && self.rx.is_empty() && self.queue.is_empty() {
            // Repetier and the virtual printer say `wait` after a second with nothing to do,
            // so a host whose `ok` was lost does not wait for it forever.
            match self.last_activity {
                Some(t) if now.duration_since(t) >= WAIT_AFTER => {
                    self.emit("wait");
                    self.last_activity = Some(now);
                    worked = true;
                }
                None => self.last_activity = Some(now),
                Some(_) => {}
            }
        }
        worked
    }

    fn emit(&mut self, line: &str) {
        let mut line = line.to_string();
        if self.cfg.faults.corrupt_reply > 0.0
            && !line.is_empty()
            && self.rng.chance(self.cfg.faults.corrupt_reply)
        {
            let mut bytes = line.into_bytes();
            let at = self.rng.below(bytes.len());
            bytes[at] = 0x80 | (self.rng.next_u64() as u8 & 0x7f);
            line = String::from_utf8_lossy(&bytes).into_owned();
            self.counts.corrupt_reply += 1;
        }
        self.out.push_back(line);
    }

    /// Refuses the line being read: the dialect's refusal lines, and its `ok`.
    fn refuse(&mut self, why: Refusal) {
        // Marlin empties its receive ring before asking for the resend.
        self.rx.clear();
        self.line_buf.clear();
        for line in self.cfg.dialect.refusal(why, self.last_n) {
            self.emit(&line);
        }
        if self.cfg.dialect == Dialect::Repetier {
            self.skips_left = REPETIER_SKIPS;
        }
        if self.cfg.dialect.ok_after_refusal() {
            if self.rng.chance(self.cfg.faults.no_resend_ok) {
                self.counts.no_resend_ok += 1;
            } else {
                self.ok(None);
            }
        }
    }

    fn ok(&mut self, line: Option<u64>) {
        if self.cfg.faults.advanced_ok {
            let free = self.cfg.slots.saturating_sub(self.queue.len());
            self.emit(&format!("ok N{} P15 B{free}", self.last_n));
        } else {
            let ok = self.cfg.dialect.ok(line);
            self.emit(&ok);
        }
    }

    fn process_line(&mut self, mut raw: Vec<u8>) {
        let f = self.cfg.faults.clone();
        if self.rng.chance(f.drop) {
            self.counts.drop += 1;
            return;
        }
        if !raw.is_empty() && self.rng.chance(f.corrupt) {
            let at = self.rng.below(raw.len());
            let old = raw[at];
            let mut new = old;
            while new == old {
                new = b'!' + self.rng.below(94) as u8;
            }
            raw[at] = new;
            self.counts.corrupt += 1;
        }
        let text = String::from_utf8_lossy(&raw).to_string();
        let text = text.split(';').next().unwrap_or("").trim().to_string();
        if text.is_empty() {
            return;
        }
        let frame = framing(&text);
        if !self.cfg.dialect.checks_lines() {
            // Klipper reads past line numbers and checksums without checking them.
            self.queue.push_back(Executed {
                line: frame.number,
                command: frame.body.to_string(),
            });
            return;
        }
        let command = frame.body.to_string();
        if !frame.has_number_word {
            if frame.has_checksum_mark {
                self.refuse(Refusal::NoLineNumber);
                return;
            }
            self.queue.push_back(Executed {
                line: None,
                command,
            });
            return;
        }
        let m110 = match Command::parse(&command) {
            Ok(Some(c)) if c.code.is('M', 110) => Some(c),
            _ => None,
        };
        // strtol: a line number that is not digits reads as 0.
        let n = frame.number.unwrap_or(0);
        let checksum_ok = frame.has_checksum_mark && frame.checksum_matches();
        if self.cfg.dialect.checksum_first() && !checksum_ok {
            self.refuse_checksum(frame.has_checksum_mark);
            return;
        }
        if m110.is_none() && n != self.last_n.wrapping_add(1) {
            self.out_of_sequence(n);
            return;
        }
        if !checksum_ok {
            self.refuse_checksum(frame.has_checksum_mark);
            return;
        }
        if self.rng.chance(f.error) {
            // A refusal without the resend request a host would need.
            self.counts.error += 1;
            self.rx.clear();
            self.line_buf.clear();
            let lines = self.cfg.dialect.refusal(Refusal::Checksum, self.last_n);
            let resends: Vec<String> = lines
                .iter()
                .filter_map(|l| crate::dialect::resend_request(l).map(|_| l.clone()))
                .collect();
            for l in lines.iter().filter(|l| !resends.contains(l)) {
                self.emit(l);
            }
            if self.cfg.dialect.ok_after_refusal() {
                self.ok(None);
            }
            return;
        }
        if m110.is_none()
            && self.rng.chance(f.spurious_resend)
            && let Some(resend) = self.cfg.dialect.resend(n)
        {
            // A good line refused with a bare request for itself, as OctoPrint's simulator
            // does on its `resend` error: the line is not taken.
            self.counts.spurious_resend += 1;
            self.rx.clear();
            self.line_buf.clear();
            self.emit(&resend);
            if self.cfg.dialect.ok_after_refusal() {
                self.ok(None);
            }
            return;
        }
        self.last_n = match &m110 {
            Some(c) if self.cfg.dialect.m110_takes_argument() => {
                c.get('N').map_or(n, |v| v.max(0.0) as u64)
            }
            _ => n,
        };
        self.skips_left = 0;
        self.queue.push_back(Executed {
            line: Some(n),
            command,
        });
    }

    fn refuse_checksum(&mut self, has_mark: bool) {
        self.refuse(if has_mark {
            Refusal::Checksum
        } else {
            Refusal::NoChecksum
        });
    }

    /// A line whose number is not the last one + 1.
    fn out_of_sequence(&mut self, n: u64) {
        let d = self.cfg.dialect;
        if d.ignores_repeats() && (n == self.last_n || n.wrapping_add(1) == self.last_n) {
            // Marlin 2: a resend that crossed the request for it; dropped without a word.
            return;
        }
        let seen = n <= self.last_n && self.last_n - n < 40;
        if (self.skips_left > 0 || (d == Dialect::Repetier && seen))
            && let Some(skip) = d.skip(n)
        {
            self.skips_left = self.skips_left.saturating_sub(1);
            self.emit(&skip);
            self.ok(None);
            return;
        }
        self.refuse(Refusal::LineNumber {
            expected: self.last_n.wrapping_add(1),
            got: n,
        });
    }

    fn execute(&mut self, cmd: Executed, now: Instant) {
        let text = cmd.command.clone();
        let line = cmd.line;
        self.executed.push(cmd);
        self.executed_count += 1;
        if self.rng.chance(self.cfg.faults.busy)
            && let Some(busy) = self.cfg.dialect.busy()
        {
            self.counts.busy += 1;
            for _ in 0..3 {
                self.emit(busy);
            }
        }
        let parsed = Command::parse(&text).ok().flatten();
        if let Some(c) = &parsed {
            self.machine.apply(c);
        }
        for h in self.hotends.iter_mut().chain([&mut self.bed]) {
            h.approach(self.cfg.heat_rate / 10.0);
        }
        let Some(c) = parsed else {
            self.emit(&format!("echo:Unknown command: \"{text}\""));
            self.after_ok(line, None);
            return;
        };
        let s = c.get('S').or_else(|| c.get('R'));
        let tool = c
            .get('T')
            .map_or(self.machine.tool.min(1), |t| (t as usize).min(1));
        match (c.code.letter, c.code.number) {
            ('M', 105) => {
                let report = self.temperature_report();
                self.after_ok(line, Some(format!("ok{report}")));
                return;
            }
            ('M', 104) => self.hotends[tool].target = s.unwrap_or(0.0),
            ('M', 140) => self.bed.target = s.unwrap_or(0.0),
            ('M', n @ (109 | 190)) => {
                let bed = n == 190;
                let heater = if bed {
                    &mut self.bed
                } else {
                    &mut self.hotends[tool]
                };
                if let Some(s) = s {
                    heater.target = s;
                }
                self.run = Run::Heating {
                    bed,
                    next_tick: now,
                    ticks: 0,
                };
                return;
            }
            ('M', 110) => {
                // Marlin sets its count again when M110 runs.
                if self.cfg.dialect.m110_takes_argument()
                    && let Some(n) = c.get('N')
                {
                    self.last_n = n.max(0.0) as u64;
                }
            }
            ('M', 155) => {
                self.auto_report = match s {
                    Some(secs) if secs > 0.0 => {
                        let every = Duration::from_secs_f64(secs.min(60.0));
                        Some((every, now + every))
                    }
                    _ => None,
                };
            }
            ('M', 115) => {
                let name = self.cfg.dialect.firmware_name();
                self.emit(&format!("FIRMWARE_NAME:{name} PROTOCOL_VERSION:1.0"));
                let adv = u8::from(self.cfg.faults.advanced_ok);
                self.emit(&format!("Cap:ADVANCED_OK:{adv}"));
                self.emit("Cap:AUTOREPORT_TEMP:1");
            }
            ('M', 114) => {
                let p = self.machine.position.map(|v| v.unwrap_or(0.0));
                self.emit(&format!(
                    "X:{:.2} Y:{:.2} Z:{:.2} E:{:.2} Count X:0 Y:0 Z:0",
                    p[0], p[1], p[2], self.machine.e
                ));
            }
            (l, n) if is_known(l, n) => {}
            _ => {
                self.emit(&format!("echo:Unknown command: \"{text}\""));
            }
        }
        self.after_ok(line, None);
    }

    /// Sends the `ok` (or `ok_text`) unless it is lost, and fires a one-shot event due at
    /// this command count.
    fn after_ok(&mut self, line: Option<u64>, ok_text: Option<String>) {
        if self.rng.chance(self.cfg.faults.drop_ok) {
            self.counts.drop_ok += 1;
        } else {
            match ok_text {
                Some(s) => self.emit(&s),
                None => self.ok(line),
            }
        }
        let f = &self.cfg.faults;
        let n = self.executed_count;
        if self.fired {
            return;
        }
        if f.reset_at == Some(n) {
            self.fired = true;
            self.counts.reset += 1;
            self.reset();
        } else if f.halt_at == Some(n) {
            self.fired = true;
            self.counts.halt += 1;
            for line in self.cfg.dialect.halt() {
                self.emit(&line);
            }
            self.run = Run::Halted;
        } else if f.silent_at == Some(n) {
            self.fired = true;
            self.counts.silent += 1;
            self.run = Run::Silent;
        }
    }

    /// A board reset: everything buffered is lost, the line counter starts over.
    pub fn reset(&mut self) {
        self.rx.clear();
        self.line_buf.clear();
        self.queue.clear();
        self.last_n = 0;
        self.run = Run::Running;
        self.hotends = [Heater::ambient(); 2];
        self.bed = Heater::ambient();
        self.machine = Machine::default();
        self.auto_report = None;
        self.skips_left = 0;
        self.banner();
    }

    fn heat_tick(&mut self, bed: bool, ticks: u32, now: Instant) {
        let rate = self.cfg.heat_rate;
        let tool = self.machine.tool.min(1);
        let heater = if bed {
            &mut self.bed
        } else {
            &mut self.hotends[tool]
        };
        heater.approach(rate);
        let done = (heater.temp - heater.target).abs() < 0.5 || heater.target <= 0.0;
        let report = self.temperature_report();
        self.emit(&format!("{report} W:?"));
        if ticks % 2 == 1
            && let Some(busy) = self.cfg.dialect.busy()
        {
            self.emit(busy);
        }
        if done {
            self.run = Run::Running;
            self.after_ok(None, None);
        } else {
            self.run = Run::Heating {
                bed,
                next_tick: now + self.cfg.heat_tick,
                ticks: ticks + 1,
            };
        }
    }

    fn temperature_report(&self) -> String {
        let t = self.hotends[self.machine.tool.min(1)];
        let mut s = format!(
            " T:{:.1} /{:.1} B:{:.1} /{:.1}",
            t.temp, t.target, self.bed.temp, self.bed.target
        );
        for (i, h) in self.hotends.iter().enumerate() {
            s += &format!(" T{i}:{:.1} /{:.1}", h.temp, h.target);
        }
        s + " @:0 B@:0"
    }
}

/// Commands the model accepts silently (it does not move anything).
fn is_known(letter: char, number: u32) -> bool {
    match letter {
        'G' => matches!(number, 0..=4 | 10 | 11 | 20 | 21 | 28 | 29 | 90 | 91 | 92),
        'M' => matches!(
            number,
            17 | 18
                | 73
                | 82
                | 83
                | 84
                | 106
                | 107
                | 108
                | 117
                | 201
                | 203
                | 204
                | 205
                | 220
                | 221
                | 300
                | 400
                | 500
                | 501
                | 503
        ),
        'T' => number <= 1,
        _ => false,
    }
}

#[cfg(test)]
mod tests;
