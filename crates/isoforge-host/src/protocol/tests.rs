//! The state machine, reply form by reply form, and its laws under random faults.

use std::time::{Duration, Instant};

use proptest::prelude::*;

use super::*;
use crate::fake::{Faults, FirmwareConfig};
use crate::sim::{Outcome, Sim, commands, job};

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

fn numbers(sent: &[String]) -> Vec<u64> {
    sent.iter()
        .filter_map(|s| s.strip_prefix('N'))
        .filter_map(|s| s.split(' ').next()?.parse().ok())
        .collect()
}

/// A protocol past the handshake with M110 acknowledged, and the lines it sent next.
fn connected(job: &[&str], cfg: Config) -> (Protocol, Instant, Vec<String>) {
    let t = Instant::now();
    let texts: Vec<String> = job.iter().map(|s| s.to_string()).collect();
    let mut p = Protocol::new(commands(&texts), cfg, t);
    assert_eq!(drain(&mut p, t).sent, ["M105\n"]);
    p.feed_line("ok T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0", t);
    let d = drain(&mut p, t);
    assert!(d.events.contains(&Event::Connected));
    assert_eq!(d.sent, [gcode::frame(0, "M110 N0", 0).unwrap()]);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    (p, t, d.sent)
}

fn cfg() -> Config {
    Config::default()
}

#[test]
fn window_of_three_then_one_per_ok() {
    let (mut p, t, sent) = connected(&["G28", "G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    assert_eq!(sent[0], gcode::frame(1, "G28", 1).unwrap());
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert_eq!(numbers(&d.sent), [4]);
    assert!(d.events.contains(&Event::Progress { executed: 1 }));
}

#[test]
fn ping_pong_with_window_one() {
    let c = Config { window: 1, ..cfg() };
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3"], c);
    assert_eq!(numbers(&sent), [1]);
    for want in [2, 3] {
        p.feed_line("ok", t);
        assert_eq!(numbers(&drain(&mut p, t).sent), [want]);
    }
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn bytes_in_flight_stay_under_the_receive_buffer() {
    let long = format!("M117 {}", "x".repeat(50));
    let (_, _, sent) = connected(&[&long, &long, &long], cfg());
    // Each framed line is ~62 bytes: two fit in 127, three do not.
    assert_eq!(numbers(&sent), [1, 2]);
    let total: usize = sent.iter().map(String::len).sum();
    assert!(total <= 127);
}

#[test]
fn every_resend_form_rewinds() {
    for form in [
        "Resend: 2",
        "Resend:2",
        "rs 2",
        "rs N2 Expected checksum 67",
    ] {
        let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
        p.feed_line("ok", t); // line 1 executed, line 4 goes out
        drain(&mut p, t);
        p.feed_line(form, t);
        p.feed_line("ok", t);
        // Lines 3 and 4 were in flight behind 2: wait for their rejections or the settle time.
        let d = drain(&mut p, t + Duration::from_secs(1));
        assert_eq!(numbers(&d.sent), [2, 3, 4], "{form}");
        assert!(d.events.contains(&Event::Resend { line: 2 }), "{form}");
        assert_eq!(p.stats().resends, 1);
    }
}

#[test]
fn resend_requests_from_lines_in_flight_are_not_replayed() {
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    // Line 1 corrupted: Marlin rejects it, then lines 2 and 3 as out of sequence.
    for first in [
        "Error:checksum mismatch, Last Line: 0",
        "Error:Line Number is not Last Line Number+1, Last Line: 0",
        "Error:Line Number is not Last Line Number+1, Last Line: 0",
    ] {
        p.feed_line(first, t);
        p.feed_line("Resend: 1", t);
        p.feed_line("ok", t);
    }
    let d = drain(&mut p, t);
    // All zombies accounted for: resend at once, once.
    assert_eq!(numbers(&d.sent), [1, 2, 3]);
    assert_eq!(p.stats().resends, 1);
    let mut events = vec![];
    for _ in 0..4 {
        p.feed_line("ok", t);
        events.extend(drain(&mut p, t).events);
    }
    assert!(events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn resend_without_ok_counts_as_acknowledged_after_settling() {
    let c = cfg();
    let settle = c.resend_settle;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3"], c);
    p.feed_line("Resend: 1", t);
    assert!(drain(&mut p, t).sent.is_empty(), "waits for zombies first");
    let d = drain(&mut p, t + settle);
    assert_eq!(numbers(&d.sent), [1, 2, 3]);
    // Next plain ok is an execution, not the resend's.
    p.feed_line("ok", t + settle);
    let d = drain(&mut p, t + settle);
    assert!(d.events.contains(&Event::Progress { executed: 1 }));
}

#[test]
fn error_without_resend_is_an_implicit_resend() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    p.feed_line("ok", t);
    drain(&mut p, t);
    p.feed_line("Error:checksum mismatch, Last Line: 1", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t + Duration::from_secs(1));
    assert_eq!(numbers(&d.sent), [2]);
}

#[test]
fn unknown_or_looping_resends_stop_the_job() {
    let c = Config {
        history: 2,
        ..cfg()
    };
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4", "G1 X5"], c);
    for _ in 0..3 {
        p.feed_line("ok", t);
    }
    drain(&mut p, t);
    p.feed_line("Resend: 9", t);
    let d = drain(&mut p, t);
    assert!(d.failed.is_none());
    assert!(
        d.events
            .iter()
            .any(|e| matches!(e, Event::Warning(w) if w.contains("never sent")))
    );
    p.feed_line("Resend: 1", t);
    let d = drain(&mut p, t);
    assert!(matches!(
        d.failed,
        Some(ProtocolError::ResendOutOfHistory { requested: 1, .. })
    ));

    let (mut p, mut t, _) = connected(&["G1 X1", "G1 X2"], Config { window: 1, ..cfg() });
    let mut failed = None;
    for _ in 0..20 {
        p.feed_line("Error:checksum mismatch, Last Line: 0", t);
        p.feed_line("Resend: 1", t);
        p.feed_line("ok", t);
        t += Duration::from_secs(1);
        let d = drain(&mut p, t);
        if d.failed.is_some() {
            failed = d.failed;
            break;
        }
    }
    let err = failed.expect("gave up").to_string();
    assert!(
        err.contains("line 1") && err.contains("times in a row"),
        "{err}"
    );
}

#[test]
fn silence_probes_then_stops_with_the_last_line() {
    let c = cfg();
    let timeout = c.timeout;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], c);
    p.feed_line("ok", t);
    drain(&mut p, t);
    let mut now = t;
    let mut probes = 0;
    let mut failed = None;
    for _ in 0..10 {
        now += timeout;
        let d = drain(&mut p, now);
        probes += d.sent.iter().filter(|s| *s == "M105\n").count();
        if let Some(f) = d.failed {
            failed = Some(f);
            break;
        }
    }
    assert_eq!(probes, 3);
    let err = failed.expect("stopped").to_string();
    assert!(
        err.contains("stopped answering") && err.contains("line 1"),
        "{err}"
    );
}

#[test]
fn busy_extends_the_timeout_and_long_commands_wait_longer() {
    let c = cfg();
    let (mut p, t, _) = connected(
        &["G28", "G1 X1"],
        Config {
            window: 1,
            ..c.clone()
        },
    );
    // G28 in flight: the normal timeout passes without a probe.
    let d = drain(&mut p, t + c.timeout * 2);
    assert!(d.sent.is_empty());
    // A plain move: busy every 2 s keeps it alive.
    p.feed_line("ok", t);
    let mut now = t;
    drain(&mut p, now);
    for _ in 0..10 {
        now += Duration::from_secs(2);
        p.feed_line("echo:busy: processing", now);
        assert!(drain(&mut p, now).sent.is_empty());
    }
    // Temperature chatter alone does not.
    now += c.timeout;
    p.feed_line(" T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0", now);
    assert_eq!(drain(&mut p, now).sent, ["M105\n"]);
}

#[test]
fn a_lost_ok_is_recovered_by_probe_and_resync() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
    p.feed_line("ok", t);
    p.feed_line("ok", t);
    // The ok for line 3 is lost.
    let now = t + cfg().timeout;
    assert_eq!(drain(&mut p, now).sent, ["M105\n"]);
    p.feed_line("ok T:20.0 /0.0 B:20.0 /0.0", now);
    let d = drain(&mut p, now);
    assert_eq!(
        numbers(&d.sent),
        [3],
        "resync sends the oldest unconfirmed line"
    );
    // The printer had it: it names its last line.
    p.feed_line(
        "Error:Line Number is not Last Line Number+1, Last Line: 3",
        now,
    );
    p.feed_line("Resend: 4", now);
    p.feed_line("ok", now);
    let d = drain(&mut p, now);
    assert!(d.events.contains(&Event::Progress { executed: 3 }));
    assert!(d.events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn start_mid_job_is_a_reset() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    p.feed_line("ok", t);
    p.feed_line("start", t);
    let err = drain(&mut p, t).failed.expect("failed").to_string();
    assert!(err.contains("reset") && err.contains("line 1"), "{err}");
}

#[test]
fn printer_errors_stop_the_job_and_unknown_commands_do_not() {
    let (mut p, t, _) = connected(&["G1 X1", "X99", "G1 X2"], cfg());
    p.feed_line("ok", t);
    p.feed_line("echo:Unknown command: \"X99\"", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.failed.is_none());
    assert!(
        d.events
            .iter()
            .any(|e| matches!(e, Event::Warning(w) if w.contains("X99")))
    );
    p.feed_line("Error:Printer halted. kill() called!", t);
    let err = drain(&mut p, t).failed.expect("failed").to_string();
    assert!(err.contains("Printer halted"), "{err}");
}

#[test]
fn temperatures_from_ok_and_auto_report() {
    let (mut p, t, _) = connected(&["M105", "G1 X1"], cfg());
    p.feed_line("ok T:200.0 /210.0 B:60.0 /60.0 @:0 B@:0", t);
    p.feed_line(" T:201.0 /210.0 B:60.0 /60.0 @:0 B@:0", t);
    p.feed_line("T0:100.0 /0.0 T1:50.00/ 60.00", t);
    let temps: Vec<Temperatures> = drain(&mut p, t)
        .events
        .into_iter()
        .filter_map(|e| match e {
            Event::Temperatures(t) => Some(t),
            _ => None,
        })
        .collect();
    assert_eq!(temps.len(), 3);
    assert_eq!(temps[0].tools[0].target, Some(210.0));
    assert_eq!(temps[1].tools[0].actual, 201.0);
    assert_eq!(temps[2].tools[1].target, Some(60.0));
}

#[test]
fn host_actions_pause_resume_cancel() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4", "G1 X5"], cfg());
    p.feed_line("//action:pause", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.events.contains(&Event::Paused(true)));
    assert!(d.sent.is_empty(), "paused: nothing new");
    p.feed_line("//action:resume", t);
    assert_eq!(numbers(&drain(&mut p, t).sent), [4]);
    p.feed_line("//action:cancel", t);
    let mut sent = drain(&mut p, t).sent;
    let mut events = vec![];
    for _ in 0..6 {
        p.feed_line("ok", t);
        let d = drain(&mut p, t);
        sent.extend(d.sent);
        events.extend(d.events);
    }
    let all: Vec<_> = sent
        .iter()
        .map(|s| s.split('*').next().unwrap_or("").to_string())
        .collect();
    // Line 5 was never sent: the shutdown takes its number.
    assert_eq!(all, ["N5 M104 S0", "N6 M140 S0", "N7 M84"]);
    assert!(events.contains(&Event::Finished { cancelled: true }));
}

#[test]
fn emergency_cancel_sends_m112() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    p.cancel(true);
    let d = drain(&mut p, t);
    assert_eq!(d.sent, ["M112\n"]);
    assert!(d.events.contains(&Event::Finished { cancelled: true }));
}

#[test]
fn advanced_ok_follows_the_free_slot_count() {
    let (mut p, t, sent) = connected(
        &[
            "G1 X1", "G1 X2", "G1 X3", "G1 X4", "G1 X5", "G1 X6", "G1 X7",
        ],
        cfg(),
    );
    assert_eq!(numbers(&sent), [1, 2, 3]);
    // Lines 1-3 received, 1 executed, 2 slots free: two more may go.
    p.feed_line("ok N3 P15 B2", t);
    assert_eq!(numbers(&drain(&mut p, t).sent), [4, 5]);
    // Nothing more received, no slot free: wait.
    p.feed_line("ok N3 P15 B0", t);
    assert!(drain(&mut p, t).sent.is_empty());
}

#[test]
fn connects_on_start_and_gives_up_without_answer() {
    let t = Instant::now();
    let mut p = Protocol::new(commands(&job(2)), cfg(), t);
    drain(&mut p, t);
    p.feed_line("start", t);
    assert!(drain(&mut p, t).sent.is_empty(), "boot chatter first");
    let d = drain(&mut p, t + Duration::from_secs(1));
    assert!(d.events.contains(&Event::Connected));

    let mut p = Protocol::new(commands(&job(2)), cfg(), t);
    let mut probes = 0;
    let mut failed = None;
    for s in 0..20 {
        let d = drain(&mut p, t + Duration::from_secs(s));
        probes += d.sent.len();
        if d.failed.is_some() {
            failed = d.failed;
            break;
        }
    }
    assert!(probes >= 10, "kept asking with M105");
    assert!(matches!(failed, Some(ProtocolError::NoConnection { .. })));
}

#[test]
fn sim_clean_run_executes_everything_once() {
    let j = job(500);
    let mut sim = Sim::new(&j, cfg(), FirmwareConfig::default(), 1);
    let out = sim.run(200_000);
    assert!(
        matches!(out, Outcome::Finished { cancelled: false }),
        "{out:?}"
    );
    assert_eq!(sim.executed_job(), j);
    assert_eq!(sim.proto.stats().resends, 0);
    assert_eq!(sim.fw.lost_bytes(), 0, "flow control kept within 128 bytes");
}

fn faulty_run(faults: Faults, window: usize, n: usize, seed: u64) -> (Outcome, Sim, Vec<String>) {
    let j = job(n);
    let c = Config { window, ..cfg() };
    let fw = FirmwareConfig {
        faults,
        ..FirmwareConfig::default()
    };
    let mut sim = Sim::new(&j, c, fw, seed);
    let out = sim.run(2_000_000);
    (out, sim, j)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random corruption both ways, drops, lost oks, spurious and ok-less resends, on random
    /// windows and link chunking: every command executes exactly once, in order.
    #[test]
    fn faults_never_lose_or_repeat_a_command(
        seed in any::<u64>(),
        corrupt in 0.0..0.08f64,
        corrupt_reply in 0.0..0.02f64,
        drop in 0.0..0.04f64,
        drop_ok in 0.0..0.03f64,
        error in 0.0..0.03f64,
        spurious_resend in 0.0..0.03f64,
        no_resend_ok in 0.0..0.5f64,
        busy in 0.0..0.05f64,
        advanced_ok in any::<bool>(),
        window in 1usize..6,
        chunk in prop::sample::select(vec![1usize, 7, 64, 512]),
    ) {
        let faults = Faults {
            corrupt, corrupt_reply, drop, drop_ok, error, spurious_resend, no_resend_ok, busy,
            advanced_ok, seed, ..Faults::default()
        };
        let j = job(250);
        let c = Config { window, ..cfg() };
        let fw = FirmwareConfig { faults, ..FirmwareConfig::default() };
        let mut sim = Sim::new(&j, c, fw, seed ^ 0x5eed);
        sim.chunk = chunk;
        let out = sim.run(3_000_000);
        prop_assert!(matches!(out, Outcome::Finished { cancelled: false }), "{:?}\n{}\n{}", out, sim.fw.describe(), sim.trace.iter().cloned().collect::<Vec<_>>().join("\n"));
        let done = sim.executed_job();
        prop_assert!(done == j, "executed {} of {}\n{}", done.len(), j.len(), sim.trace.iter().cloned().collect::<Vec<_>>().join("\n"));
    }
}

#[test]
fn reset_mid_job_stops_with_reset_error() {
    let faults = Faults {
        reset_at: Some(100),
        ..Faults::default()
    };
    let (out, sim, j) = faulty_run(faults, 3, 300, 3);
    assert!(
        matches!(out, Outcome::Failed(ProtocolError::PrinterReset { .. })),
        "{out:?}"
    );
    // What executed is a prefix of the job, each once, and at least what was acknowledged.
    let done = sim.executed_job();
    assert_eq!(done[..], j[..done.len()]);
    assert!(sim.proto.executed() <= done.len());
}
