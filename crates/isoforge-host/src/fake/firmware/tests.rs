//! The firmware model against Marlin's documented behaviour.

use std::time::Instant;

use super::*;
use crate::gcode::frame;

fn fw(faults: Faults) -> Firmware {
    let mut f = Firmware::new(FirmwareConfig {
        faults,
        ..FirmwareConfig::default()
    });
    while f.take_output().is_some() {}
    f
}

fn run(f: &mut Firmware) -> Vec<String> {
    let now = Instant::now();
    while f.step(now) {}
    std::iter::from_fn(|| f.take_output()).collect()
}

#[test]
fn boots_with_start() {
    let mut f = Firmware::new(FirmwareConfig::default());
    assert_eq!(f.take_output().as_deref(), Some("start"));
}

#[test]
fn executes_numbered_lines_in_order_with_ok() {
    let mut f = fw(Faults::default());
    f.receive(frame(0, "M110 N0", 0).unwrap().as_bytes());
    f.receive(frame(1, "G28", 1).unwrap().as_bytes());
    f.receive(b"M105\n");
    let out = run(&mut f);
    assert_eq!(out[0], "ok");
    assert_eq!(out[1], "ok");
    assert!(out[2].starts_with("ok T:"), "{out:?}");
    let e = f.executed();
    assert_eq!(
        e[1],
        Executed {
            line: Some(1),
            command: "G28".into()
        }
    );
    assert_eq!(e[2].line, None);
}

#[test]
fn line_number_is_checked_before_checksum() {
    let mut f = fw(Faults::default());
    // Wrong number and wrong checksum: Marlin reports the number.
    f.receive(b"N5 G28*1\n");
    let out = run(&mut f);
    assert_eq!(
        out,
        [
            "Error:Line Number is not Last Line Number+1, Last Line: 0",
            "Resend: 1",
            "ok"
        ]
    );
    f.receive(b"N1 G28*1\n");
    assert_eq!(run(&mut f)[0], "Error:checksum mismatch, Last Line: 0");
    f.receive(b"N1 G28\n");
    assert_eq!(
        run(&mut f)[0],
        "Error:No Checksum with line number, Last Line: 0"
    );
    assert!(f.executed().is_empty());
}

#[test]
fn an_error_drains_the_receive_buffer() {
    let mut f = fw(Faults::default());
    let mut bytes = b"N9 G1 X1*1\n".to_vec();
    bytes.extend(frame(1, "G1 X2", 0).unwrap().as_bytes());
    f.receive(&bytes);
    let out = run(&mut f);
    // The good line behind the bad one was flushed with it: one error, nothing executed.
    assert_eq!(out.iter().filter(|l| l.starts_with("Error")).count(), 1);
    assert!(f.executed().is_empty());
}

#[test]
fn bytes_beyond_the_receive_buffer_are_lost() {
    let mut f = fw(Faults::default());
    let mut bytes = Vec::new();
    for n in 1..=10 {
        bytes.extend(
            frame(n, "G1 X100.000 Y100.000 E1.00000", 0)
                .unwrap()
                .as_bytes(),
        );
    }
    f.receive(&bytes);
    assert!(f.lost_bytes() > 0);
    let out = run(&mut f);
    assert_eq!(
        out,
        ["ok", "ok", "ok"],
        "three whole lines fit in 128 bytes"
    );
    // The cut fourth line merges with the next one and is refused.
    f.receive(frame(11, "G1 X1", 0).unwrap().as_bytes());
    let out = run(&mut f);
    assert_eq!(out.get(1).map(String::as_str), Some("Resend: 4"), "{out:?}");
}

#[test]
fn heating_blocks_with_busy_and_temperatures() {
    let mut f = fw(Faults::default());
    f.receive(b"M109 S200\nM105\n");
    let out = run(&mut f);
    assert!(out.iter().any(|l| l == "echo:busy: processing"));
    assert!(
        out.iter()
            .any(|l| l.starts_with(" T:") && l.contains("/200.0"))
    );
    let last = out.last().unwrap();
    assert!(last.starts_with("ok T:200.0 /200.0"), "{out:?}");
}

#[test]
fn m112_halts_at_once() {
    let mut f = fw(Faults::default());
    f.receive(b"M112\n");
    assert!(f.is_dead());
    assert_eq!(run(&mut f), ["Error:Printer halted. kill() called!"]);
    f.receive(b"M105\n");
    assert!(run(&mut f).is_empty());
}

#[test]
fn advanced_ok_reports_line_and_free_slots() {
    let mut f = fw(Faults {
        advanced_ok: true,
        ..Faults::default()
    });
    f.receive(frame(1, "G1 X1", 0).unwrap().as_bytes());
    let out = run(&mut f);
    assert_eq!(out, ["ok N1 P15 B4"]);
}

#[test]
fn one_shot_events() {
    let mut f = fw(Faults {
        reset_at: Some(2),
        ..Faults::default()
    });
    for n in 1..=3 {
        f.receive(frame(n, "G1 X1", 0).unwrap().as_bytes());
    }
    let out = run(&mut f);
    assert_eq!(out[..3], ["ok", "ok", "start"]);
    assert_eq!(f.executed().len(), 2);

    let mut f = fw(Faults {
        halt_at: Some(1),
        ..Faults::default()
    });
    f.receive(frame(1, "G1 X1", 0).unwrap().as_bytes());
    assert_eq!(run(&mut f), ["ok", "Error:Printer halted. kill() called!"]);

    let mut f = fw(Faults {
        silent_at: Some(1),
        ..Faults::default()
    });
    f.receive(frame(1, "G1 X1", 0).unwrap().as_bytes());
    f.receive(frame(2, "G1 X1", 0).unwrap().as_bytes());
    assert_eq!(run(&mut f), ["ok"]);
}

#[test]
fn unknown_commands_are_reported() {
    let mut f = fw(Faults::default());
    f.receive(b"X99\n");
    assert_eq!(run(&mut f), ["echo:Unknown command: \"X99\"", "ok"]);
}
