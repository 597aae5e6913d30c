//! `isoforge fake-printer` and `isoforge print` as separate processes, as a user runs them.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{fixtures, isoforge, isoforge_bin};
use isoforge_host::gcode;
use isoforge_host::journal::{self, JournalRecord};

/// A running `isoforge fake-printer`, killed if the test ends early.
struct FakeProcess {
    child: Child,
    port: String,
}

impl FakeProcess {
    fn start(faults: &str, log: &Path) -> FakeProcess {
        Self::start_with(&["--faults", faults], log)
    }

    fn start_with(args: &[&str], log: &Path) -> FakeProcess {
        // Heating takes no time unless the test asks for it.
        let heat: &[&str] = if args.contains(&"--heat-tick") {
            &[]
        } else {
            &["--heat-tick", "0"]
        };
        let mut child = Command::new(isoforge_bin())
            .arg("fake-printer")
            .args(heat)
            .arg("--log")
            .arg(log)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("fake-printer starts");
        let mut first = String::new();
        let stdout = child.stdout.take().expect("piped");
        BufReader::new(stdout)
            .read_line(&mut first)
            .expect("a first line");
        let port = first.trim().to_string();
        assert!(
            port.starts_with("/dev/"),
            "first line is the pty path: {port:?}"
        );
        FakeProcess { child, port }
    }

    /// The fake exits by itself once the host has disconnected.
    fn wait_exit(mut self) {
        let deadline = Instant::now() + Duration::from_secs(10);
        while Instant::now() < deadline {
            if let Ok(Some(status)) = self.child.try_wait() {
                assert!(status.success());
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("fake-printer did not exit after the host disconnected");
    }
}

impl Drop for FakeProcess {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Numbered commands from a `--log` file, without the host's own: `M110` sets the count and
/// `M105` is its probe, numbered like every line it sends (the test files have neither).
fn logged_job(log: &Path) -> Vec<String> {
    std::fs::read_to_string(log)
        .expect("log")
        .lines()
        .filter_map(|l| l.split_once('\t'))
        .filter(|(n, c)| *n != "-" && !c.starts_with("M110") && *c != "M105")
        .map(|(_, c)| c.to_string())
        .collect()
}

fn file_commands(path: &Path) -> Vec<String> {
    gcode::read_file(path)
        .expect("parses")
        .commands
        .into_iter()
        .map(|c| c.text)
        .collect()
}

#[test]
fn help_says_what_print_does() {
    let out = isoforge(&["print", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    for word in [
        "--port",
        "--resume",
        "--from-layer",
        "--window",
        "--rx-buffer",
        "--emergency",
        "journal",
        "M112",
        "Ctrl-C",
        "fake-printer",
    ] {
        assert!(help.contains(word), "print --help lacks {word}");
    }
    let out = isoforge(&["fake-printer", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    for word in [
        "--faults",
        "corrupt=",
        "reset-at=",
        "seed=",
        "--log",
        "--baud",
    ] {
        assert!(help.contains(word), "fake-printer --help lacks {word}");
    }
}

#[test]
fn print_a_20000_command_job_through_both_binaries() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    std::fs::write(
        &gcode_path,
        isoforge_host::sample::vase_with_commands(20_000),
    )
    .unwrap();
    let log = dir.path().join("executed.tsv");
    let fake = FakeProcess::start("corrupt=0.01,drop=0.002,seed=3", &log);
    let out = isoforge(&[
        "print",
        gcode_path.to_str().unwrap(),
        "--port",
        &fake.port,
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["completed"], true);
    assert!(json["resends"].as_u64().unwrap() > 0);
    let want = file_commands(&gcode_path);
    assert!(json["lines_sent"].as_u64().unwrap() > want.len() as u64);
    assert!(json["seconds"].as_f64().unwrap() > 0.0);
    fake.wait_exit();
    assert_eq!(logged_job(&log), want);
    let j = JournalRecord::load(&journal::default_path(&gcode_path)).unwrap();
    assert_eq!(j.status, journal::Status::Completed);
}

#[test]
fn reset_then_resume_through_both_binaries() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    let text = isoforge_host::sample::vase_with_commands(5_000);
    std::fs::write(&gcode_path, &text).unwrap();
    let g = gcode_path.to_str().unwrap();

    let log1 = dir.path().join("run1.tsv");
    let fake = FakeProcess::start("reset-at=2500", &log1);
    let out = isoforge(&["print", g, "--port", &fake.port]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("reset") && stderr.contains("--resume"),
        "{stderr}"
    );
    fake.wait_exit();

    // What the resume will send first, from the journal the first run left.
    let record = JournalRecord::load(&journal::default_path(&gcode_path)).unwrap();
    let program = gcode::parse(&text).unwrap();
    let plan = journal::plan_resume(
        &program,
        journal::fingerprint(text.as_bytes()),
        Some(&record),
        None,
    )
    .unwrap();

    let log2 = dir.path().join("run2.tsv");
    let fake = FakeProcess::start("", &log2);
    let out = isoforge(&["print", g, "--port", &fake.port, "--resume", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("Resuming") && stderr.contains("heat"),
        "says what it will do: {stderr}"
    );
    fake.wait_exit();

    let mut all = logged_job(&log1);
    all.extend(logged_job(&log2).into_iter().skip(plan.prelude.len()));
    assert_eq!(
        all,
        file_commands(&gcode_path),
        "each command exactly once across both runs"
    );
}

#[test]
fn a_line_marlin_would_truncate_is_refused_before_printing() {
    let file = fixtures().join("gcode/too-long.gcode");
    let out = isoforge(&[
        "print",
        file.to_str().unwrap(),
        "--port",
        "/dev/null-not-a-port",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("line 2") && stderr.contains("95"),
        "{stderr}"
    );
}

#[test]
fn a_missing_port_is_a_clear_error() {
    let file = fixtures().join("gcode/square-tube.gcode");
    let out = isoforge(&[
        "print",
        file.to_str().unwrap(),
        "--port",
        "/dev/isoforge-no-such-port",
        "--no-journal",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("/dev/isoforge-no-such-port"), "{stderr}");
}

#[test]
fn bad_fault_specs_are_usage_errors_with_the_syntax() {
    let out = isoforge(&["fake-printer", "--faults", "corrupt=7"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--faults") && stderr.contains("corrupt") && stderr.contains("seed="),
        "{stderr}"
    );
}

#[test]
fn ctrl_c_without_a_terminal_cancels_cleanly() {
    signal_cancels_cleanly("-INT");
}

#[test]
fn sigterm_cancels_cleanly() {
    signal_cancels_cleanly("-TERM");
}

/// Sends `signal` to a running `print` and checks it cancelled the job properly.
/// Issue 9, item 1: an `M110` in the file would reset the printer's line count mid-job (a
/// runaway relative move, a hang, a move run twice, a misleading error). The host owns the
/// numbering: every such line is left out with a warning, and the rest runs once, in order.
#[test]
fn m110_in_a_file_is_left_out_with_a_warning() {
    let cases = [
        "G28\nG91\nG1 X1\nM110 N1\nG1 X2\nG1 X3\nG90\n",
        "G28\nG1 X1\nG1 X2\nM110 N100\nG1 X3\nG1 X4\n",
        "G28\nM110 N2\nG1 X1\nG1 X2\n",
        "M110 N0\nG28\nG1 X1\n",
    ];
    for text in cases {
        let dir = tempfile::tempdir().unwrap();
        let gcode_path = dir.path().join("m110.gcode");
        std::fs::write(&gcode_path, text).unwrap();
        let log = dir.path().join("executed.tsv");
        let fake = FakeProcess::start_with(&[], &log);
        let out = isoforge(&[
            "print",
            gcode_path.to_str().unwrap(),
            "--port",
            &fake.port,
            "--no-journal",
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{text:?}: {stderr}");
        assert!(
            stderr.contains("warning") && stderr.contains("M110") && stderr.contains("not sent"),
            "{text:?}: {stderr}"
        );
        fake.wait_exit();
        let want: Vec<&str> = text.lines().filter(|l| !l.starts_with("M110")).collect();
        assert_eq!(logged_job(&log), want, "{text:?}");
        // Nothing but the host's own opening M110 reached the printer.
        let all = std::fs::read_to_string(&log).unwrap();
        assert_eq!(all.matches("M110").count(), 1, "{all}");
    }
}

#[test]
fn sighup_cancels_cleanly() {
    signal_cancels_cleanly("-HUP");
}

#[test]
fn a_file_with_cr_only_line_endings_prints() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("old-mac.gcode");
    std::fs::write(&gcode_path, "G28\rG90\rG1 X10 Y10 F3000\rG1 X20\r").unwrap();
    let log = dir.path().join("executed.tsv");
    let fake = FakeProcess::start_with(&[], &log);
    let out = isoforge(&[
        "print",
        gcode_path.to_str().unwrap(),
        "--port",
        &fake.port,
        "--no-journal",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    fake.wait_exit();
    assert_eq!(
        logged_job(&log),
        ["G28", "G90", "G1 X10 Y10 F3000", "G1 X20"]
    );
}

#[test]
fn a_10_mb_line_is_not_echoed_whole() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("huge.gcode");
    let mut text = String::from("G28\nG1 X");
    text.push_str(&"1".repeat(10_000_000));
    text.push('\n');
    std::fs::write(&gcode_path, text).unwrap();
    let out = isoforge(&[
        "print",
        gcode_path.to_str().unwrap(),
        "--port",
        "/dev/null",
        "--no-journal",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("line 2"), "{stderr}");
    assert!(stderr.len() < 2_000, "{} bytes of error", stderr.len());
}

fn signal_cancels_cleanly(signal: &str) {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    std::fs::write(
        &gcode_path,
        isoforge_host::sample::vase_with_commands(5_000),
    )
    .unwrap();
    let log = dir.path().join("executed.tsv");
    // A slow link (9600 baud: about 30 lines a second) so the job is still running.
    let fake = FakeProcess::start_with(&["--baud", "9600"], &log);

    let print = Command::new(isoforge_bin())
        .args([
            "print",
            gcode_path.to_str().unwrap(),
            "--port",
            &fake.port,
            "--json",
        ])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill")
        .args([signal, &print.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = print.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("cancelled"), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("JSON even when cancelled");
    assert_eq!(json["completed"], false);
    assert_eq!(json["cancelled"], true);
    fake.wait_exit();
    // Stopped early, then heaters and motors off, as the last commands executed.
    let done = logged_job(&log);
    assert!(
        done.len() < 5_000,
        "cancelled early ({} commands ran)",
        done.len()
    );
    assert_eq!(done[done.len() - 3..], ["M104 S0", "M140 S0", "M84"]);
    let j = JournalRecord::load(&journal::default_path(&gcode_path)).unwrap();
    assert_eq!(j.status, journal::Status::Cancelled);
    // The journal names a point inside the file, so --resume could carry on.
    assert!(j.executed > 0 && j.executed < done.len());
}

#[test]
fn a_new_print_keeps_an_unfinished_journal_until_told_to_restart() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    std::fs::write(
        &gcode_path,
        isoforge_host::sample::vase_with_commands(2_000),
    )
    .unwrap();
    let g = gcode_path.to_str().unwrap();
    let journal_path = journal::default_path(&gcode_path);

    let log1 = dir.path().join("run1.tsv");
    let fake = FakeProcess::start("reset-at=1000", &log1);
    let out = isoforge(&["print", g, "--port", &fake.port]);
    assert_eq!(out.status.code(), Some(1));
    fake.wait_exit();
    let failed = std::fs::read(&journal_path).unwrap();

    // Printing the same file again is refused before anything is sent, and the message says
    // how to go on.
    let log2 = dir.path().join("run2.tsv");
    let fake = FakeProcess::start("", &log2);
    let out = isoforge(&["print", g, "--port", &fake.port]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("unfinished")
            && stderr.contains("--resume")
            && stderr.contains("--restart"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(&journal_path).unwrap(),
        failed,
        "journal kept"
    );
    // With --restart the job starts over and its journal is replaced.
    let out = isoforge(&["print", g, "--port", &fake.port, "--restart"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    fake.wait_exit();
    assert_eq!(logged_job(&log2), file_commands(&gcode_path));
    let j = JournalRecord::load(&journal_path).unwrap();
    assert_eq!(j.status, journal::Status::Completed);
}

#[test]
fn a_journal_path_that_is_not_a_journal_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("part.gcode");
    let text = isoforge_host::sample::vase_with_commands(100);
    std::fs::write(&gcode_path, &text).unwrap();
    let notes = dir.path().join("notes.txt");
    std::fs::write(&notes, "my notes\n").unwrap();
    let g = gcode_path.to_str().unwrap();
    // The G-code itself is refused as an input; another file that is not a journal is
    // refused as not a journal; --restart overrides neither.
    for (journal, why) in [
        (g, "is the input"),
        (notes.to_str().unwrap(), "not overwritten"),
    ] {
        for extra in [&[][..], &["--restart"][..]] {
            let mut args = vec!["print", g, "--port", "/dev/isoforge-no-such-port"];
            args.extend_from_slice(&["--journal", journal]);
            args.extend_from_slice(extra);
            let out = isoforge(&args);
            assert_eq!(out.status.code(), Some(1), "{journal} {extra:?}");
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(stderr.contains(why), "{journal} {extra:?}: {stderr}");
            assert_eq!(std::fs::read_to_string(&gcode_path).unwrap(), text);
            assert_eq!(std::fs::read_to_string(&notes).unwrap(), "my notes\n");
        }
    }
}

#[test]
fn an_edited_journal_is_refused_and_sends_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    std::fs::write(
        &gcode_path,
        isoforge_host::sample::vase_with_commands(2_000),
    )
    .unwrap();
    let g = gcode_path.to_str().unwrap();
    let journal_path = journal::default_path(&gcode_path);
    let log1 = dir.path().join("run1.tsv");
    let fake = FakeProcess::start("reset-at=1000", &log1);
    let out = isoforge(&["print", g, "--port", &fake.port]);
    assert_eq!(out.status.code(), Some(1));
    fake.wait_exit();

    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&journal_path).unwrap()).unwrap();
    let edits: [(&str, serde_json::Value, &str); 3] = [
        ("/job/state/hotends", serde_json::json!([5000.0]), "hotends"),
        ("/job/state/bed", serde_json::json!(1e9), "bed"),
        ("/job/executed", serde_json::json!(999_999), "executed"),
    ];
    for (pointer, value, word) in edits {
        let mut v = good.clone();
        *v.pointer_mut(pointer).unwrap() = value;
        std::fs::write(&journal_path, v.to_string()).unwrap();
        let log = dir.path().join(format!("{word}.tsv"));
        let fake = FakeProcess::start("", &log);
        let out = isoforge(&["print", g, "--port", &fake.port, "--resume"]);
        assert_eq!(out.status.code(), Some(1), "{pointer}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(word), "{pointer}: {stderr}");
        drop(fake);
        let sent = std::fs::read_to_string(&log).unwrap_or_default();
        assert!(
            !sent.contains("M109") && !sent.contains("G92"),
            "{pointer}: something was sent:\n{sent}"
        );
    }
    // `z` edited to NaN cannot even be written as JSON: the journal no longer parses.
    let mut v = good.clone();
    *v.pointer_mut("/job/state/z").unwrap() = serde_json::json!(1234.5678);
    let text = serde_json::to_string_pretty(&v)
        .unwrap()
        .replace("1234.5678", "NaN");
    std::fs::write(&journal_path, text).unwrap();
    let out = isoforge(&[
        "print",
        g,
        "--port",
        "/dev/isoforge-no-such-port",
        "--resume",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(journal_path.to_str().unwrap()), "{stderr}");
}

/// The fake printer's `# emergency m112=N m108=N` log line, as (m112, m108).
fn emergency_counts(log: &Path) -> (u64, u64) {
    let text = std::fs::read_to_string(log).expect("log");
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("# emergency "))
        .unwrap_or_else(|| panic!("no emergency line in the log:\n{text}"));
    let count = |key: &str| -> u64 {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{key} in {line:?}"))
    };
    (count("m112="), count("m108="))
}

/// Starts `isoforge print FILE --port PORT --json EXTRA..` with stdin not a terminal.
fn spawn_print(gcode: &Path, port: &str, extra: &[&str]) -> std::process::Child {
    Command::new(isoforge_bin())
        .args(["print", gcode.to_str().unwrap(), "--port", port, "--json"])
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

#[test]
fn a_cancel_during_a_heating_wait_ends_it_with_m108_and_turns_the_heaters_off() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("heat.gcode");
    std::fs::write(
        &gcode_path,
        "M140 S60\nM104 S200\nM109 S200\nG28\nG1 Z5 F600\nG1 X10 Y10 F3000\nM84\n",
    )
    .unwrap();
    let log = dir.path().join("executed.tsv");
    // 40 °C a tick, 4 s a tick: the wait for 200 °C lasts about 20 s unless interrupted.
    let fake = FakeProcess::start_with(&["--heat-tick", "4"], &log);
    let print = spawn_print(&gcode_path, &fake.port, &[]);
    std::thread::sleep(Duration::from_secs(3));
    let status = Command::new("kill")
        .args(["-TERM", &print.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = print.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("cancelled"), "{stderr}");
    fake.wait_exit();
    // The wait was under way, and M108 ended it (the printer says so), ...
    let done = logged_job(&log);
    assert!(done.iter().any(|c| c == "M109 S200"), "{done:?}");
    assert_eq!(emergency_counts(&log), (0, 1));
    // ... then heaters and motors off; the homing queued behind the wait never ran.
    assert!(!done.iter().any(|c| c == "G28"), "{done:?}");
    assert_eq!(done[done.len() - 3..], ["M104 S0", "M140 S0", "M84"]);
}

#[test]
fn emergency_cancel_sends_m112_and_the_printer_halts() {
    let dir = tempfile::tempdir().unwrap();
    let gcode_path = dir.path().join("vase.gcode");
    std::fs::write(
        &gcode_path,
        isoforge_host::sample::vase_with_commands(5_000),
    )
    .unwrap();
    let log = dir.path().join("executed.tsv");
    // A slow link (9600 baud: about 30 lines a second) so the job is still running.
    let fake = FakeProcess::start_with(&["--baud", "9600"], &log);
    let print = spawn_print(&gcode_path, &fake.port, &["--emergency"]);
    std::thread::sleep(Duration::from_millis(1500));
    let status = Command::new("kill")
        .args(["-TERM", &print.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = print.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("JSON even when stopped");
    assert_eq!(json["completed"], false);
    fake.wait_exit();
    // The printer's emergency parser took the M112 and halted: nothing ran after it, not
    // even the shutdown commands the host sends for a firmware that ignores M112.
    assert_eq!(emergency_counts(&log), (1, 0));
    let done = logged_job(&log);
    assert!(!done.is_empty() && done.len() < 5_000, "{} ran", done.len());
    assert!(
        !done.iter().any(|c| c == "M104 S0" || c == "M84"),
        "{done:?}"
    );
}
