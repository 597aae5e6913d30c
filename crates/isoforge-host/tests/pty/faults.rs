//! Streaming a 20,000-command job to the fake printer over a real pty, one fault at a time:
//! the printer's executed record must equal the file's commands, each exactly once, in order.

use crate::support::*;
use isoforge_host::fake::Faults;

fn stream_with(faults: Faults, what: &str) -> isoforge_host::streamer::Report {
    let (_, program) = vase(JOB_COMMANDS);
    let printer = fake(faults);
    let report = print(&printer, &program, 0, vec![], None);
    assert!(report.completed, "{what}: {:?}", report.error);
    assert_same(&job_commands(&printer.executed()), &texts(&program), what);
    report
}

#[test]
fn clean_link() {
    let r = stream_with(Faults::default(), "clean");
    assert_eq!(r.resends, 0);
}

#[test]
fn corrupted_bytes_host_to_printer() {
    let r = stream_with(
        Faults {
            corrupt: 0.01,
            seed: 1,
            ..Faults::default()
        },
        "corrupt",
    );
    assert!(r.resends > 50, "corruption caused resends: {}", r.resends);
}

#[test]
fn corrupted_bytes_printer_to_host() {
    stream_with(
        Faults {
            corrupt_reply: 0.005,
            seed: 2,
            ..Faults::default()
        },
        "corrupt-reply",
    );
}

#[test]
fn dropped_lines() {
    let r = stream_with(
        Faults {
            drop: 0.005,
            seed: 3,
            ..Faults::default()
        },
        "drop",
    );
    assert!(r.resends > 20, "{}", r.resends);
}

#[test]
fn dropped_oks() {
    stream_with(
        Faults {
            drop_ok: 0.001,
            seed: 4,
            ..Faults::default()
        },
        "drop-ok",
    );
}

#[test]
fn errors_without_resend() {
    stream_with(
        Faults {
            error: 0.005,
            seed: 5,
            ..Faults::default()
        },
        "error",
    );
}

#[test]
fn spurious_resends() {
    let r = stream_with(
        Faults {
            spurious_resend: 0.005,
            seed: 6,
            ..Faults::default()
        },
        "spurious-resend",
    );
    assert!(r.resends > 20, "{}", r.resends);
}

#[test]
fn resends_without_ok() {
    stream_with(
        Faults {
            corrupt: 0.01,
            no_resend_ok: 0.5,
            seed: 7,
            ..Faults::default()
        },
        "no-resend-ok",
    );
}

#[test]
fn busy_printer() {
    stream_with(
        Faults {
            busy: 0.01,
            seed: 8,
            ..Faults::default()
        },
        "busy",
    );
}

#[test]
fn advanced_ok_with_corruption() {
    stream_with(
        Faults {
            advanced_ok: true,
            corrupt: 0.01,
            seed: 9,
            ..Faults::default()
        },
        "advanced-ok",
    );
}
