//! Reply forms and flows, one at a time, on a hand-fed protocol.

use super::*;

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
fn every_resend_form_goes_back_and_sends_the_refused_line_alone() {
    for form in [
        "Resend: 2",
        "Resend:2",
        "rs 2",
        "rs N2",
        "rs N2 Expected checksum 67",
    ] {
        let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
        p.feed_line("ok", t); // line 1 executed, line 4 goes out
        drain(&mut p, t);
        p.feed_line(form, t);
        p.feed_line("ok", t); // the refusal's
        // Lines 3 and 4 were in flight behind 2: after their refusals or the settle time,
        // line 2 goes again, alone.
        let d = drain(&mut p, t + Duration::from_secs(1));
        assert_eq!(numbers(&d.sent), [2], "{form}");
        assert!(d.events.contains(&Event::Resend { line: 2 }), "{form}");
        // Taken: the count is set again (nothing in flight), then the rest goes.
        let now = t + Duration::from_secs(1);
        p.feed_line("ok", now);
        let d = drain(&mut p, now);
        assert_eq!(bodies(&d.sent), ["N2 M110 N2"], "{form}");
        p.feed_line("ok", now);
        assert_eq!(numbers(&drain(&mut p, now).sent), [3, 4], "{form}");
        assert_eq!(p.stats().resends, 1, "{form}");
    }
}

#[test]
fn refusals_of_the_lines_behind_are_not_acted_on() {
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    // Line 1 damaged: Marlin refuses it, then lines 2 and 3 as out of sequence.
    for first in [
        "Error:checksum mismatch, Last Line: 0",
        "Error:Line Number is not Last Line Number+1, Last Line: 0",
        "Error:Line Number is not Last Line Number+1, Last Line: 0",
    ] {
        p.feed_line(first, t);
        p.feed_line("Resend: 1", t);
        p.feed_line("ok", t);
    }
    // Every refusal accounted for: no settle wait; line 1 once.
    let d = drain(&mut p, t);
    assert_eq!(numbers(&d.sent), [1]);
    assert_eq!(p.stats().resends, 1);
    let mut events = vec![];
    let mut sent = vec![];
    for _ in 0..6 {
        p.feed_line("ok", t);
        let d = drain(&mut p, t);
        sent.extend(d.sent);
        events.extend(d.events);
    }
    // The count set again, lines 2 and 3, then a numbered M105 before calling it done.
    assert_eq!(
        bodies(&sent),
        ["N1 M110 N1", "N2 G1 X2", "N3 G1 X3", "N4 M105"]
    );
    assert!(events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn a_resend_request_without_its_ok() {
    let c = cfg();
    let settle = c.resend_settle;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3"], c);
    p.feed_line("Resend: 1", t);
    assert!(
        drain(&mut p, t).sent.is_empty(),
        "waits for the refusals behind"
    );
    let now = t + settle * 2;
    assert_eq!(numbers(&drain(&mut p, now).sent), [1]);
    // The next plain ok is line 1 executing, not the request's.
    p.feed_line("ok", now);
    let d = drain(&mut p, now);
    assert!(d.events.contains(&Event::Progress { executed: 1 }));
}

#[test]
fn an_error_naming_the_last_line_without_a_request_asks_for_the_next_after_a_grace() {
    let c = cfg();
    let grace = c.error_grace;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], c);
    p.feed_line("ok", t);
    drain(&mut p, t);
    p.feed_line("Error:No Line Number with checksum, Last Line: 1", t);
    assert!(drain(&mut p, t).sent.is_empty());
    let d = drain(&mut p, t + grace);
    assert_eq!(numbers(&d.sent), [2]);
    assert!(d.events.contains(&Event::Resend { line: 2 }));
}

#[test]
fn a_refusal_without_a_count_or_request_is_asked_about() {
    let c = cfg();
    let grace = c.error_grace;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], c);
    p.feed_line("ok", t);
    drain(&mut p, t);
    // The virtual printer's wording, with neither a request nor an `ok`.
    p.feed_line("Error: Missing checksum", t);
    let d = drain(&mut p, t + grace);
    assert_eq!(bodies(&d.sent), ["N3 M105"], "a numbered probe asks");
    // The firmware has not taken line 2: it refuses the probe and names the line.
    p.feed_line("Error: expected line 2 got 3", t + grace);
    p.feed_line("Resend:2", t + grace);
    p.feed_line("ok", t + grace);
    let d = drain(&mut p, t + grace * 2);
    assert_eq!(numbers(&d.sent), [2]);
}

#[test]
fn an_error_the_table_does_not_know_is_a_warning() {
    let c = cfg();
    let grace = c.error_grace;
    let (mut p, t, _) = connected(&["G29", "G1 X1"], c);
    p.feed_line("Error:Probing failed on point 3", t);
    let d = drain(&mut p, t + grace);
    assert!(d.failed.is_none());
    assert!(has_warning(&d.events, "Probing failed"));
    p.feed_line("ok", t + grace);
    p.feed_line("ok", t + grace);
    let d = drain(&mut p, t + grace);
    assert!(d.events.contains(&Event::Progress { executed: 2 }));
}

#[test]
fn fatal_errors_of_every_firmware_stop_the_job() {
    for lines in [
        vec!["Error:Printer halted. kill() called!"],
        vec!["Error:Thermal Runaway, system stopped! Heater_ID: 0"],
        vec!["Error:MINTEMP triggered, system stopped! Heater_ID: bed"],
        vec!["Error: MAXTEMP triggered!"],
        vec!["Error:Printer stopped due to errors. Fix the error and use M999 to restart."],
        vec!["Error:0", ": Extruder switched off. MAXTEMP triggered !"],
        vec!["!! Lost communication with MCU 'mcu'"],
        vec!["fatal:Heater/sensor failure. Printer stopped and heaters disabled."],
    ] {
        let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
        p.feed_line("ok", t);
        for l in &lines {
            p.feed_line(l, t);
        }
        let err = drain(&mut p, t).failed.map(|e| e.to_string());
        let err = err.unwrap_or_else(|| panic!("{lines:?} did not stop the job"));
        assert!(
            err.contains("stopped with an error") && err.contains("job command 1"),
            "{err}"
        );
    }
}

#[test]
fn a_request_for_the_line_after_the_last_sent_loses_nothing() {
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    // The virtual printer's answer to a line it already has.
    p.feed_line("Error: expected line 4 got 3", t);
    p.feed_line("Resend:4", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.sent.is_empty(), "nothing to send again: {:?}", d.sent);
    let mut sent = vec![];
    let mut events = vec![];
    for _ in 0..4 {
        p.feed_line("ok", t);
        let d = drain(&mut p, t);
        sent.extend(d.sent);
        events.extend(d.events);
    }
    assert_eq!(bodies(&sent), ["N4 M105"]);
    assert!(events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn requests_never_sent_out_of_history_or_looping() {
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
    assert!(has_warning(&d.events, "never sent"));
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
fn silence_is_probed_with_numbered_m105_then_reported() {
    let c = cfg();
    let timeout = c.timeout;
    let max_probes = c.max_probes as usize;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], c);
    p.feed_line("ok", t);
    drain(&mut p, t);
    let mut now = t;
    let mut probes = vec![];
    let mut failed = None;
    for _ in 0..20 {
        now += timeout;
        let d = drain(&mut p, now);
        probes.extend(d.sent);
        if let Some(f) = d.failed {
            failed = Some(f);
            break;
        }
    }
    assert_eq!(probes.len(), max_probes, "{probes:?}");
    assert!(
        probes
            .iter()
            .all(|s| s.starts_with('N') && s.contains(" M105*"))
    );
    let err = failed.expect("stopped").to_string();
    assert!(
        err.contains("stopped answering") && err.contains("job command 1"),
        "{err}"
    );
}

#[test]
fn a_probe_answered_with_a_damaged_line_was_answered() {
    // On a noisy link a line was lost, then the answer to the first probe was damaged
    // (`rs\u{fffd}212`), then the next probe was lost: counted as three unanswered probes,
    // that once ended a job with the printer still talking.
    let c = cfg();
    let timeout = c.timeout;
    let max_probes = c.max_probes as usize;
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], c);
    p.feed_line("ok", t);
    drain(&mut p, t);
    let mut now = t;
    let mut probes = 0;
    let mut failed = None;
    for _ in 0..40 {
        now += timeout;
        let d = drain(&mut p, now);
        probes += d.sent.len();
        if d.failed.is_some() {
            failed = d.failed;
            break;
        }
        if probes == max_probes - 1 {
            p.feed_line("rs\u{fffd}2", now);
        }
    }
    assert!(
        failed.is_some(),
        "a printer that then stays silent still ends the job"
    );
    // The count of unanswered probes starts again after the damaged answer.
    assert_eq!(probes, 2 * max_probes - 1);
}

#[test]
fn an_ok_right_after_an_rs_request_is_the_resent_lines() {
    // RepRapFirmware and Smoothieware print no `ok` after a refusal. The resent line's `ok`,
    // arriving right after the last request, was taken for the refusal's: the line then
    // waited for a probe, on every resend.
    for form in ["rs 1", "rs N1"] {
        let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
        assert_eq!(numbers(&sent), [1, 2, 3]);
        for _ in 0..3 {
            p.feed_line(form, t);
        }
        assert_eq!(numbers(&drain(&mut p, t).sent), [1], "{form}");
        let now = t + Duration::from_millis(1);
        p.feed_line("ok", now);
        let d = drain(&mut p, now);
        assert!(
            d.events.contains(&Event::Progress { executed: 1 }),
            "{form}: {:?}",
            d.events
        );
        assert_eq!(bodies(&d.sent), ["N1 M110 N1"], "{form}");
    }
}

#[test]
fn long_commands_wait_longer_and_busy_keeps_the_job_alive() {
    let c = cfg();
    let (mut p, t, _) = connected(
        &["G28", "G1 X1"],
        Config {
            window: 1,
            ..c.clone()
        },
    );
    // G28 in flight: no probe before the normal timeout.
    assert!(drain(&mut p, t + c.timeout / 2).sent.is_empty());
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
    assert_eq!(bodies(&drain(&mut p, now).sent), ["N3 M105"]);
}

#[test]
fn a_lost_ok_costs_a_short_probe_not_the_timeout() {
    let c = cfg();
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3"], c.clone());
    let gap = Duration::from_millis(2);
    p.feed_line("ok", t + gap);
    p.feed_line("ok", t + gap * 2);
    let d = drain(&mut p, t + gap * 2);
    assert!(d.sent.is_empty(), "{:?}", d.sent);
    // The ok for line 3 is lost: the printer is quiet with a line counted in flight. The
    // probe comes after several of the printer's gaps (at least the floor), far sooner than
    // the timeout.
    let soon = t + gap * 2 + c.quiet_floor;
    let d = drain(&mut p, soon);
    assert_eq!(bodies(&d.sent), ["N4 M105"]);
    assert!(c.quiet_floor * 10 <= c.timeout);
    // Its answer confirms everything before it; no line is sent again.
    p.feed_line("ok T:20.0 /0.0 B:20.0 /0.0", soon);
    let d = drain(&mut p, soon);
    assert!(d.sent.is_empty(), "{:?}", d.sent);
    assert!(d.events.contains(&Event::Progress { executed: 3 }));
    assert!(d.events.contains(&Event::Finished { cancelled: false }));
}

#[test]
fn wait_with_lines_in_flight_asks_at_once() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    // Repetier and the virtual printer say `wait` when idle with nothing queued.
    p.feed_line("wait", t);
    assert_eq!(bodies(&drain(&mut p, t).sent), ["N4 M105"]);
}

#[test]
fn a_clean_job_after_a_noisy_boot_ends_without_a_probe() {
    // The virtual printer's reset lines, a stray byte among them: before the job, they
    // change nothing (they once made the host re-send the last line after its ok).
    let t = Instant::now();
    let texts: Vec<String> = ["G1 X1", "G1 X2", "M84"].map(String::from).to_vec();
    let mut p = Protocol::new(commands(&texts), cfg(), t);
    let mut sent = drain(&mut p, t).sent;
    for l in [
        "start",
        "Marlin: Virtual Marlin!",
        "\u{80}",
        "SD card ok",
        "wait",
    ] {
        p.feed_line(l, t);
    }
    p.feed_line("ok T:21.3/ 0.00 B:21.3/ 0.00", t);
    let later = t + Duration::from_secs(1);
    let mut events = vec![];
    for _ in 0..5 {
        let d = drain(&mut p, later);
        sent.extend(d.sent);
        events.extend(d.events);
        p.feed_line("ok", later);
    }
    assert!(events.contains(&Event::Finished { cancelled: false }));
    assert_eq!(
        bodies(&sent),
        ["M105\n", "N0 M110 N0", "N1 G1 X1", "N2 G1 X2", "N3 M84"]
    );
}

#[test]
fn the_opening_m110_waits_until_the_oks_of_the_connection_stop() {
    // Smoothieware's banner ends with `ok`, and the probe was damaged on the way: its `ok`
    // comes after `Unknown command`. Taken for the `ok` of `M110 N0`, it once let line 1 out
    // before M110 ran; running M110 then set the count back to 0, the printer asked for line
    // 1 again and executed it twice (a random fault mix on the Smoothie model found this).
    let t = Instant::now();
    let job = crate::sim::job(2);
    let settle = cfg().boot_wait;
    let mut p = Protocol::new(commands(&job), cfg(), t);
    assert_eq!(drain(&mut p, t).sent, ["M105\n"]);
    p.feed_line("Smoothie", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.sent.is_empty(), "{:?}", d.sent);
    let late = t + Duration::from_millis(20);
    p.feed_line("echo:Unknown command: \"M1b5\"", late);
    p.feed_line("ok", late);
    let d = drain(&mut p, late + settle - Duration::from_millis(1));
    assert!(
        d.sent.is_empty(),
        "still within the quiet time: {:?}",
        d.sent
    );
    let d = drain(&mut p, late + settle);
    assert!(d.events.contains(&Event::Connected));
    assert_eq!(bodies(&d.sent), ["N0 M110 N0"]);
}

#[test]
fn an_irregular_job_ends_with_a_probe_and_never_sends_an_acknowledged_line_again() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    // A damaged line from the printer: an `ok` may have been lost in it.
    p.feed_line("o\u{fffd}", t);
    p.feed_line("ok", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert_eq!(bodies(&d.sent), ["N3 M105"]);
    assert!(!d.events.contains(&Event::Finished { cancelled: false }));
    p.feed_line("ok T:20.0 /0.0 B:20.0 /0.0", t);
    let d = drain(&mut p, t);
    assert!(d.sent.is_empty());
    assert!(d.events.contains(&Event::Finished { cancelled: false }));
}

/// Lines 1 to 3 in flight on the virtual printer's wording: line 1 refused with `first` (an
/// error naming no line), lines 2 and 3 for their number; line 1 then goes again, alone.
fn line_one_refused(first: &str) -> (Protocol, Instant) {
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    p.feed_line(first, t);
    p.feed_line("Resend:1", t);
    p.feed_line("ok", t);
    for got in [2, 3] {
        p.feed_line(&format!("Error: expected line 1 got {got}"), t);
        p.feed_line("Resend:1", t);
        p.feed_line("ok", t);
    }
    assert_eq!(numbers(&drain(&mut p, t).sent), [1]);
    (p, t)
}

#[test]
fn a_drifted_count_is_set_again() {
    // Line 1 damaged; lines 2 and 3 refused for their number (the simulator counts their
    // checksums all the same).
    let (mut p, t) = line_one_refused("Error: Missing checksum");
    // Line 1, sent alone, is damaged again; the drifted count names line 4.
    p.feed_line("Error: Missing checksum", t);
    p.feed_line("Resend:4", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(has_warning(&d.events, "line count is off"));
    assert_eq!(bodies(&d.sent), ["N0 M110 N0"]);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert_eq!(bodies(&d.sent), ["N1 G1 X1"]);
}

#[test]
fn a_request_for_a_line_before_the_one_refused_is_not_a_drift() {
    // The virtual printer's form: checksum errors name no line.
    let (mut p, t) = line_one_refused("Error: Checksum mismatch");
    // Line 1 is damaged again; its refusal comes damaged, and an `ok` a little later is
    // taken for line 1's (doubted: line 2 then goes alone).
    p.feed_line("Error: Checksum mismatch", t);
    p.feed_line("Re\u{fffd}end:1", t);
    let soon = t + Duration::from_millis(30);
    p.feed_line("ok", soon);
    let later = t + Duration::from_secs(1);
    let d = drain(&mut p, later);
    assert_eq!(numbers(&d.sent), [2]);
    // Line 2 is damaged too, and the printer asks for line 1: it never took it. Setting
    // the count to 1 (as for a drift) would skip line 1; it goes again instead.
    p.feed_line("Error: Checksum mismatch", later);
    p.feed_line("Resend:1", later);
    p.feed_line("ok", later);
    let d = drain(&mut p, later + Duration::from_secs(1));
    assert!(
        !has_warning(&d.events, "line count is off"),
        "{:?}",
        d.events
    );
    assert_eq!(bodies(&d.sent), ["N1 G1 X1"]);
}

#[test]
fn an_ok_naming_a_line_already_done_acknowledges_nothing() {
    // Repetier's `ok` names the line it took. One naming a line before those in flight (a
    // repeat, or a damaged ADVANCED_OK `ok`) once freed the oldest line's slot.
    let (mut p, t, sent) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    assert_eq!(numbers(&sent), [1, 2, 3]);
    p.feed_line("ok 0", t);
    let d = drain(&mut p, t);
    assert!(d.sent.is_empty(), "{:?}", d.sent);
    assert!(!d.events.contains(&Event::Progress { executed: 1 }));
    p.feed_line("ok 1", t);
    assert_eq!(numbers(&drain(&mut p, t).sent), [4]);
}

#[test]
fn teacups_bare_echo_and_repetiers_skip_are_not_requests() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3"], cfg());
    p.feed_line("ok", t);
    drain(&mut p, t);
    // Teacup: the request, then the number of the line it received.
    p.feed_line("rs N2 Expected checksum 67", t);
    p.feed_line("rs 3", t);
    let d = drain(&mut p, t + Duration::from_secs(1));
    assert_eq!(numbers(&d.sent), [2]);
    assert_eq!(p.stats().resends, 1);

    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    // Repetier: a line it did not take, with an `ok` that is not an execution.
    p.feed_line("skip 3", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(!d.events.iter().any(|e| matches!(e, Event::Progress { .. })));
}

#[test]
fn repetiers_numbered_ok_names_the_line() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2", "G1 X3", "G1 X4"], cfg());
    // `ok 2`: lines 1 and 2 taken (the `ok` for 1 was lost).
    p.feed_line("ok 2", t);
    let d = drain(&mut p, t);
    assert!(d.events.contains(&Event::Progress { executed: 2 }));
    assert_eq!(numbers(&d.sent), [4]);
}

#[test]
fn start_mid_job_is_a_reset() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    p.feed_line("ok", t);
    p.feed_line("start", t);
    let err = drain(&mut p, t).failed.expect("failed").to_string();
    assert!(
        err.contains("reset") && err.contains("job command 1"),
        "{err}"
    );
}

#[test]
fn unknown_commands_are_warnings() {
    let (mut p, t, _) = connected(&["G1 X1", "X99", "G1 X2"], cfg());
    p.feed_line("ok", t);
    p.feed_line("echo:Unknown command: \"X99\"", t);
    p.feed_line("ok", t);
    let d = drain(&mut p, t);
    assert!(d.failed.is_none());
    assert!(has_warning(&d.events, "X99"));
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
    // Line 5 was never sent: the shutdown takes its number.
    assert_eq!(bodies(&sent), ["N5 M104 S0", "N6 M140 S0", "N7 M84"]);
    assert!(events.contains(&Event::Finished { cancelled: true }));
}

#[test]
fn a_cancel_during_heating_ends_the_wait_and_turns_the_heaters_off_first() {
    let (mut p, t, sent) = connected(&["M109 S200", "G28", "G1 X1"], cfg());
    // Nothing is queued behind a heating wait.
    assert_eq!(bodies(&sent), ["N1 M109 S200"]);
    p.cancel(false);
    // M108 goes at once, past the wait.
    assert_eq!(bodies(&drain(&mut p, t).sent), ["N2 M108"]);
    let mut sent = vec![];
    for _ in 0..6 {
        p.feed_line("ok", t);
        sent.extend(drain(&mut p, t).sent);
    }
    // The homing never goes; heaters and motors off.
    assert_eq!(bodies(&sent), ["N3 M104 S0", "N4 M140 S0", "N5 M84"]);
}

#[test]
fn emergency_sends_numbered_m112_then_heaters_and_motors_off() {
    let (mut p, t, _) = connected(&["G1 X1", "G1 X2"], cfg());
    p.cancel(true);
    let d = drain(&mut p, t);
    assert_eq!(
        bodies(&d.sent),
        [
            "N3 M112",
            "N3 M110 N3",
            "N4 M104 S0",
            "N5 M140 S0",
            "N6 M84"
        ]
    );
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
    let job = crate::sim::job(2);
    let mut p = Protocol::new(commands(&job), cfg(), t);
    drain(&mut p, t);
    p.feed_line("start", t);
    assert!(drain(&mut p, t).sent.is_empty(), "boot chatter first");
    let d = drain(&mut p, t + Duration::from_secs(1));
    assert!(d.events.contains(&Event::Connected));

    let mut p = Protocol::new(commands(&job), cfg(), t);
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
    // The unnumbered connection probes are counted where they are sent.
    assert_eq!(p.stats().bytes_sent, probes as u64 * 5);
}
