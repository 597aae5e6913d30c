//! The job journal: how far a print got, written durably while it runs, and the plan for
//! `--resume` built from it.
//!
//! The journal is a small JSON object beside the G-code (`part.gcode.journal`), read and
//! written by serde with unknown keys refused. JSON rather than TOML: it has no literal for
//! NaN or infinity, so a non-finite position cannot even be written down; serde_json says
//! line and column of a damaged file; and other tools read it without a TOML parser. What
//! is read is validated before anything is sent: temperatures within what a printer can
//! reach, positions finite and on a printer's scale, counts consistent with each other and,
//! when resuming, with the G-code file itself.
//!
//! It is replaced atomically (temporary file, fsync, rename, fsync of the folder) at most
//! every `JOURNAL_CADENCE` (250 ms) while lines are acknowledged, and at once when the job stops,
//! so after a crash it names a line that was executed, never one that was not.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use isoforge_output::{Durability, Options, Streams};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::gcode::Program;
use crate::state::MachineState;

/// How often the journal is rewritten while a job runs: a crash costs at most this much
/// progress (those lines are then executed again on resume), and 4 fsyncs a second cost
/// nothing next to a serial link.
pub(crate) const JOURNAL_CADENCE: Duration = Duration::from_millis(250);

/// How far above the print the nozzle lifts before homing X and Y on resume, mm.
pub(crate) const RESUME_LIFT: f64 = 5.0;

/// The `format` every journal starts with.
const FORMAT: &str = "isoforge-journal";
/// The journal layout this version writes and reads (1 was the older key=value text).
const VERSION: u32 = 2;

/// Hottest hotend target a journal may ask for, °C: all-metal hotends reach 400 °C (the
/// same bound as the profile's `nozzle_temperature`).
const MAX_HOTEND: f64 = 400.0;
/// Hottest bed target, °C (the profile's `bed_temperature` bound).
const MAX_BED: f64 = 150.0;
/// Hotends a journal may name (tool changers have a handful; 16 is generous).
const MAX_HOTENDS: usize = 16;
/// Largest position magnitude, mm: no printer is 10 m across.
const MAX_POSITION: f64 = 10_000.0;
/// Largest extruder position, mm of filament: absolute E grows over a print (a kilogram of
/// 1.75 mm PLA is about 330 m), so allow well beyond that.
const MAX_E: f64 = 1e7;
/// Fastest feed rate, mm/min (the profile's 1500 mm/s travel is 90,000).
const MAX_FEEDRATE: f64 = 100_000.0;
/// Part fan PWM, 0-255.
const MAX_FAN: f64 = 255.0;

/// Where a job stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
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

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Running => "running",
            Status::Completed => "completed",
            Status::Failed => "failed",
            Status::Cancelled => "cancelled",
        })
    }
}

/// What the journal holds. The field names are the journal's keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JournalRecord {
    /// The G-code file.
    pub gcode: String,
    /// FNV-1a hash of the file's bytes, so a changed file is not resumed by mistake
    /// (written as 16 hex digits).
    #[serde(with = "hex")]
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

/// The file: a format tag and version around the record, so a journal of another layout
/// (or not a journal at all) is named as such.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct JournalFile {
    format: String,
    version: u32,
    job: JournalRecord,
}

/// The fingerprint as hex text: JSON numbers lose integers above 2^53 in many readers.
mod hex {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        u64::from_str_radix(&text, 16)
            .map_err(|_| serde::de::Error::custom(format!("fingerprint {text:?} is not hex")))
    }
}

/// A journal value that no printer job can have.
#[derive(Clone, Debug, PartialEq, Error)]
#[error("`{field}` = {value}: {expected}")]
pub struct InvalidValue {
    /// The key (`state.hotends[0]`, `executed`).
    pub field: String,
    /// The value found.
    pub value: String,
    /// What it must be.
    pub expected: String,
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
    /// The file is not a journal of this version.
    #[error("journal {path}: {what}")]
    NotAJournal {
        /// The file.
        path: String,
        /// What it is instead.
        what: String,
    },
    /// The file is not valid JSON, or a key is unknown, missing or of the wrong type.
    #[error("journal {path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What serde says.
        message: String,
    },
    /// A value no job can have (a 5000 °C hotend, a NaN position, more executed commands
    /// than the file has).
    #[error("journal {path}: {problem}")]
    Invalid {
        /// The file.
        path: String,
        /// The value and what it must be.
        problem: InvalidValue,
    },
    /// The journal was written for a different version of the file.
    #[error(
        "the journal was written for a different version of {gcode} ({then} commands then, \
         {now} now)"
    )]
    ChangedFile {
        /// The G-code file.
        gcode: String,
        /// Commands when the journal was written.
        then: usize,
        /// Commands now.
        now: usize,
    },
    /// The journal's progress does not match the file at the point it names.
    #[error(
        "the journal does not match {gcode} after command {executed}: {what} (edited or \
         damaged?)"
    )]
    Inconsistent {
        /// The G-code file.
        gcode: String,
        /// Commands the journal says were executed.
        executed: usize,
        /// What differs.
        what: String,
    },
    /// The job finished; there is nothing to resume.
    #[error("the journal says {gcode} was printed completely; nothing to resume")]
    Completed {
        /// The G-code file.
        gcode: String,
    },
    /// A layer to resume from that the file does not have.
    #[error("layer {layer}: the file has {known}")]
    NoSuchLayer {
        /// The layer asked for.
        layer: u32,
        /// The layers the file has.
        known: String,
    },
    /// Resuming without a journal or a layer.
    #[error("resuming needs the job's journal, or a layer to resume from")]
    NothingToResume,
    /// A new job would overwrite the journal of one that did not finish.
    #[error(
        "journal {path} holds an unfinished job of {gcode} ({status} after {executed} of \
         {total} commands); a new print would overwrite it"
    )]
    Unfinished {
        /// The journal file.
        path: String,
        /// Its G-code file.
        gcode: String,
        /// How it ended.
        status: Status,
        /// Commands executed.
        executed: usize,
        /// Commands in the file.
        total: usize,
    },
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

impl JournalRecord {
    /// The file's text.
    pub fn to_text(&self) -> String {
        let file = JournalFile {
            format: FORMAT.into(),
            version: VERSION,
            job: self.clone(),
        };
        // A record of plain numbers and strings always serializes; non-finite numbers (which
        // validation refuses) would come out as `null` and fail to load, never as NaN.
        let mut text = serde_json::to_string_pretty(&file).unwrap_or_default();
        text.push('\n');
        text
    }

    /// Reads a journal file.
    pub fn load(path: &Path) -> Result<JournalRecord, JournalError> {
        let text =
            isoforge_output::read_input_to_string(path).map_err(|source| JournalError::Io {
                path: path.display().to_string(),
                source,
            })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Parses and validates a journal's text; `path` is only for messages.
    pub fn parse(text: &str, path: &str) -> Result<JournalRecord, JournalError> {
        if text.starts_with("isoforge-journal 1") {
            return Err(JournalError::NotAJournal {
                path: path.into(),
                what: "written by an older isoforge (format 1), which this version cannot \
                       resume"
                    .into(),
            });
        }
        // The tag first, so a JSON file of another kind is not reported key by key.
        #[derive(Deserialize)]
        struct Tag {
            format: Option<String>,
            version: Option<u32>,
        }
        let syntax = |e: serde_json::Error| JournalError::Syntax {
            path: path.into(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        };
        let tag: Tag = serde_json::from_str(text).map_err(|e| {
            if e.is_syntax() || e.is_eof() {
                syntax(e)
            } else {
                JournalError::NotAJournal {
                    path: path.into(),
                    what: "not an isoforge journal".into(),
                }
            }
        })?;
        match (tag.format.as_deref(), tag.version) {
            (Some(FORMAT), Some(VERSION)) => {}
            (Some(FORMAT), v) => {
                return Err(JournalError::NotAJournal {
                    path: path.into(),
                    what: format!("journal version {v:?}; this isoforge reads version {VERSION}"),
                });
            }
            _ => {
                return Err(JournalError::NotAJournal {
                    path: path.into(),
                    what: "not an isoforge journal".into(),
                });
            }
        }
        let file: JournalFile = serde_json::from_str(text).map_err(syntax)?;
        file.job
            .validate()
            .map_err(|problem| JournalError::Invalid {
                path: path.into(),
                problem,
            })?;
        Ok(file.job)
    }

    /// Checks that the record could describe a real job: temperatures a printer can reach,
    /// finite positions on a printer's scale, and counts consistent with each other.
    pub fn validate(&self) -> Result<(), InvalidValue> {
        let s = &self.state;
        if s.hotends.is_empty() || s.hotends.len() > MAX_HOTENDS {
            return Err(invalid(
                "state.hotends",
                format!("{} hotends", s.hotends.len()),
                format!("1 to {MAX_HOTENDS} hotends"),
            ));
        }
        for (i, &t) in s.hotends.iter().enumerate() {
            within(&format!("state.hotends[{i}]"), t, 0.0, MAX_HOTEND, " °C")?;
        }
        within("state.bed", s.bed, 0.0, MAX_BED, " °C")?;
        if s.tool >= s.hotends.len() {
            return Err(invalid(
                "state.tool",
                s.tool.to_string(),
                format!("a tool below {}, the hotends listed", s.hotends.len()),
            ));
        }
        for (name, v) in [("state.x", s.x), ("state.y", s.y), ("state.z", s.z)] {
            if let Some(v) = v {
                within(name, v, -MAX_POSITION, MAX_POSITION, " mm")?;
            }
        }
        within("state.e", s.e, -MAX_E, MAX_E, " mm")?;
        if let Some(f) = s.feedrate {
            within("state.feedrate", f, 0.0, MAX_FEEDRATE, " mm/min")?;
        }
        within("state.fan", s.fan, 0.0, MAX_FAN, "")?;
        if self.executed > self.total {
            return Err(invalid(
                "executed",
                self.executed.to_string(),
                format!("at most the {} commands of the file", self.total),
            ));
        }
        if (self.executed == 0) != (self.source_line == 0) {
            return Err(invalid(
                "source_line",
                self.source_line.to_string(),
                "0 exactly when no command was executed".into(),
            ));
        }
        Ok(())
    }

    /// Checks that the record fits `program`, the file it names: the same file (fingerprint
    /// and length), and at the command it says was last executed, the same source line and
    /// the same printer state the file builds up to there.
    pub fn check_against(&self, program: &Program, fingerprint: u64) -> Result<(), JournalError> {
        self.check_same_file(program, fingerprint)?;
        let inconsistent = |what: String| JournalError::Inconsistent {
            gcode: self.gcode.clone(),
            executed: self.executed,
            what,
        };
        let line = self
            .executed
            .checked_sub(1)
            .and_then(|i| program.commands.get(i))
            .map_or(0, |c| c.source_line);
        if line != self.source_line {
            return Err(inconsistent(format!(
                "it names file line {}, the file has that command on line {line}",
                self.source_line
            )));
        }
        let replayed = MachineState::replay(
            program.commands[..self.executed]
                .iter()
                .map(|c| c.text.as_str()),
        );
        if !same_state(&replayed, &self.state) {
            return Err(inconsistent(format!(
                "its printer state {:?} is not the file's {:?}",
                self.state, replayed
            )));
        }
        Ok(())
    }
}

impl JournalRecord {
    /// The record was written for this version of the file.
    fn check_same_file(&self, program: &Program, fingerprint: u64) -> Result<(), JournalError> {
        if self.fingerprint != fingerprint || self.total != program.commands.len() {
            return Err(JournalError::ChangedFile {
                gcode: self.gcode.clone(),
                then: self.total,
                now: program.commands.len(),
            });
        }
        Ok(())
    }
}

/// The same state up to rounding: relative extrusion sums its steps in floating point, and a
/// resumed run adds the same steps to a starting value read back from the journal, so `e`
/// can differ in the last digits.
fn same_state(a: &MachineState, b: &MachineState) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * x.abs().max(y.abs()).max(1.0);
    let close_opt = |x: Option<f64>, y: Option<f64>| match (x, y) {
        (Some(x), Some(y)) => close(x, y),
        (x, y) => x.is_none() && y.is_none(),
    };
    a.hotends.len() == b.hotends.len()
        && a.hotends.iter().zip(&b.hotends).all(|(x, y)| close(*x, *y))
        && close(a.bed, b.bed)
        && a.tool == b.tool
        && a.absolute == b.absolute
        && a.absolute_e == b.absolute_e
        && close_opt(a.x, b.x)
        && close_opt(a.y, b.y)
        && close_opt(a.z, b.z)
        && close(a.e, b.e)
        && close_opt(a.feedrate, b.feedrate)
        && close(a.fan, b.fan)
        && a.inches == b.inches
}

fn invalid(field: &str, value: String, expected: String) -> InvalidValue {
    InvalidValue {
        field: field.into(),
        value,
        expected,
    }
}

/// `v` finite and within `[lo, hi]`.
fn within(field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<(), InvalidValue> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        return Ok(());
    }
    Err(invalid(
        field,
        format!("{v}{unit}"),
        format!("a number from {lo} to {hi}{unit}"),
    ))
}

/// Refuses to start a new job whose journal would overwrite what should be kept: the
/// journal of a job that did not finish (it could still be resumed), or a file at the
/// journal's path that is not a journal at all. No file, or a finished job's journal, is
/// fine. `restart` allows overwriting an unfinished job's journal, never a non-journal.
pub fn check_can_start(path: &Path, restart: bool) -> Result<(), JournalError> {
    let text = match isoforge_output::read_input(path) {
        Ok(bytes) => bytes,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(JournalError::Io {
                path: path.display().to_string(),
                source,
            });
        }
    };
    let shown = path.display().to_string();
    let not_a_journal = |what: String| JournalError::NotAJournal {
        path: shown.clone(),
        what: format!("{what}; it is not overwritten"),
    };
    let Ok(text) = String::from_utf8(text) else {
        return Err(not_a_journal("not a journal (not text)".into()));
    };
    match JournalRecord::parse(&text, &shown) {
        Ok(r) if r.status == Status::Completed || restart => Ok(()),
        Ok(r) => Err(JournalError::Unfinished {
            path: shown,
            gcode: r.gcode,
            status: r.status,
            executed: r.executed,
            total: r.total,
        }),
        // A damaged journal of ours (it still carries our tag) can be started over, on
        // request; anything else at the path is the user's and stays.
        Err(JournalError::Syntax { .. } | JournalError::Invalid { .. })
            if restart && text.contains(&format!("\"{FORMAT}\"")) =>
        {
            Ok(())
        }
        Err(e) => Err(not_a_journal(e.to_string())),
    }
}

/// Replaces `path` with `contents` so that a crash leaves the old file or the new one, whole:
/// `isoforge-output` with the file and its folder synced to disk. A symlink's target is
/// replaced; a FIFO or device is refused, since `--resume` must read the journal back.
pub(crate) fn write_durable(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let options = Options {
        durability: Durability::Sync,
        streams: Streams::Refuse,
        ..Options::default()
    };
    isoforge_output::write_file(path, contents, options).map_err(std::io::Error::from)
}

/// Keeps a job's journal up to date.
pub(crate) struct Journal {
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
    // From a layer, the state comes from the file; from the journal, it must fit the file.
    match (journal, from_layer) {
        (Some(j), Some(_)) => j.check_same_file(program, fingerprint)?,
        (Some(j), None) => j.check_against(program, fingerprint)?,
        (None, _) => {}
    }
    let (start, state, why) = match (from_layer, journal) {
        (Some(n), _) => {
            let layer = program.layer(n).ok_or_else(|| {
                let known = match (program.layers.first(), program.layers.last()) {
                    (Some(a), Some(b)) => format!("layers {} to {}", a.number, b.number),
                    _ => "no layers (no ;LAYER: comments or extruding Z moves)".into(),
                };
                JournalError::NoSuchLayer { layer: n, known }
            })?;
            let start = layer.first_command;
            let state =
                MachineState::replay(program.commands[..start].iter().map(|c| c.text.as_str()));
            (start, state, format!("from the start of layer {n}"))
        }
        (None, Some(j)) => {
            if j.status == Status::Completed {
                return Err(JournalError::Completed {
                    gcode: j.gcode.clone(),
                });
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
        (None, None) => return Err(JournalError::NothingToResume),
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
    if state.inches {
        // Positions and feeds are restored in millimetres, then the file's inches return.
        cmds.push("G21".into());
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
    if state.inches {
        cmds.push("G20".into());
        words.push("inch units again (G20)".into());
    }
    (cmds, words)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::parse;
    use std::fs;

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
        let err = JournalRecord::parse("hello\n", "j").unwrap_err();
        assert!(matches!(err, JournalError::Syntax { line: 1, .. }), "{err}");
        assert!(err.to_string().contains("journal j:1:"), "{err}");
        let p = parse(G).unwrap();
        let text = record(&p, 42, 8)
            .to_text()
            .replace("\"fingerprint\": \"", "\"fingerprint\": \"zz");
        let err = JournalRecord::parse(&text, "j").unwrap_err();
        let line = text
            .lines()
            .position(|l| l.contains("fingerprint"))
            .unwrap()
            + 1;
        assert!(
            matches!(&err, JournalError::Syntax { line: l, message, .. } if *l == line && message.contains("not hex")),
            "{err}"
        );
        // The older key=value format and other JSON are named as such.
        let err = JournalRecord::parse("isoforge-journal 1\nexecuted=3\n", "j").unwrap_err();
        assert!(matches!(err, JournalError::NotAJournal { .. }), "{err}");
        let err = JournalRecord::parse("{\"name\": 3}", "j").unwrap_err();
        assert!(matches!(err, JournalError::NotAJournal { .. }), "{err}");
    }

    /// The record's text with one value (a JSON pointer below `job`) replaced.
    fn edited(r: &JournalRecord, pointer: &str, value: serde_json::Value) -> String {
        let mut v: serde_json::Value = serde_json::from_str(&r.to_text()).unwrap();
        *v.pointer_mut(&format!("/job{pointer}")).unwrap() = value;
        serde_json::to_string_pretty(&v).unwrap()
    }

    #[test]
    fn impossible_values_are_refused_naming_the_field() {
        let p = parse(G).unwrap();
        let r = record(&p, 42, 8);
        use serde_json::json;
        for (pointer, value, field) in [
            ("/state/hotends", json!([5000.0]), "state.hotends[0]"),
            ("/state/hotends", json!([-20.0]), "state.hotends[0]"),
            ("/state/hotends", json!([]), "state.hotends"),
            ("/state/bed", json!(900.0), "state.bed"),
            ("/state/z", json!(1e300), "state.z"),
            ("/state/fan", json!(300.0), "state.fan"),
            ("/state/tool", json!(3), "state.tool"),
            ("/executed", json!(99), "executed"),
            ("/source_line", json!(0), "source_line"),
        ] {
            let err = JournalRecord::parse(&edited(&r, pointer, value.clone()), "j").unwrap_err();
            assert!(
                matches!(&err, JournalError::Invalid { problem, .. } if problem.field == field),
                "{pointer}={value}: {err}"
            );
        }
        // NaN has no JSON literal: `z = NaN` is not even JSON.
        let text = edited(&r, "/state/z", json!(1.5)).replace("1.5", "NaN");
        let err = JournalRecord::parse(&text, "j").unwrap_err();
        assert!(matches!(err, JournalError::Syntax { .. }), "{err}");
        // Unknown keys are refused, not skipped.
        let mut v: serde_json::Value = serde_json::from_str(&r.to_text()).unwrap();
        v["job"]["state"]["laser"] = json!(1);
        let err = JournalRecord::parse(&v.to_string(), "j").unwrap_err();
        assert!(
            matches!(&err, JournalError::Syntax { message, .. } if message.contains("laser")),
            "{err}"
        );
    }

    #[test]
    fn a_journal_that_does_not_fit_the_file_is_refused() {
        let p = parse(G).unwrap();
        let r = record(&p, 7, 9);
        let mut hotter = r.clone();
        hotter.state.hotends = vec![250.0];
        assert!(matches!(
            plan_resume(&p, 7, Some(&hotter), None),
            Err(JournalError::Inconsistent { executed: 9, .. })
        ));
        let mut moved = r.clone();
        moved.source_line = 3;
        assert!(matches!(
            plan_resume(&p, 7, Some(&moved), None),
            Err(JournalError::Inconsistent { .. })
        ));
    }

    #[test]
    fn an_unfinished_job_is_not_overwritten() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.gcode.journal");
        assert!(check_can_start(&path, false).is_ok());
        let p = parse(G).unwrap();
        let mut r = record(&p, 7, 5);
        write_durable(&path, r.to_text().as_bytes()).unwrap();
        assert!(matches!(
            check_can_start(&path, false),
            Err(JournalError::Unfinished {
                executed: 5,
                status: Status::Failed,
                ..
            })
        ));
        assert!(check_can_start(&path, true).is_ok());
        r.status = Status::Completed;
        write_durable(&path, r.to_text().as_bytes()).unwrap();
        assert!(check_can_start(&path, false).is_ok());
        // A file that is not a journal (the G-code itself, say) is never overwritten.
        std::fs::write(&path, G).unwrap();
        for restart in [false, true] {
            assert!(matches!(
                check_can_start(&path, restart),
                Err(JournalError::NotAJournal { .. })
            ));
        }
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
    }

    #[test]
    fn refuses_a_changed_file_or_a_finished_job() {
        let p = parse(G).unwrap();
        let r = record(&p, 7, 3);
        assert!(matches!(
            plan_resume(&p, 8, Some(&r), None),
            Err(JournalError::ChangedFile {
                then: 10,
                now: 10,
                ..
            })
        ));
        let mut done = r.clone();
        done.status = Status::Completed;
        assert!(matches!(
            plan_resume(&p, 7, Some(&done), None),
            Err(JournalError::Completed { .. })
        ));
        assert!(matches!(
            plan_resume(&p, 7, None, Some(9)),
            Err(JournalError::NoSuchLayer { layer: 9, .. })
        ));
        assert!(matches!(
            plan_resume(&p, 7, None, None),
            Err(JournalError::NothingToResume)
        ));
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

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]

        /// Random bytes: an error or a valid record, never a panic.
        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..300)) {
            if let Ok(r) = JournalRecord::parse(&String::from_utf8_lossy(&bytes), "r") {
                proptest::prop_assert!(r.validate().is_ok());
            }
        }

        /// A real journal with bytes changed: an error, or a record that passes validation
        /// (and so holds nothing a printer cannot do).
        #[test]
        fn mutated_journals_give_errors_or_valid_records(
            edits in proptest::collection::vec(
                (proptest::prelude::any::<proptest::sample::Index>(), proptest::prelude::any::<u8>()),
                1..6,
            )
        ) {
            let p = parse(G).unwrap();
            let mut bytes = record(&p, 42, 8).to_text().into_bytes();
            for (at, b) in edits {
                let i = at.index(bytes.len());
                bytes[i] = b;
            }
            if let Ok(r) = JournalRecord::parse(&String::from_utf8_lossy(&bytes), "m") {
                proptest::prop_assert!(r.validate().is_ok());
                proptest::prop_assert!(r.state.hotends.iter().all(|t| *t <= MAX_HOTEND));
                proptest::prop_assert!(r.state.z.is_none_or(f64::is_finite));
            }
        }
    }
}
