//! The job journal: how far a print got, written durably while it runs, and the plan for
//! `--resume` built from it.
//!
//! The journal is a small `key=value` text file beside the G-code (`part.gcode.journal`). It is
//! replaced atomically (temporary file, fsync, rename, fsync of the folder) at most every
//! [`JOURNAL_CADENCE`] while lines are acknowledged, and at once when the job stops, so after
//! a crash it names a line that was executed, never one that was not.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use isoforge_output::{Durability, Options, Streams};
use thiserror::Error;

use crate::gcode::Program;
use crate::state::MachineState;

/// How often the journal is rewritten while a job runs: a crash costs at most this much
/// progress (those lines are then executed again on resume), and 4 fsyncs a second cost
/// nothing next to a serial link.
pub const JOURNAL_CADENCE: Duration = Duration::from_millis(250);

/// How far above the print the nozzle lifts before homing X and Y on resume, mm.
pub const RESUME_LIFT: f64 = 5.0;

/// Where a job stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// Running, or the host died while it ran.
    Running,
    /// Every command executed.
    Completed,
    /// Stopped by an error.
    Failed,
    /// Cancelled by the user or the printer.
    Cancelled,
}

impl Status {
    fn as_str(self) -> &'static str {
        match self {
            Status::Running => "running",
            Status::Completed => "completed",
            Status::Failed => "failed",
            Status::Cancelled => "cancelled",
        }
    }
}

/// What the journal holds.
#[derive(Clone, Debug, PartialEq)]
pub struct JournalRecord {
    /// The G-code file.
    pub gcode: String,
    /// FNV-1a hash of the file's bytes, so a changed file is not resumed by mistake.
    pub fingerprint: u64,
    /// Commands in the file.
    pub total: usize,
    /// Commands `0..executed` of the file are known executed.
    pub executed: usize,
    /// Source line of the last executed command (0: none yet).
    pub source_line: usize,
    /// The layer of the last executed command.
    pub layer: Option<u32>,
    /// The printer state after the executed commands.
    pub state: MachineState,
    /// Where the job stands.
    pub status: Status,
}

/// A journal that cannot be written, read or used.
#[derive(Debug, Error)]
pub enum JournalError {
    /// Reading or writing failed.
    #[error("journal {path}: {source}")]
    Io {
        /// The journal file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// The file is not a journal, or is damaged.
    #[error("journal {path}:{line}: {reason}")]
    Bad {
        /// The journal file.
        path: String,
        /// The line with the problem.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The journal does not fit the job.
    #[error("{0}")]
    Mismatch(String),
}

/// FNV-1a over the bytes: cheap, stable, enough to notice an edited file.
pub fn fingerprint(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `part.gcode` → `part.gcode.journal`.
pub fn default_path(gcode: &Path) -> PathBuf {
    let mut name = gcode.as_os_str().to_owned();
    name.push(".journal");
    PathBuf::from(name)
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v}"))
}

impl JournalRecord {
    /// The file's text.
    pub fn to_text(&self) -> String {
        let s = &self.state;
        let mut t = String::from("isoforge-journal 1\n");
        let hotends: Vec<String> = s.hotends.iter().map(|h| format!("{h}")).collect();
        let _ = write!(
            t,
            "gcode={}\nfingerprint={:016x}\ntotal={}\nexecuted={}\nsource_line={}\nlayer={}\n\
             status={}\nhotends={}\nbed={}\ntool={}\nabsolute={}\nabsolute_e={}\nx={}\ny={}\nz={}\n\
             e={}\nfeedrate={}\nfan={}\n",
            self.gcode,
            self.fingerprint,
            self.total,
            self.executed,
            self.source_line,
            self.layer.map_or(String::new(), |l| l.to_string()),
            self.status.as_str(),
            hotends.join(","),
            s.bed,
            s.tool,
            u8::from(s.absolute),
            u8::from(s.absolute_e),
            fmt_opt(s.x),
            fmt_opt(s.y),
            fmt_opt(s.z),
            s.e,
            fmt_opt(s.feedrate),
            s.fan,
        );
        t
    }

    /// Reads a journal file.
    pub fn load(path: &Path) -> Result<JournalRecord, JournalError> {
        let text = fs::read_to_string(path).map_err(|source| JournalError::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses a journal's text; `path` is only for messages.
    pub fn parse(text: &str, path: &str) -> Result<JournalRecord, JournalError> {
        let bad = |line: usize, reason: String| JournalError::Bad {
            path: path.to_string(),
            line,
            reason,
        };
        let mut lines = text.lines().enumerate();
        match lines.next() {
            Some((_, "isoforge-journal 1")) => {}
            _ => return Err(bad(1, "not an isoforge journal (first line)".into())),
        }
        let mut r = JournalRecord {
            gcode: String::new(),
            fingerprint: 0,
            total: 0,
            executed: 0,
            source_line: 0,
            layer: None,
            state: MachineState::default(),
            status: Status::Running,
        };
        let mut seen = 0u32;
        for (i, line) in lines {
            let n = i + 1;
            let Some((key, value)) = line.split_once('=') else {
                return Err(bad(n, format!("expected key=value, got {line:?}")));
            };
            let num = |v: &str| -> Result<f64, JournalError> {
                v.parse()
                    .map_err(|_| bad(n, format!("{key}: {v:?} is not a number")))
            };
            let count = |v: &str| -> Result<usize, JournalError> {
                v.parse()
                    .map_err(|_| bad(n, format!("{key}: {v:?} is not a count")))
            };
            let opt = |v: &str| -> Result<Option<f64>, JournalError> {
                if v.is_empty() {
                    Ok(None)
                } else {
                    num(v).map(Some)
                }
            };
            match key {
                "gcode" => r.gcode = value.to_string(),
                "fingerprint" => {
                    r.fingerprint = u64::from_str_radix(value, 16)
                        .map_err(|_| bad(n, format!("fingerprint {value:?} is not hex")))?;
                    seen |= 1;
                }
                "total" => r.total = count(value)?,
                "executed" => {
                    r.executed = count(value)?;
                    seen |= 2;
                }
                "source_line" => r.source_line = count(value)?,
                "layer" => r.layer = opt(value)?.map(|l| l as u32),
                "status" => {
                    r.status = match value {
                        "running" => Status::Running,
                        "completed" => Status::Completed,
                        "failed" => Status::Failed,
                        "cancelled" => Status::Cancelled,
                        _ => return Err(bad(n, format!("unknown status {value:?}"))),
                    }
                }
                "hotends" => {
                    r.state.hotends = value
                        .split(',')
                        .filter(|s| !s.is_empty())
                        .map(num)
                        .collect::<Result<_, _>>()?;
                }
                "bed" => r.state.bed = num(value)?,
                "tool" => r.state.tool = count(value)?,
                "absolute" => r.state.absolute = value == "1",
                "absolute_e" => r.state.absolute_e = value == "1",
                "x" => r.state.x = opt(value)?,
                "y" => r.state.y = opt(value)?,
                "z" => r.state.z = opt(value)?,
                "e" => r.state.e = num(value)?,
                "feedrate" => r.state.feedrate = opt(value)?,
                "fan" => r.state.fan = num(value)?,
                _ => {} // Newer keys are skipped, not fatal.
            }
        }
        if seen != 3 {
            return Err(bad(0, "fingerprint or executed is missing".into()));
        }
        if r.executed > r.total {
            return Err(bad(0, "more commands executed than the file has".into()));
        }
        Ok(r)
    }
}

/// Replaces `path` with `contents` so that a crash leaves the old file or the new one, whole:
/// `isoforge-output` with the file and its folder synced to disk. A symlink's target is
/// replaced; a FIFO or device is refused, since `--resume` must read the journal back.
pub fn write_durable(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let options = Options {
        durability: Durability::Sync,
        streams: Streams::Refuse,
        ..Options::default()
    };
    isoforge_output::write_file(path, contents, options).map_err(std::io::Error::from)
}

/// Keeps a job's journal up to date.
pub struct Journal {
    path: PathBuf,
    record: JournalRecord,
    last_write: Option<Instant>,
    dirty: bool,
}

impl Journal {
    /// Starts a journal (written at once).
    pub fn create(path: PathBuf, record: JournalRecord) -> Result<Journal, JournalError> {
        let mut j = Journal {
            path,
            record,
            last_write: None,
            dirty: true,
        };
        j.write(Instant::now())?;
        Ok(j)
    }

    /// Where it is written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The current record.
    pub fn record(&self) -> &JournalRecord {
        &self.record
    }

    /// Notes progress; writes when [`JOURNAL_CADENCE`] has passed since the last write.
    pub fn update(
        &mut self,
        executed: usize,
        source_line: usize,
        layer: Option<u32>,
        state: &MachineState,
        now: Instant,
    ) -> Result<(), JournalError> {
        self.record.executed = executed;
        self.record.source_line = source_line;
        self.record.layer = layer;
        self.record.state = state.clone();
        self.dirty = true;
        if self
            .last_write
            .is_none_or(|t| now.duration_since(t) >= JOURNAL_CADENCE)
        {
            self.write(now)?;
        }
        Ok(())
    }

    /// Writes the final state now.
    pub fn finish(&mut self, status: Status) -> Result<(), JournalError> {
        self.record.status = status;
        self.dirty = true;
        self.write(Instant::now())
    }

    fn write(&mut self, now: Instant) -> Result<(), JournalError> {
        if !self.dirty {
            return Ok(());
        }
        write_durable(&self.path, self.record.to_text().as_bytes()).map_err(|source| {
            JournalError::Io {
                path: self.path.display().to_string(),
                source,
            }
        })?;
        self.dirty = false;
        self.last_write = Some(now);
        Ok(())
    }
}

/// What `--resume` will do.
#[derive(Clone, Debug, PartialEq)]
pub struct ResumePlan {
    /// Index of the first file command to send.
    pub start: usize,
    /// Commands sent first: heat, restore modes, move back.
    pub prelude: Vec<String>,
    /// The state being restored.
    pub state: MachineState,
    /// The plan in plain words.
    pub summary: String,
}

fn num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// Plans a resume: from the journal's first unexecuted command, or from a layer's start.
pub fn plan_resume(
    program: &Program,
    fingerprint: u64,
    journal: Option<&JournalRecord>,
    from_layer: Option<u32>,
) -> Result<ResumePlan, JournalError> {
    if let Some(j) = journal
        && (j.fingerprint != fingerprint || j.total != program.commands.len())
    {
        return Err(JournalError::Mismatch(format!(
            "the journal was written for a different version of {} ({} commands then, {} now); \
             resume with --from-layer N, or print from the start",
            j.gcode,
            j.total,
            program.commands.len()
        )));
    }
    let (start, state, why) = match (from_layer, journal) {
        (Some(n), _) => {
            let layer = program.layer(n).ok_or_else(|| {
                let known = match (program.layers.first(), program.layers.last()) {
                    (Some(a), Some(b)) => format!("layers {} to {}", a.number, b.number),
                    _ => "no layers (no ;LAYER: comments or extruding Z moves)".into(),
                };
                JournalError::Mismatch(format!("--from-layer {n}: the file has {known}"))
            })?;
            let start = layer.first_command;
            let state =
                MachineState::replay(program.commands[..start].iter().map(|c| c.text.as_str()));
            (start, state, format!("from the start of layer {n}"))
        }
        (None, Some(j)) => {
            if j.status == Status::Completed {
                return Err(JournalError::Mismatch(format!(
                    "the journal says {} was printed completely; nothing to resume",
                    j.gcode
                )));
            }
            let why = if j.executed == 0 {
                "from the beginning (no command was acknowledged)".to_string()
            } else {
                format!(
                    "after the last acknowledged command (file line {})",
                    j.source_line
                )
            };
            (j.executed, j.state.clone(), why)
        }
        (None, None) => {
            return Err(JournalError::Mismatch(
                "--resume needs the job's journal (or --from-layer N)".into(),
            ));
        }
    };
    let (prelude, steps) = prelude_for(&state);
    let first_line = program.commands.get(start).map_or(0, |c| c.source_line);
    let mut summary = format!(
        "Resuming {why}: {} of {} commands remain, starting at file line {first_line}.\n",
        program.commands.len() - start,
        program.commands.len()
    );
    for s in steps {
        summary += &format!("  - {s}\n");
    }
    Ok(ResumePlan {
        start,
        prelude,
        state,
        summary,
    })
}

/// The commands that bring a printer back to `state`, and their description.
fn prelude_for(state: &MachineState) -> (Vec<String>, Vec<String>) {
    let mut cmds = Vec::new();
    let mut words = Vec::new();
    let multi = state.hotends.len() > 1;
    let tool_word = |i: usize| {
        if multi {
            format!(" T{i}")
        } else {
            String::new()
        }
    };
    let hot: Vec<(usize, f64)> = state
        .hotends
        .iter()
        .copied()
        .enumerate()
        .filter(|(_, t)| *t > 0.0)
        .collect();
    if state.bed > 0.0 {
        cmds.push(format!("M140 S{}", num(state.bed)));
    }
    for &(i, t) in &hot {
        cmds.push(format!("M104{} S{}", tool_word(i), num(t)));
    }
    if state.bed > 0.0 {
        cmds.push(format!("M190 S{}", num(state.bed)));
    }
    for &(i, t) in &hot {
        cmds.push(format!("M109{} S{}", tool_word(i), num(t)));
    }
    if state.bed > 0.0 || !hot.is_empty() {
        let temps: Vec<String> = hot
            .iter()
            .map(|(i, t)| format!("hotend {i} to {} °C", num(*t)))
            .chain((state.bed > 0.0).then(|| format!("bed to {} °C", num(state.bed))))
            .collect();
        words.push(format!(
            "heat {} and wait (M140/M104, then M190/M109)",
            temps.join(", ")
        ));
    } else {
        words.push("no heaters were on: no heating".into());
    }
    if multi {
        cmds.push(format!("T{}", state.tool));
        words.push(format!("select tool {}", state.tool));
    }
    if let Some(z) = state.z {
        // After a reset the firmware no longer knows Z, but the axis has not moved: declare
        // it, lift clear of the part, and home only X and Y (homing Z would hit the print).
        cmds.push(format!("G92 Z{}", num(z)));
        cmds.push("G91".into());
        cmds.push(format!("G1 Z{} F600", num(RESUME_LIFT)));
        cmds.push("G90".into());
        cmds.push("G28 X Y".into());
        let mut w = format!(
            "set Z to {} (G92), lift {} mm, home X and Y",
            num(z),
            num(RESUME_LIFT)
        );
        if let (Some(x), Some(y)) = (state.x, state.y) {
            cmds.push(format!("G1 X{} Y{} F3000", num(x), num(y)));
            w += &format!(", move to X{} Y{}", num(x), num(y));
        }
        cmds.push(format!("G1 Z{} F600", num(z)));
        w += &format!(", lower to Z{}", num(z));
        words.push(w);
    }
    cmds.push(if state.absolute { "G90" } else { "G91" }.into());
    cmds.push(if state.absolute_e { "M82" } else { "M83" }.into());
    cmds.push(format!("G92 E{}", num(state.e)));
    words.push(format!(
        "{} positioning (G9{}), {} extrusion (M8{}), E set to {} (G92)",
        if state.absolute {
            "absolute"
        } else {
            "relative"
        },
        if state.absolute { 0 } else { 1 },
        if state.absolute_e {
            "absolute"
        } else {
            "relative"
        },
        if state.absolute_e { 2 } else { 3 },
        num(state.e)
    ));
    if let Some(f) = state.feedrate {
        cmds.push(format!("G1 F{}", num(f)));
    }
    if state.fan > 0.0 {
        cmds.push(format!("M106 S{}", num(state.fan)));
        words.push(format!("fan at {}", num(state.fan)));
    }
    (cmds, words)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::parse;

    fn record(program: &Program, fp: u64, executed: usize) -> JournalRecord {
        let state =
            MachineState::replay(program.commands[..executed].iter().map(|c| c.text.as_str()));
        JournalRecord {
            gcode: "part.gcode".into(),
            fingerprint: fp,
            total: program.commands.len(),
            executed,
            source_line: program.commands[executed - 1].source_line,
            layer: None,
            state,
            status: Status::Failed,
        }
    }

    const G: &str = "M140 S60\nM104 S210\nG28\nG90\nM83\n;LAYER:0\nG1 Z0.2 F600\nG1 X10 Y10 E1 F1200\n;LAYER:1\nG1 Z0.4\nG1 X20 Y10 E1\nG1 X20 Y20 E1\n";

    #[test]
    fn record_round_trips_through_text() {
        let p = parse(G).unwrap();
        let r = record(&p, 42, 8);
        let back = JournalRecord::parse(&r.to_text(), "j").unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn damaged_journals_are_errors_with_line_numbers() {
        let err = JournalRecord::parse("hello\n", "j")
            .unwrap_err()
            .to_string();
        assert!(err.contains("j:1"), "{err}");
        let err = JournalRecord::parse("isoforge-journal 1\nfingerprint=zz\n", "j")
            .unwrap_err()
            .to_string();
        assert!(err.contains("j:2"), "{err}");
    }

    #[test]
    fn resume_plan_restores_heat_modes_and_position() {
        let p = parse(G).unwrap();
        let r = record(&p, 7, 9);
        let plan = plan_resume(&p, 7, Some(&r), None).unwrap();
        assert_eq!(plan.start, 9);
        let pre = plan.prelude.join("\n");
        for want in [
            "M140 S60",
            "M104 S210",
            "M190 S60",
            "M109 S210",
            "G92 Z0.4",
            "G28 X Y",
            "G1 X20 Y10 F3000",
            "G1 Z0.4 F600",
            "M83",
            "G92 E2",
        ] {
            assert!(pre.contains(want), "missing {want}:\n{pre}");
        }
        // Heat first, then wait; modes after the move.
        let pos = |s: &str| plan.prelude.iter().position(|c| c == s).unwrap();
        assert!(pos("M104 S210") < pos("M190 S60"));
        assert!(pos("G28 X Y") < pos("M83"));
        assert!(plan.summary.contains("file line 12"), "{}", plan.summary);
    }

    #[test]
    fn from_layer_replays_the_file() {
        let p = parse(G).unwrap();
        let plan = plan_resume(&p, 7, None, Some(1)).unwrap();
        assert_eq!(plan.start, 7);
        assert_eq!(plan.state.z, Some(0.2));
        assert!(plan_resume(&p, 7, None, Some(9)).is_err());
    }

    #[test]
    fn refuses_a_changed_file_or_a_finished_job() {
        let p = parse(G).unwrap();
        let r = record(&p, 7, 3);
        assert!(plan_resume(&p, 8, Some(&r), None).is_err());
        let mut done = r.clone();
        done.status = Status::Completed;
        assert!(plan_resume(&p, 7, Some(&done), None).is_err());
    }

    #[test]
    fn journal_writes_at_its_cadence_and_at_the_end() {
        let dir = std::env::temp_dir().join(format!("isoforge-cadence-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.journal");
        let p = parse(G).unwrap();
        let mut j = Journal::create(path.clone(), record(&p, 1, 1)).unwrap();
        let t0 = Instant::now();
        let s = MachineState::default();
        j.update(2, 2, None, &s, t0).unwrap();
        // Within the cadence: the file still says 1.
        assert_eq!(JournalRecord::load(&path).unwrap().executed, 1);
        j.update(3, 3, None, &s, t0 + JOURNAL_CADENCE).unwrap();
        assert_eq!(JournalRecord::load(&path).unwrap().executed, 3);
        j.update(4, 4, None, &s, t0 + JOURNAL_CADENCE).unwrap();
        j.finish(Status::Cancelled).unwrap();
        let r = JournalRecord::load(&path).unwrap();
        assert_eq!((r.executed, r.status), (4, Status::Cancelled));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn durable_write_replaces_whole() {
        let dir = std::env::temp_dir().join(format!("isoforge-journal-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("x.journal");
        write_durable(&path, b"one").unwrap();
        write_durable(&path, b"two").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"two");
        assert!(!dir.join("x.journal.tmp").exists());
        fs::remove_dir_all(&dir).unwrap();
    }
}
