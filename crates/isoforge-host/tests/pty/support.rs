//! Shared by the host end-to-end tests: a realistic job, a fake printer on a pty, streaming.

use std::path::PathBuf;
use std::time::Duration;

use isoforge_host::fake::{Executed, FakeConfig, FakePrinter, Faults, FirmwareConfig};
use isoforge_host::gcode::{self, Program};
use isoforge_host::journal::{self, JournalRecord, Status};
use isoforge_host::protocol::Config;
use isoforge_host::state::MachineState;
use isoforge_host::streamer::{self, Control, Job, Report};

/// Commands in every fault test's job (the issue asks for at least 20,000).
pub const JOB_COMMANDS: usize = 20_000;

/// A sliced-looking vase job with at least `n` commands, as text and parsed.
pub fn vase(n: usize) -> (String, Program) {
    let text = isoforge_host::sample::vase_with_commands(n);
    let program = gcode::parse(&text).expect("the sample parses");
    assert!(program.commands.len() >= n);
    (text, program)
}

/// A fake printer executing instantly, kept alive across host sessions.
pub fn fake(faults: Faults) -> FakePrinter {
    FakePrinter::spawn(FakeConfig {
        firmware: FirmwareConfig {
            faults,
            ..FirmwareConfig::default()
        },
        ..FakeConfig::default()
    })
    .expect("a pty")
}

/// Timeouts short enough for tests, long enough for a busy debug build.
pub fn test_config() -> Config {
    Config {
        timeout: Duration::from_millis(700),
        long_timeout: Duration::from_secs(3),
        quiet_floor: Duration::from_millis(50),
        connect_timeout: Duration::from_secs(5),
        ..Config::default()
    }
}

/// Streams commands `start..` (after `prelude`) of `program` to the fake printer.
pub fn print(
    printer: &FakePrinter,
    program: &Program,
    start: usize,
    prelude: Vec<String>,
    journal: Option<(PathBuf, JournalRecord)>,
) -> Report {
    let mut port = streamer::open_port(printer.path(), 115_200).expect("open the pty");
    let job = Job {
        program,
        start,
        prelude,
        journal,
    };
    streamer::stream(&mut *port, job, test_config(), &Control::new(), |_| {})
}

/// A fresh journal record for a job from the start.
pub fn new_journal(
    path: &std::path::Path,
    text: &str,
    program: &Program,
) -> (PathBuf, JournalRecord) {
    (
        path.to_path_buf(),
        JournalRecord {
            gcode: "vase.gcode".into(),
            fingerprint: journal::fingerprint(text.as_bytes()),
            total: program.commands.len(),
            executed: 0,
            source_line: 0,
            layer: None,
            state: MachineState::default(),
            status: Status::Running,
        },
    )
}

/// Job commands from an executed record: numbered, without the host's own lines (M110
/// renumbering, M105 probes; the sample jobs have neither).
pub fn job_commands(record: &[Executed]) -> Vec<String> {
    record
        .iter()
        .filter(|e| e.line.is_some() && !e.command.starts_with("M110") && e.command != "M105")
        .map(|e| e.command.clone())
        .collect()
}

/// The file's commands as text.
pub fn texts(program: &Program) -> Vec<String> {
    program.commands.iter().map(|c| c.text.clone()).collect()
}

/// Asserts `done` equals `want`, reporting the first difference rather than two huge lists.
pub fn assert_same(done: &[String], want: &[String], what: &str) {
    if let Some(i) = (0..done.len().min(want.len())).find(|&i| done[i] != want[i]) {
        panic!(
            "{what}: command {i} differs: executed {:?}, file has {:?}",
            done[i], want[i]
        );
    }
    assert_eq!(
        done.len(),
        want.len(),
        "{what}: executed count differs from the file"
    );
}
