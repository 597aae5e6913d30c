//! Glue to `isoforge-host`: the serial ports the page may pick (the machine's and the
//! studio's own fake printer), and a print job streamed on its own thread with the same
//! journal and resume as `isoforge print`, its progress published as events.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

use isoforge_host::fake::{FakeConfig, FakePrinter, FirmwareConfig};
use isoforge_host::gcode;
use isoforge_host::journal::{self, JournalError, JournalRecord, Status};
use isoforge_host::protocol::{Config, Event};
use isoforge_host::state::MachineState;
use isoforge_host::streamer::{self, Control, Job, Progress, Update};
use isoforge_output::{Durability, Options, Streams, check_file};
use serde::Serialize;

/// The fake printer's heating pace, as `isoforge fake-printer`'s default: real seconds
/// per simulated second, so a heat-up shows on the page for a moment without a long wait.
const FAKE_HEAT_TICK: Duration = Duration::from_millis(50);

/// A port the page may print to.
#[derive(Debug, Clone, Serialize)]
pub struct PortInfo {
    /// The device path.
    pub path: String,
    /// What it is: `usb`, `pci`, `bluetooth`, `other`, or `fake` for the studio's own.
    pub kind: &'static str,
}

/// Why a print could not start or stopped.
#[derive(Debug, thiserror::Error)]
pub enum PrintError {
    /// The port is neither one of the machine's serial ports nor the fake printer.
    #[error("{0}: not a serial port of this machine (pick one from the list)")]
    UnknownPort(String),
    /// A job is running already.
    #[error("a print is running; cancel it first")]
    Busy,
    /// The G-code file cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The G-code does not parse.
    #[error(transparent)]
    Gcode(#[from] gcode::GcodeError),
    /// The journal forbids it (an unfinished job, a changed file, nothing to resume).
    #[error("{0}")]
    Journal(#[from] JournalError),
    /// The journal's place cannot be written.
    #[error("the job journal: {0}")]
    JournalFile(#[from] isoforge_output::OutputError),
    /// The port does not open.
    #[error("cannot open the serial port {port}: {source}")]
    Port {
        /// The port.
        port: String,
        /// Why.
        source: serialport::Error,
    },
    /// The fake printer does not start.
    #[error("the fake printer: {0}")]
    Fake(#[from] isoforge_host::fake::FakeError),
    /// The printing thread cannot start.
    #[error("cannot start the printing thread: {0}")]
    Thread(std::io::Error),
}

/// Where the print stands, as the page shows it.
#[derive(Debug, Clone, Default, Serialize)]
pub struct PrintStatus {
    /// `idle`, `running`, `paused`, `completed`, `cancelled` or `failed`.
    pub state: &'static str,
    /// The G-code file's name in the folder.
    pub file: String,
    /// The port.
    pub port: String,
    /// Commands of the file known executed.
    pub executed: usize,
    /// Commands in the file.
    pub total: usize,
    /// Percent done.
    pub percent: f64,
    /// The current layer.
    pub layer: Option<u32>,
    /// Its height, mm.
    pub z: Option<f64>,
    /// Seconds left, from the recent pace.
    pub eta_seconds: Option<f64>,
    /// Hotend actual and target, °C.
    pub hotend: Option<[f64; 2]>,
    /// Bed actual and target, °C.
    pub bed: Option<[f64; 2]>,
    /// Lines sent, resends included.
    pub lines_sent: u64,
    /// Resends answered.
    pub resends: u64,
    /// Why it stopped, when it failed.
    pub error: Option<String>,
    /// The last warnings and messages from the printer (a few).
    pub notes: Vec<String>,
    /// What a resume did first, in words.
    pub resume_plan: Option<String>,
}

/// How many printer notes the status keeps.
const NOTES_KEPT: usize = 8;

impl PrintStatus {
    fn take_progress(&mut self, p: &Progress) {
        self.executed = p.executed;
        self.total = p.total;
        self.percent = p.percent;
        self.layer = p.layer;
        self.z = p.z;
        self.eta_seconds = p.eta.map(|d| d.as_secs_f64());
        self.state = if p.paused { "paused" } else { "running" };
        if let Some(t) = &p.temps {
            self.hotend = t.tools.first().map(|r| [r.actual, r.target.unwrap_or(0.0)]);
            self.bed = t.bed.map(|r| [r.actual, r.target.unwrap_or(0.0)]);
        }
    }

    fn note(&mut self, text: String) {
        if self.notes.len() == NOTES_KEPT {
            self.notes.remove(0);
        }
        self.notes.push(text);
    }
}

/// What the page asks for.
#[derive(Debug, Clone)]
pub struct PrintRequest {
    /// The G-code file, already in the folder.
    pub gcode: PathBuf,
    /// Its name, for the status.
    pub name: String,
    /// The port.
    pub port: String,
    /// Baud rate.
    pub baud: u32,
    /// Continue the job from its journal.
    pub resume: bool,
    /// Start over although the journal holds an unfinished job.
    pub restart: bool,
}

struct Running {
    control: Control,
    thread: JoinHandle<()>,
}

/// The printer side of the studio: its fake printer and the one job that may run.
#[derive(Default)]
pub struct Printer {
    fake: Mutex<Option<FakePrinter>>,
    job: Mutex<Option<Running>>,
    status: Arc<Mutex<PrintStatus>>,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Printer {
    /// The ports to offer: the fake printer's (when started) first, then the machine's.
    pub fn ports(&self) -> Vec<PortInfo> {
        let mut list: Vec<PortInfo> = lock(&self.fake)
            .as_ref()
            .map(|f| PortInfo {
                path: f.path().to_string(),
                kind: "fake",
            })
            .into_iter()
            .collect();
        list.extend(machine_ports());
        list
    }

    /// Starts the fake printer (once; later calls give the running one's path).
    pub fn start_fake(&self) -> Result<String, PrintError> {
        let mut fake = lock(&self.fake);
        if let Some(f) = fake.as_ref() {
            return Ok(f.path().to_string());
        }
        let printer = FakePrinter::spawn(FakeConfig {
            firmware: FirmwareConfig {
                heat_tick: FAKE_HEAT_TICK,
                ..FirmwareConfig::default()
            },
            baud: None,
            // It outlives one job: the page may print to it again.
            exit_on_disconnect: false,
            log: None,
        })?;
        let path = printer.path().to_string();
        *fake = Some(printer);
        Ok(path)
    }

    /// What the fake printer has executed, in order (line number, command).
    pub fn fake_executed(&self) -> Option<Vec<(Option<u64>, String)>> {
        lock(&self.fake).as_ref().map(|f| {
            f.executed()
                .into_iter()
                .map(|e| (e.line, e.command))
                .collect()
        })
    }

    /// The current status.
    pub fn status(&self) -> PrintStatus {
        let mut s = lock(&self.status).clone();
        if s.state.is_empty() {
            s.state = "idle";
        }
        s
    }

    /// Pauses, resumes or cancels the running job; false when none runs.
    pub fn control(&self, what: &str) -> bool {
        let job = lock(&self.job);
        let Some(running) = job.as_ref().filter(|r| !r.thread.is_finished()) else {
            return false;
        };
        match what {
            "pause" => running.control.pause(),
            "resume" => running.control.resume(),
            "cancel" => running.control.cancel(),
            _ => return false,
        }
        true
    }

    /// Starts a print; `publish` is called with every status change, from the printing
    /// thread.
    pub fn start(
        &self,
        req: PrintRequest,
        publish: impl Fn(&PrintStatus) + Send + 'static,
    ) -> Result<(), PrintError> {
        let mut job = lock(&self.job);
        if job.as_ref().is_some_and(|r| !r.thread.is_finished()) {
            return Err(PrintError::Busy);
        }
        if !self.ports().iter().any(|p| p.path == req.port) {
            return Err(PrintError::UnknownPort(req.port));
        }
        let prepared = prepare(&req)?;
        let port = streamer::open_port(&req.port, req.baud).map_err(|source| PrintError::Port {
            port: req.port.clone(),
            source,
        })?;
        let control = Control::new();
        {
            let mut s = lock(&self.status);
            *s = PrintStatus {
                state: "running",
                file: req.name.clone(),
                port: req.port.clone(),
                total: prepared.program.commands.len(),
                executed: prepared.start,
                resume_plan: prepared.summary.clone(),
                ..PrintStatus::default()
            };
            publish(&s);
        }
        let status = self.status.clone();
        let thread_control = control.clone();
        let thread = std::thread::Builder::new()
            .name("studio-print".into())
            .spawn(move || run(port, prepared, &thread_control, &status, publish))
            .map_err(PrintError::Thread)?;
        *job = Some(Running { control, thread });
        Ok(())
    }

    /// Cancels a running job and waits for it (the studio is closing).
    pub fn shut_down(&self) {
        if let Some(r) = lock(&self.job).take() {
            r.control.cancel();
            let _ = r.thread.join();
        }
    }
}

/// The machine's serial ports. The enumeration reads /sys/class/tty, and panics where that
/// is missing (a jail, another system): look first.
fn machine_ports() -> Vec<PortInfo> {
    if !Path::new("/sys/class/tty").is_dir() {
        return Vec::new();
    }
    let Ok(ports) = serialport::available_ports() else {
        return Vec::new();
    };
    ports
        .into_iter()
        .map(|p| PortInfo {
            path: p.port_name,
            kind: match p.port_type {
                serialport::SerialPortType::UsbPort(_) => "usb",
                serialport::SerialPortType::PciPort => "pci",
                serialport::SerialPortType::BluetoothPort => "bluetooth",
                serialport::SerialPortType::Unknown => "other",
            },
        })
        .collect()
}

struct Prepared {
    program: gcode::Program,
    start: usize,
    prelude: Vec<String>,
    journal: (PathBuf, JournalRecord),
    summary: Option<String>,
}

/// What `isoforge print` does before sending a byte: read and parse the file, check the
/// journal's place, plan a resume or make sure a fresh start loses no unfinished job.
fn prepare(req: &PrintRequest) -> Result<Prepared, PrintError> {
    let bytes = isoforge_output::read_input(&req.gcode).map_err(|source| PrintError::Read {
        path: req.gcode.clone(),
        source,
    })?;
    let program = gcode::parse(&String::from_utf8_lossy(&bytes))?;
    let fingerprint = journal::fingerprint(&bytes);
    let journal_path = journal::default_path(&req.gcode);
    check_file(
        &journal_path,
        Options {
            inputs: &[&req.gcode],
            durability: Durability::Sync,
            streams: Streams::Refuse,
        },
    )?;
    let (start, prelude, state, summary) = if req.resume {
        let record = JournalRecord::load(&journal_path)?;
        let plan = journal::plan_resume(&program, fingerprint, Some(&record), None)?;
        (plan.start, plan.prelude, plan.state, Some(plan.summary))
    } else {
        journal::check_can_start(&journal_path, req.restart)?;
        (0, Vec::new(), MachineState::default(), None)
    };
    let source_line = start
        .checked_sub(1)
        .and_then(|i| program.commands.get(i))
        .map_or(0, |c| c.source_line);
    let record = JournalRecord {
        gcode: req.gcode.display().to_string(),
        fingerprint,
        total: program.commands.len(),
        executed: start,
        source_line,
        layer: start
            .checked_sub(1)
            .and_then(|i| program.layer_of(i))
            .map(|l| l.number),
        state,
        status: Status::Running,
    };
    Ok(Prepared {
        program,
        start,
        prelude,
        journal: (journal_path, record),
        summary,
    })
}

/// True when the G-code's journal holds a job that did not finish (the page offers resume).
pub fn resumable(gcode: &Path) -> bool {
    JournalRecord::load(&journal::default_path(gcode)).is_ok_and(|r| r.status != Status::Completed)
}

fn run(
    mut port: Box<dyn serialport::SerialPort>,
    prepared: Prepared,
    control: &Control,
    status: &Mutex<PrintStatus>,
    publish: impl Fn(&PrintStatus),
) {
    let job = Job {
        program: &prepared.program,
        start: prepared.start,
        prelude: prepared.prelude,
        journal: Some(prepared.journal),
    };
    let report = streamer::stream(&mut *port, job, Config::default(), control, |u| {
        let mut s = lock(status);
        match u {
            Update::Progress(p) => s.take_progress(p),
            Update::Event(Event::Warning(w)) => s.note(format!("warning: {w}")),
            Update::Event(Event::Paused(true)) => s.note("the printer asked to pause".into()),
            Update::Event(Event::Paused(false)) => s.note("the printer asked to resume".into()),
            Update::Event(_) => return,
        }
        publish(&s);
    });
    let mut s = lock(status);
    s.executed = report.executed;
    s.lines_sent = report.lines_sent;
    s.resends = report.resends;
    s.eta_seconds = None;
    if s.total > 0 {
        s.percent = 100.0 * report.executed as f64 / s.total as f64;
    }
    s.state = if let Some(e) = &report.error {
        s.error = Some(e.to_string());
        "failed"
    } else if report.cancelled {
        "cancelled"
    } else if report.completed {
        "completed"
    } else {
        "failed"
    };
    publish(&s);
}
