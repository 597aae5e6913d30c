//! The protocol against the firmware model of every dialect, through the simulated link:
//! under every fault the model injects, each command executes exactly once, in order.

use proptest::prelude::*;

use super::*;
use crate::dialect::Dialect;
use crate::fake::{Faults, FirmwareConfig};
use crate::sim::{Outcome, Sim, job};

/// Runs a job of `n` commands and asserts it completed with every command once, in order;
/// on failure shows the link around the first wrong command.
fn run_clean(what: &str, dialect: Dialect, faults: Faults, window: usize, n: usize) -> Sim {
    let j = job(n);
    let seed = faults.seed;
    let fw = FirmwareConfig {
        faults,
        dialect,
        ..FirmwareConfig::default()
    };
    let mut sim = Sim::new(&j, Config { window, ..cfg() }, fw, seed ^ 0x5eed);
    sim.trace_len = 50_000;
    let out = sim.run(5_000_000);
    let done = sim.executed_job();
    if done != j || !matches!(out, Outcome::Finished { cancelled: false }) {
        let i = (0..done.len().min(j.len()))
            .find(|&i| done[i] != j[i])
            .unwrap_or(done.len().min(j.len()));
        let key = done.get(i).or(j.get(i)).cloned().unwrap_or_default();
        let at = sim
            .trace
            .iter()
            .position(|l| l.contains(&format!(" {key}*")))
            .unwrap_or(sim.trace.len().saturating_sub(40));
        let around: Vec<_> = sim
            .trace
            .iter()
            .skip(at.saturating_sub(30))
            .take(60)
            .cloned()
            .collect();
        panic!(
            "{what} ({dialect}, window {window}, seed {seed}): {out:?}; command {i} executed \
             {:?}, the job has {:?} ({} of {} executed)\n{}\nfirmware: {}\n{}",
            done.get(i),
            j.get(i),
            done.len(),
            j.len(),
            sim.proto.describe(),
            sim.fw.describe(),
            around.join("\n")
        );
    }
    sim
}

#[test]
fn a_clean_link_sends_nothing_twice_and_probes_nothing() {
    for dialect in Dialect::ALL {
        let sim = run_clean("clean", dialect, Faults::default(), 3, 500);
        let s = sim.proto.stats();
        assert_eq!((s.resends, s.probes, s.renumbers), (0, 0, 0), "{dialect}");
        assert_eq!(s.lines_sent, 501, "{dialect}: M110 and the job, once each");
        assert_eq!(sim.fw.lost_bytes(), 0, "flow control kept within 128 bytes");
    }
}

/// Every fault the model injects, one kind at a time, on every dialect that can recover
/// from it (Klipper checks no line numbers, so nothing can bring back a damaged or lost
/// line there; its link is a local pipe that damages nothing).
#[test]
fn every_fault_on_every_dialect() {
    let kinds = [
        (
            "corrupt",
            Faults {
                corrupt: 0.02,
                ..Faults::default()
            },
        ),
        (
            "corrupt-reply",
            Faults {
                corrupt_reply: 0.01,
                ..Faults::default()
            },
        ),
        (
            "drop",
            Faults {
                drop: 0.01,
                ..Faults::default()
            },
        ),
        (
            "drop-ok",
            Faults {
                drop_ok: 0.01,
                ..Faults::default()
            },
        ),
        (
            "error",
            Faults {
                error: 0.01,
                ..Faults::default()
            },
        ),
        (
            "spurious-resend",
            Faults {
                spurious_resend: 0.01,
                ..Faults::default()
            },
        ),
        (
            "no-resend-ok",
            Faults {
                corrupt: 0.02,
                no_resend_ok: 0.5,
                ..Faults::default()
            },
        ),
        (
            "busy",
            Faults {
                busy: 0.02,
                ..Faults::default()
            },
        ),
        (
            "advanced-ok",
            Faults {
                corrupt: 0.02,
                advanced_ok: true,
                ..Faults::default()
            },
        ),
    ];
    for dialect in Dialect::ALL {
        for (what, f) in &kinds {
            let lossless_link = matches!(*what, "corrupt-reply" | "drop-ok" | "busy");
            if !dialect.checks_lines() && !lossless_link {
                continue;
            }
            for (seed, window) in [(1, 3), (2, 1)] {
                run_clean(what, dialect, Faults { seed, ..f.clone() }, window, 600);
            }
        }
    }
}

/// A job of 250 commands under `faults`, as the random hunt below runs it: it must finish,
/// with every command executed once, in order, and never overrun the receive buffer.
fn run_mix(
    dialect: Dialect,
    faults: Faults,
    window: usize,
    chunk: usize,
) -> Result<(), TestCaseError> {
    let seed = faults.seed;
    let j = job(250);
    let fw = FirmwareConfig {
        faults,
        dialect,
        ..FirmwareConfig::default()
    };
    let mut sim = Sim::new(&j, Config { window, ..cfg() }, fw, seed ^ 0x5eed);
    sim.chunk = chunk;
    let out = sim.run(3_000_000);
    let trace = || sim.trace.iter().cloned().collect::<Vec<_>>().join("\n");
    prop_assert!(
        matches!(out, Outcome::Finished { cancelled: false }),
        "{out:?}\n{}\n{}",
        sim.proto.describe(),
        trace()
    );
    let done = sim.executed_job();
    prop_assert!(
        done == j,
        "executed {} of {}\n{}",
        done.len(),
        j.len(),
        trace()
    );
    prop_assert_eq!(
        sim.fw.lost_bytes(),
        0,
        "overran the receive buffer\n{}",
        trace()
    );
    Ok(())
}

proptest! {
    // PROPTEST_CASES raises the count for a longer hunt.
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(48),
        ..ProptestConfig::default()
    })]

    /// Random mixes of every fault at once, on random dialects, windows and link chunking.
    #[test]
    fn faults_never_lose_or_repeat_a_command(
        seed in any::<u64>(),
        dialect in prop::sample::select(
            Dialect::ALL.into_iter().filter(|d| d.checks_lines()).collect::<Vec<_>>()
        ),
        corrupt in 0.0..0.05f64,
        corrupt_reply in 0.0..0.02f64,
        drop in 0.0..0.03f64,
        drop_ok in 0.0..0.03f64,
        error in 0.0..0.02f64,
        spurious_resend in 0.0..0.02f64,
        no_resend_ok in 0.0..0.5f64,
        busy in 0.0..0.05f64,
        advanced_ok in any::<bool>(),
        window in 1usize..5,
        chunk in prop::sample::select(vec![1usize, 7, 64, 512]),
    ) {
        let faults = Faults {
            corrupt, corrupt_reply, drop, drop_ok, error, spurious_resend, no_resend_ok, busy,
            advanced_ok, seed, ..Faults::default()
        };
        run_mix(dialect, faults, window, chunk)?;
    }
}

/// Mixes the hunt above found (40,000 cases at a time), each with what it exposed. The
/// proptest regression file replays them too; here they are named, and kept when a
/// shrunk input has no seed line of its own.
#[test]
fn mixes_that_once_failed() {
    // (what it exposed, dialect, window, chunk, advanced_ok, seed,
    //  [corrupt, corrupt_reply, drop, drop_ok, error, spurious_resend, no_resend_ok, busy])
    type Mix = (&'static str, Dialect, usize, usize, bool, u64, [f64; 8]);
    let mixes: [Mix; 9] = [
        (
            "an `ok` from the connection taken for M110's: line 1 ran twice",
            Dialect::Smoothie,
            2,
            64,
            false,
            15145023834887848096,
            [
                0.029078641460870882,
                0.009091384115909665,
                0.019326772518353116,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
        ),
        (
            "a probe answered with a damaged line counted as unanswered: the job stopped",
            Dialect::RepRapFirmware,
            3,
            1,
            false,
            16327628312596882553,
            [
                0.006080354866494309,
                0.016424190275947406,
                0.02288951958398901,
                0.0,
                0.011528278315541372,
                0.016140384538090708,
                0.0,
                0.01930804525783218,
            ],
        ),
        (
            "the resent line's `ok` taken for an `rs` refusal's; three lines lost in a row",
            Dialect::RepRapFirmware,
            1,
            1,
            true,
            11298467896925845781,
            [
                0.0162662322305883,
                0.008218077159918749,
                0.018786999393621447,
                0.029484252630284584,
                0.019485808718661117,
                0.006248548232070621,
                0.0,
                0.020160296203496655,
            ],
        ),
        (
            "a renumbering waited for lines sent past it: the job stalled",
            Dialect::OctoPrintVirtual,
            2,
            1,
            true,
            1217794692488968532,
            [
                0.0306933386280603,
                0.00998640403958726,
                0.0040477833076483566,
                0.023601311209591348,
                0.01758813437175741,
                0.0002965647966544875,
                0.17224121442174692,
                0.04658783496623664,
            ],
        ),
        (
            "an error acted on after the watchdog's line: two lines ran twice",
            Dialect::OctoPrintVirtual,
            1,
            1,
            true,
            14753867694463266175,
            [
                0.04863355287224217,
                0.018185914228891552,
                0.026957464165462998,
                0.013905183084506693,
                0.007205901822054283,
                0.002435282698299599,
                0.16345717032905172,
                0.008058698734006772,
            ],
        ),
        (
            "a request for an earlier line taken as a drift: M110 skipped a line",
            Dialect::OctoPrintVirtual,
            1,
            1,
            true,
            14753868573862361582,
            [
                0.04863355287224217,
                0.018185914228891552,
                0.026957464165462998,
                0.013905183084506693,
                0.007205901822054283,
                0.002435282698299599,
                0.16345717032905172,
                0.008058698734006772,
            ],
        ),
        (
            "probes behind an answered M105 counted done: the receive buffer overran",
            Dialect::Repetier,
            2,
            512,
            true,
            3914325046441994744,
            [
                0.04299414081424383,
                0.004677836640245668,
                0.00818942264991054,
                0.00282130031110501,
                0.006564317293531284,
                0.01494454027446298,
                0.17293191599797264,
                0.04164800014158537,
            ],
        ),
        (
            "a damaged ADVANCED_OK `ok` taken for a line's: M110 ran under the lines after it",
            Dialect::Marlin,
            1,
            64,
            true,
            11565997248057540677,
            [
                0.027157292124632575,
                0.010794869840468345,
                0.012676980021398337,
                0.006324517949848798,
                0.00047920412958955686,
                0.01618309099528992,
                0.27665498345180833,
                0.04948809979807841,
            ],
        ),
        (
            "Repetier, every fault: the job stopped",
            Dialect::Repetier,
            1,
            1,
            true,
            4776005614806705106,
            [
                0.012058098922576657,
                0.018060679893141317,
                0.022362663843936835,
                0.023584034948168957,
                0.007852940668091756,
                0.004763835863097889,
                0.1549015068620372,
                5.274796968327597e-5,
            ],
        ),
    ];
    for (what, dialect, window, chunk, advanced_ok, seed, r) in mixes {
        let faults = Faults {
            corrupt: r[0],
            corrupt_reply: r[1],
            drop: r[2],
            drop_ok: r[3],
            error: r[4],
            spurious_resend: r[5],
            no_resend_ok: r[6],
            busy: r[7],
            advanced_ok,
            seed,
            ..Faults::default()
        };
        if let Err(e) = run_mix(dialect, faults, window, chunk) {
            panic!("{what} ({dialect}, seed {seed}): {e}");
        }
    }
}

#[test]
fn reset_mid_job_stops_with_reset_error() {
    let faults = Faults {
        reset_at: Some(100),
        seed: 3,
        ..Faults::default()
    };
    let j = job(300);
    let fw = FirmwareConfig {
        faults,
        ..FirmwareConfig::default()
    };
    let mut sim = Sim::new(&j, cfg(), fw, 3);
    let out = sim.run(2_000_000);
    assert!(
        matches!(out, Outcome::Failed(ProtocolError::PrinterReset { .. })),
        "{out:?}"
    );
    // What executed is a prefix of the job, each once, and at least what was acknowledged.
    let done = sim.executed_job();
    assert_eq!(done[..], j[..done.len()]);
    assert!(sim.proto.executed() <= done.len());
}

/// A probe whose `ok` is taken for another line's leaves a line counted in flight; the
/// printer answered after the probe went out, so the next probe comes at the quiet pace, not
/// after the full timeout. Before, each such episode stalled 5 s: this mix ran 644 simulated
/// seconds for 30,000 commands, now about 32.
#[test]
fn every_fault_at_once_does_not_stall_on_timeouts() {
    let text = crate::sample::vase_with_commands(30_000);
    let j: Vec<String> = crate::gcode::parse(&text)
        .expect("the sample parses")
        .commands
        .into_iter()
        .map(|c| c.text)
        .collect();
    let fw = FirmwareConfig {
        faults: Faults::parse(
            "corrupt=0.005,corrupt-reply=0.002,drop=0.002,drop-ok=0.002,error=0.002,\
             spurious-resend=0.002,no-resend-ok=0.3,busy=0.005,seed=29",
        )
        .expect("a valid spec"),
        ..FirmwareConfig::default()
    };
    let mut sim = Sim::new(&j, cfg(), fw, 29);
    let start = sim.now;
    let out = sim.run(50_000_000);
    assert!(
        matches!(out, Outcome::Finished { cancelled: false }),
        "{out:?}"
    );
    assert_eq!(sim.executed_job(), j);
    let took = sim.now - start;
    assert!(
        took < std::time::Duration::from_secs(120),
        "{took:?} simulated"
    );
}

#[test]
fn a_reply_in_the_instant_a_probe_goes_out_counts_as_after_it() {
    // Every fault at once, Marlin, seed 0: after a resend the host steps forward with a line
    // as its probe, and the printer's `ok` is read in the same instant (one loop of the
    // streamer). Compared by the clock it looked earlier than the probe, so the host waited
    // out the whole 5 s timeout: 6.5 s of simulated time for the job. Heard as after the
    // probe, the host asks again at the printer's pace.
    let faults =
        Faults::parse("corrupt=0.01,drop=0.005,error=0.005,drop-ok=0.005,busy=0.01,seed=0")
            .expect("spec");
    let sim = run_clean("every fault", Dialect::Marlin, faults, 3, 1000);
    let events = sim
        .events
        .iter()
        .filter(|e| matches!(e, Event::Probe { .. }))
        .count();
    assert!(events > 0, "the faults made the host probe");
    let elapsed = sim.now.duration_since(sim.start);
    assert!(
        elapsed < std::time::Duration::from_secs(3),
        "simulated time {elapsed:?}: a probe's answer was waited out"
    );
}
