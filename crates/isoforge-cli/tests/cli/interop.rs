//! The interop test: `isoforge print` streams a PrusaSlicer file (fixtures/gcode/
//! cube-16mm-prusaslicer.gcode.gz, 21,785 commands) to OctoPrint's virtual printer behind a
//! pty (tools/peers/octoprint_bridge.py) on several links: clean, a bit flipped in every 50th
//! line, the simulator's own injected errors, and busy reports. Each run must exit 0 with the
//! simulator's executed log equal to the file, each command once, in order. Printrun's
//! printcore (ping-pong) streams on the clean link as the speed reference, in the same run: the
//! test prints both speeds side by side, and asserts nothing about them, since a timed assert
//! fails on a busy machine (CI runs this beside the 100,000-command soak on 2 cores) without
//! anything being wrong. docs/host.md records the figures.
//!
//! It needs the Python peers: `.ci/run` runs `tools/peers/setup.sh` and then this test with
//! `ISOFORGE_PEERS_VENV` naming the venv. Under plain `cargo test` it is ignored; run with
//! `--ignored` and no venv it fails loudly.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{fixtures, isoforge};

fn venv() -> PathBuf {
    let Some(dir) = std::env::var_os("ISOFORGE_PEERS_VENV") else {
        panic!(
            "ISOFORGE_PEERS_VENV is not set: run tools/peers/setup.sh and point it at the venv \
             it prints (.ci/run does both)"
        );
    };
    let dir = PathBuf::from(dir);
    assert!(
        dir.join("bin/python").exists(),
        "ISOFORGE_PEERS_VENV={}: no bin/python there; run tools/peers/setup.sh",
        dir.display()
    );
    dir
}

fn tools() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/peers")
}

/// The virtual printer on a pty, until the host closes the port.
struct Bridge {
    child: Child,
    port: String,
    log: PathBuf,
}

impl Bridge {
    fn start(venv: &Path, dir: &Path, name: &str, link: &[&str]) -> Bridge {
        let log = dir.join(format!("{name}.executed"));
        let mut child = Command::new(venv.join("bin/python"))
            .arg(tools().join("octoprint_bridge.py"))
            .arg("--log")
            .arg(&log)
            // Moves take no time and the hotend sits at print temperature, so the runs
            // measure the link and the hosts, not the simulated machine.
            .args(["--instant-moves", "--pinned-hotend", "200"])
            .args(link)
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("the bridge starts");
        let mut first = String::new();
        BufReader::new(child.stdout.take().expect("piped"))
            .read_line(&mut first)
            .expect("the bridge prints its port");
        let port = first.trim().to_string();
        assert!(port.starts_with("/dev/"), "bridge port: {first:?}");
        Bridge { child, port, log }
    }

    /// Waits for the bridge to see the host go and write its log; returns the commands the
    /// simulator executed, without the host's own link commands.
    fn finish(mut self) -> Vec<String> {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            if let Ok(Some(status)) = self.child.try_wait() {
                assert!(status.success(), "bridge: {status}");
                break;
            }
            assert!(Instant::now() < deadline, "the bridge did not stop");
            std::thread::sleep(Duration::from_millis(50));
        }
        own_commands_removed(&std::fs::read_to_string(&self.log).expect("bridge log"))
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Lines of a log or G-code without the host's link commands (`M110` sets the line count,
/// `M105` is the connect and watchdog probe; the file has neither).
fn own_commands_removed(text: &str) -> Vec<String> {
    text.lines()
        .map(|l| l.split(';').next().unwrap_or("").trim().to_string())
        .filter(|l| !l.is_empty() && !l.starts_with("M110") && l != "M105")
        .collect()
}

/// The fixture, decompressed into `dir`.
fn sliced_file(dir: &Path) -> (PathBuf, Vec<String>) {
    let gz = fixtures().join("gcode/cube-16mm-prusaslicer.gcode.gz");
    let out = Command::new("gzip")
        .arg("-dc")
        .arg(&gz)
        .output()
        .expect("gzip runs");
    assert!(out.status.success(), "gzip -dc {}", gz.display());
    let path = dir.join("cube.gcode");
    std::fs::write(&path, &out.stdout).unwrap();
    let text = String::from_utf8(out.stdout).expect("ASCII G-code");
    let commands = own_commands_removed(&text);
    let all = text
        .lines()
        .filter(|l| !l.split(';').next().unwrap_or("").trim().is_empty())
        .count();
    assert_eq!(commands.len(), all, "the file itself holds no M105/M110");
    assert!(commands.len() >= 20_000, "{} commands", commands.len());
    (path, commands)
}

/// Prints the file over one link; returns lines per second.
fn ours(venv: &Path, dir: &Path, file: &Path, want: &[String], name: &str, link: &[&str]) -> f64 {
    let bridge = Bridge::start(venv, dir, name, link);
    let out = isoforge(&[
        "print",
        file.to_str().unwrap(),
        "--port",
        &bridge.port,
        "--json",
        "--no-journal",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "{name}: exit {:?}: {stderr}",
        out.status
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    assert_eq!(json["completed"], true, "{name}");
    let done = bridge.finish();
    if done != want {
        let i = (0..done.len().min(want.len()))
            .find(|&i| done[i] != want[i])
            .unwrap_or(done.len().min(want.len()));
        panic!(
            "{name}: the simulator executed {} commands, the file has {}; first difference at \
             {i}: {:?} vs {:?}",
            done.len(),
            want.len(),
            done.get(i),
            want.get(i)
        );
    }
    let seconds = json["seconds"].as_f64().expect("seconds");
    eprintln!(
        "{name}: {} commands, {} lines sent, {} resends, {seconds:.2} s",
        want.len(),
        json["lines_sent"],
        json["resends"]
    );
    want.len() as f64 / seconds
}

/// printcore on the clean link; returns lines per second.
fn printcore(venv: &Path, dir: &Path, file: &Path, want: &[String]) -> f64 {
    let bridge = Bridge::start(venv, dir, "printcore", &[]);
    let out = Command::new(venv.join("bin/python"))
        .arg(tools().join("printcore_run.py"))
        .arg(&bridge.port)
        .arg(file)
        .output()
        .expect("printcore runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "printcore: {stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(stdout.trim()).expect("printcore JSON");
    let done = bridge.finish();
    assert_eq!(done.len(), want.len(), "printcore's run executed the file");
    json["lines_per_second"].as_f64().expect("lines_per_second")
}

#[test]
#[ignore = "needs the Python peers: .ci/run runs tools/peers/setup.sh, then this with --ignored"]
fn octoprint_virtual_printer_on_every_link() {
    let venv = venv();
    let dir = tempfile::tempdir().unwrap();
    let (file, want) = sliced_file(dir.path());
    let links: [(&str, &[&str]); 4] = [
        ("clean", &[]),
        ("bit flip every 50th line", &["--flip-every", "50"]),
        (
            "simulator errors",
            &[
                "--simulated-errors",
                "100:resend,1000:missing_lineno,2000:checksum_mismatch,5000:resend,\
                 9000:checksum_mismatch,14000:missing_lineno,20000:resend",
            ],
        ),
        (
            "busy reports",
            &[
                "--send-busy",
                "--busy-interval",
                "0.05",
                "--busy-every",
                "40",
            ],
        ),
    ];
    let mut rows = Vec::new();
    for (name, link) in links {
        rows.push((name, ours(&venv, dir.path(), &file, &want, name, link)));
    }
    let reference = printcore(&venv, dir.path(), &file, &want);
    eprintln!(
        "\nlink                       isoforge lines/s   vs printcore ({reference:.0} lines/s, clean)"
    );
    for (name, rate) in &rows {
        eprintln!("{name:<26} {rate:>16.0}   {:>6.1}x", rate / reference);
    }
}
