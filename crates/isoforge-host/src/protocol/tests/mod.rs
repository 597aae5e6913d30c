//! The state machine: reply form by reply form and flow by flow (`flows`), and its laws
//! against the firmware model of every dialect under random faults (`faults`).

use std::time::{Duration, Instant};

use super::*;
use crate::sim::commands;

mod faults;
mod flows;

struct Drained {
    sent: Vec<String>,
    events: Vec<Event>,
    failed: Option<ProtocolError>,
}

fn drain(p: &mut Protocol, now: Instant) -> Drained {
    let mut d = Drained {
        sent: vec![],
        events: vec![],
        failed: None,
    };
    while let Some(o) = p.poll(now) {
        match o {
            Output::Send(s) => d.sent.push(s),
            Output::Event(e) => d.events.push(e),
            Output::Failed(e) => d.failed = Some(e),
        }
    }
    d
}

/// The line numbers of framed lines.
fn numbers(sent: &[String]) -> Vec<u64> {
    sent.iter()
        .filter_map(|s| s.strip_prefix('N'))
        .filter_map(|s| s.split(' ').next()?.parse().ok())
        .collect()
}

/// Framed lines without their checksums: `N5 M104 S0`.
fn bodies(sent: &[String]) -> Vec<String> {
    sent.iter()
        .map(|s| s.split('*').next().unwrap_or("").to_string())
        .collect()
}

fn cfg() -> Config {
    Config::default()
}

/// A protocol past the handshake with M110 acknowledged, and the lines it sent next.
fn connected(job: &[&str], cfg: Config) -> (Protocol, Instant, Vec<String>) {
    let t0 = Instant::now();
    let texts: Vec<String> = job.iter().map(|s| s.to_string()).collect();
    let settle = cfg.boot_wait;
    let mut p = Protocol::new(commands(&texts), cfg, t0);
    assert_eq!(drain(&mut p, t0).sent, ["M105\n"]);
    p.feed_line("ok T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0", t0);
    assert!(
        drain(&mut p, t0).sent.is_empty(),
        "nothing before the oks stop"
    );
    let t = t0 + settle;
    let d = drain(&mut p, t);
    assert!(d.events.contains(&Event::Connected));
    assert_eq!(d.sent, [gcode::frame(0, "M110 N0", 0).unwrap()]);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    (p, t, d.sent)
}

fn has_warning(events: &[Event], part: &str) -> bool {
    events
        .iter()
        .any(|e| matches!(e, Event::Warning(w) if w.contains(part)))
}
