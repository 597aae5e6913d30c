//! The numbered lines of a job: what each line number carries, kept for resends.
//!
//! Line numbers (what the firmware counts, `N123`) and job indices (which command of the job)
//! are different things: the host numbers its own lines too (the opening `M110`, `M105`
//! probes, `M108`, the shutdown of a cancelled job), so they are separate types.

use std::fmt;

/// A line number on the wire.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct LineNo(pub u64);

impl LineNo {
    /// The line after this one.
    pub fn next(self) -> LineNo {
        LineNo(self.0 + 1)
    }
}

impl fmt::Display for LineNo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// The place of a command in the job (a resume's prelude, then the file's commands from
/// where the job starts).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct JobIndex(pub usize);

/// What a numbered line carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Carries {
    /// `M110 N0`: line 0, which sets the firmware's count.
    Reset,
    /// A job command.
    Job(JobIndex),
    /// `M105`: its answer comes only after everything before it has executed.
    Probe,
    /// `M108`: ends a heating wait (Marlin's emergency parser acts on it at once).
    Interrupt,
    /// Command `i` of the shutdown sequence of a cancelled job.
    Shutdown(usize),
    /// `M112`.
    Emergency,
}

impl Carries {
    /// The host's own command text (job commands have theirs in the job).
    pub fn host_text(self) -> Option<&'static str> {
        match self {
            Carries::Reset => Some("M110 N0"),
            Carries::Probe => Some("M105"),
            Carries::Interrupt => Some("M108"),
            Carries::Emergency => Some("M112"),
            Carries::Job(_) | Carries::Shutdown(_) => None,
        }
    }
}

/// Every line numbered so far, by line number.
#[derive(Debug, Default)]
pub(crate) struct Wire {
    lines: Vec<Carries>,
}

impl Wire {
    /// Numbers the next line.
    pub fn push(&mut self, c: Carries) -> LineNo {
        self.lines.push(c);
        LineNo(self.lines.len() as u64 - 1)
    }

    /// What line `n` carries.
    pub fn get(&self, n: LineNo) -> Option<Carries> {
        self.lines.get(n.0 as usize).copied()
    }

    /// The last line numbered (`None` before line 0).
    pub fn high(&self) -> Option<LineNo> {
        self.lines.len().checked_sub(1).map(|n| LineNo(n as u64))
    }

    /// The next number to give.
    pub fn next_number(&self) -> LineNo {
        LineNo(self.lines.len() as u64)
    }

    /// Forgets the lines after `keep` (the firmware took none of them) and returns them in
    /// order, so whatever they carried can be numbered again.
    pub fn truncate_after(&mut self, keep: LineNo) -> Vec<Carries> {
        let from = (keep.0 as usize + 1).min(self.lines.len());
        self.lines.split_off(from)
    }
}
