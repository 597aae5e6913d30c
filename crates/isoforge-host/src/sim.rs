//! In-process simulation for tests: the protocol and the firmware model wired through a
//! simulated link with a simulated clock, so thousands of faulty jobs run in seconds and
//! every run is reproducible.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use crate::fake::{Executed, Firmware, FirmwareConfig, Rng};
use crate::gcode::Command;
use crate::protocol::{Config, Event, Output, Protocol, ProtocolError};

/// How a simulated job ended.
#[derive(Debug)]
pub enum Outcome {
    Finished { cancelled: bool },
    Failed(ProtocolError),
    Stuck,
}

pub struct Sim {
    pub proto: Protocol,
    pub fw: Firmware,
    pub now: Instant,
    /// The simulated clock when the job began.
    pub start: Instant,
    pub events: Vec<Event>,
    pub sent: Vec<String>,
    to_fw: VecDeque<u8>,
    to_host: VecDeque<String>,
    rng: Rng,
    /// Largest chunk of bytes the link moves at once (1 = byte by byte).
    pub chunk: usize,
    /// The last things that crossed the link, for failure messages.
    pub trace: VecDeque<String>,
    /// How many trace lines to keep.
    pub trace_len: usize,
}

pub fn commands(texts: &[String]) -> Vec<Command> {
    texts
        .iter()
        .enumerate()
        .map(|(i, t)| Command {
            text: t.clone(),
            source_line: i + 1,
        })
        .collect()
}

impl Sim {
    pub fn new(job: &[String], cfg: Config, fw: FirmwareConfig, seed: u64) -> Sim {
        let now = Instant::now();
        Sim {
            proto: Protocol::new(commands(job), cfg, now),
            fw: Firmware::new(fw),
            now,
            start: now,
            events: Vec::new(),
            sent: Vec::new(),
            to_fw: VecDeque::new(),
            to_host: VecDeque::new(),
            rng: Rng::new(seed),
            chunk: 64,
            trace: VecDeque::new(),
            trace_len: 60,
        }
    }

    pub fn run(&mut self, max_iterations: usize) -> Outcome {
        for _ in 0..max_iterations {
            let mut moved = false;
            while let Some(o) = self.proto.poll(self.now) {
                moved = true;
                match o {
                    Output::Send(s) => {
                        self.to_fw.extend(s.as_bytes());
                        self.log(format!("{:?} > {}", self.now, s.trim_end()));
                        if std::env::var_os("SIM_DESCRIBE").is_some() {
                            let d = self.proto.describe();
                            self.log(format!("    {d}"));
                        }
                        self.sent.push(s);
                    }
                    Output::Event(Event::Finished { cancelled }) => {
                        return Outcome::Finished { cancelled };
                    }
                    Output::Event(e) => {
                        if !matches!(e, Event::Progress { .. } | Event::Temperatures(_)) {
                            self.log(format!("{:?} ! {e:?}", self.now));
                        }
                        self.events.push(e)
                    }
                    Output::Failed(e) => return Outcome::Failed(e),
                }
            }
            if !self.to_fw.is_empty() {
                let n = 1 + self.rng.below(self.chunk.min(self.to_fw.len()));
                let bytes: Vec<u8> = self.to_fw.drain(..n).collect();
                self.fw.receive(&bytes);
                moved = true;
            }
            for _ in 0..self.rng.below(4) {
                moved |= self.fw.step(self.now);
            }
            while let Some(l) = self.fw.take_output() {
                self.to_host.push_back(l);
            }
            for _ in 0..1 + self.rng.below(3) {
                if let Some(l) = self.to_host.pop_front() {
                    self.log(format!("{:?} < {l}", self.now));
                    self.proto.feed_line(&l, self.now);
                    moved = true;
                }
            }
            if !moved && self.fw.step(self.now) {
                // Only jump the clock when the firmware is idle too.
                moved = true;
            }
            if moved {
                self.now += Duration::from_micros(20);
            } else {
                // Nothing in transit: jump to the next timer.
                let next = [self.proto.next_deadline(), self.fw.next_deadline()]
                    .into_iter()
                    .flatten()
                    .min()
                    .unwrap_or(self.now + Duration::from_millis(1));
                self.now = next.max(self.now + Duration::from_micros(20));
            }
        }
        Outcome::Stuck
    }

    fn log(&mut self, s: String) {
        if self.trace.len() > self.trace_len {
            self.trace.pop_front();
        }
        self.trace.push_back(s);
    }

    /// The job commands the firmware executed, in order (M110 and unnumbered probes left out).
    pub fn executed_job(&self) -> Vec<String> {
        job_commands(self.fw.executed())
    }
}

/// Numbered commands of an executed record, without the host's own (M110 renumbering,
/// M105 probes: the sim's jobs have neither).
pub fn job_commands(record: &[Executed]) -> Vec<String> {
    record
        .iter()
        .filter(|e| e.line.is_some() && !e.command.starts_with("M110") && e.command != "M105")
        .map(|e| e.command.clone())
        .collect()
}

/// A job of distinct commands.
pub fn job(n: usize) -> Vec<String> {
    (0..n)
        .map(|i| format!("G1 X{}.{} Y{} E{}", i % 200, i % 7, i / 200, i))
        .collect()
}
