//! A Marlin-like firmware model with no I/O: bytes in, reply lines out, a clock passed in.
//!
//! It follows Marlin's `GCodeQueue` closely where the host protocol depends on it:
//! - a 128-byte receive ring; bytes that do not fit are lost, as on a real board;
//! - characters are pulled from the ring only while one of the 4 command slots is free;
//! - a numbered line is checked for its line number first, then its checksum
//!   (`Error:Line Number is not Last Line Number+1, Last Line: N`, `Error:checksum
//!   mismatch, Last Line: N`, `Error:No Checksum with line number, Last Line: N`); after an
//!   error the receive ring is drained and `Resend: N+1` and `ok` follow;
//! - `ok` is sent after a command executes; M105 answers `ok T:...`; M109/M190 block,
//!   reporting temperatures and `echo:busy: processing` while heating;
//! - M112 acts as soon as its line arrives (Marlin's emergency parser).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use super::faults::{Faults, Rng};
use crate::gcode::{self, checksum};

/// Marlin's `RX_BUFFER_SIZE` default.
pub const RX_BUFFER: usize = 128;
/// Marlin's `BUFSIZE` default.
pub const COMMAND_SLOTS: usize = 4;

/// One command the firmware executed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Executed {
    /// Its line number (`None` for unnumbered commands such as M105 probes).
    pub line: Option<u64>,
    /// The command, without line number and checksum.
    pub command: String,
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
}

impl Default for FirmwareConfig {
    fn default() -> Self {
        FirmwareConfig {
            faults: Faults::default(),
            heat_tick: Duration::ZERO,
            heat_rate: 40.0,
            rx_buffer: RX_BUFFER,
            slots: COMMAND_SLOTS,
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
    tool: usize,
    auto_report: Option<(Duration, Instant)>,
    lost_bytes: u64,
    /// The one-shot events fire once per firmware life, not again after the reset they cause.
    fired: bool,
}

impl Firmware {
    /// A freshly booted firmware; its first output line is `start`.
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
            tool: 0,
            auto_report: None,
            lost_bytes: 0,
            fired: false,
        };
        fw.emit("start");
        fw.emit("echo:isoforge fake printer (Marlin-like)");
        fw
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

    /// Marlin's emergency parser sees bytes as they arrive, before the command queue.
    fn scan_emergency(&mut self, b: u8) {
        if b == b'\n' || b == b'\r' {
            let text = String::from_utf8_lossy(&self.emergency_buf).to_string();
            self.emergency_buf.clear();
            let cmd = strip_line_number(&text);
            if gcode::code(cmd) == "M112" {
                self.emit("Error:Printer halted. kill() called!");
                self.run = Run::Halted;
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
            Run::Running => self.auto_report.map(|(_, at)| at),
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
        }
        self.out.push_back(line);
    }

    fn line_error(&mut self, what: &str) {
        self.emit(&format!("Error:{what}, Last Line: {}", self.last_n));
        // Marlin empties its receive ring before asking for the resend.
        self.rx.clear();
        self.line_buf.clear();
        self.emit(&format!("Resend: {}", self.last_n + 1));
        if !self.rng.chance(self.cfg.faults.no_resend_ok) {
            self.ok();
        }
    }

    fn ok(&mut self) {
        if self.cfg.faults.advanced_ok {
            let free = self.cfg.slots.saturating_sub(self.queue.len());
            self.emit(&format!("ok N{} P15 B{free}", self.last_n));
        } else {
            self.emit("ok");
        }
    }

    fn process_line(&mut self, mut raw: Vec<u8>) {
        let f = self.cfg.faults.clone();
        if self.rng.chance(f.drop) {
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
        }
        let text = String::from_utf8_lossy(&raw).to_string();
        let text = text.split(';').next().unwrap_or("").trim().to_string();
        if text.is_empty() {
            return;
        }
        let mut line_number = None;
        let mut command = text.as_str();
        if let Some(after_n) = text.strip_prefix('N') {
            let is_m110 = text.contains("M110");
            // For M110 Marlin takes the number from M110's own N word.
            let n_src = if is_m110 {
                text.find("M110")
                    .and_then(|p| text[p + 4..].find('N').map(|q| &text[p + 5 + q..]))
                    .unwrap_or(after_n)
            } else {
                after_n
            };
            let digits: String = n_src.chars().take_while(char::is_ascii_digit).collect();
            let n: u64 = digits.parse().unwrap_or(u64::MAX);
            if n != self.last_n.wrapping_add(1) && !is_m110 {
                self.line_error("Line Number is not Last Line Number+1");
                return;
            }
            let Some(star) = text.rfind('*') else {
                self.line_error("No Checksum with line number");
                return;
            };
            let sent: Option<u8> = text[star + 1..].trim().parse().ok();
            if sent != Some(checksum(&text.as_bytes()[..star])) {
                self.line_error("checksum mismatch");
                return;
            }
            if self.rng.chance(f.error) {
                // A refusal without the resend request a host would need.
                self.emit(&format!(
                    "Error:checksum mismatch, Last Line: {}",
                    self.last_n
                ));
                self.rx.clear();
                self.line_buf.clear();
                self.ok();
                return;
            }
            self.last_n = n;
            line_number = Some(n);
            command = strip_line_number(&text[..star]);
            if self.rng.chance(f.spurious_resend) {
                self.emit(&format!("Resend: {n}"));
                self.ok();
            }
        } else if text.contains('*') {
            self.line_error("No Line Number with checksum");
            return;
        }
        self.queue.push_back(Executed {
            line: line_number,
            command: command.trim().to_string(),
        });
    }

    fn execute(&mut self, cmd: Executed, now: Instant) {
        let text = cmd.command.clone();
        self.executed.push(cmd);
        self.executed_count += 1;
        if self.rng.chance(self.cfg.faults.busy) {
            for _ in 0..3 {
                self.emit("echo:busy: processing");
            }
        }
        let code = gcode::code(&text);
        let s = gcode::word(&text, 'S').or_else(|| gcode::word(&text, 'R'));
        for h in self.hotends.iter_mut().chain([&mut self.bed]) {
            h.approach(self.cfg.heat_rate / 10.0);
        }
        let tool = gcode::word(&text, 'T').map_or(self.tool, |t| (t as usize).min(1));
        let mut reply_ok = true;
        match code.as_str() {
            "M105" => {
                let report = self.temperature_report();
                self.after_ok(Some(format!("ok{report}")));
                return;
            }
            "M104" => self.hotends[tool].target = s.unwrap_or(0.0),
            "M140" => self.bed.target = s.unwrap_or(0.0),
            "M109" | "M190" => {
                let bed = code == "M190";
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
            "M110" => {
                if let Some(n) = gcode::word(&text, 'N') {
                    self.last_n = n as u64;
                }
            }
            "M155" => {
                self.auto_report = match s {
                    Some(secs) if secs > 0.0 => {
                        let every = Duration::from_secs_f64(secs.min(60.0));
                        Some((every, now + every))
                    }
                    _ => None,
                };
            }
            "M115" => {
                self.emit("FIRMWARE_NAME:isoforge fake printer (Marlin-like) PROTOCOL_VERSION:1.0");
                let adv = u8::from(self.cfg.faults.advanced_ok);
                self.emit(&format!("Cap:ADVANCED_OK:{adv}"));
                self.emit("Cap:AUTOREPORT_TEMP:1");
            }
            "M114" => self.emit("X:0.00 Y:0.00 Z:0.00 E:0.00 Count X:0 Y:0 Z:0"),
            "T0" | "T1" => self.tool = if code == "T1" { 1 } else { 0 },
            c if is_known(c) => {}
            _ => {
                self.emit(&format!("echo:Unknown command: \"{text}\""));
            }
        }
        if reply_ok {
            reply_ok = !self.rng.chance(self.cfg.faults.drop_ok);
        }
        self.after_ok(reply_ok.then(String::new));
    }

    /// Sends the `ok` (when given) and fires a one-shot event due at this command count.
    fn after_ok(&mut self, ok: Option<String>) {
        match ok {
            Some(s) if s.is_empty() => self.ok(),
            Some(s) => self.emit(&s),
            None => {}
        }
        let f = &self.cfg.faults;
        let n = self.executed_count;
        if self.fired {
            return;
        }
        if f.reset_at == Some(n) {
            self.fired = true;
            self.reset();
        } else if f.halt_at == Some(n) {
            self.fired = true;
            self.emit("Error:Printer halted. kill() called!");
            self.run = Run::Halted;
        } else if f.silent_at == Some(n) {
            self.fired = true;
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
        self.auto_report = None;
        self.emit("start");
    }

    fn heat_tick(&mut self, bed: bool, ticks: u32, now: Instant) {
        let rate = self.cfg.heat_rate;
        let heater = if bed {
            &mut self.bed
        } else {
            &mut self.hotends[self.tool]
        };
        heater.approach(rate);
        let done = (heater.temp - heater.target).abs() < 0.5 || heater.target <= 0.0;
        let report = self.temperature_report();
        self.emit(&format!("{report} W:?"));
        if ticks % 2 == 1 {
            self.emit("echo:busy: processing");
        }
        if done {
            self.run = Run::Running;
            let ok = !self.rng.chance(self.cfg.faults.drop_ok);
            self.after_ok(ok.then(String::new));
        } else {
            self.run = Run::Heating {
                bed,
                next_tick: now + self.cfg.heat_tick,
                ticks: ticks + 1,
            };
        }
    }

    fn temperature_report(&self) -> String {
        let t = self.hotends[self.tool];
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

/// Drops a leading `N123 `.
fn strip_line_number(text: &str) -> &str {
    let t = text.trim_start();
    match t.strip_prefix('N') {
        Some(rest) => rest
            .trim_start_matches(|c: char| c.is_ascii_digit())
            .trim_start(),
        None => t,
    }
}

/// Commands the model accepts silently (it does not move anything).
fn is_known(code: &str) -> bool {
    matches!(
        code,
        "G0" | "G1"
            | "G2"
            | "G3"
            | "G4"
            | "G10"
            | "G11"
            | "G20"
            | "G21"
            | "G28"
            | "G29"
            | "G90"
            | "G91"
            | "G92"
            | "M17"
            | "M18"
            | "M73"
            | "M82"
            | "M83"
            | "M84"
            | "M106"
            | "M107"
            | "M117"
            | "M201"
            | "M203"
            | "M204"
            | "M205"
            | "M220"
            | "M221"
            | "M300"
            | "M400"
            | "M500"
            | "M501"
            | "M503"
    )
}

#[cfg(test)]
mod tests;
