//! Classifying one line from the printer.
//!
//! `ok` in its forms (`ok`, `ok N12 P15 B3` with ADVANCED_OK, `ok 12` from Repetier,
//! `ok T:...` as the M105 reply), resend requests in every firmware's form (see
//! [`crate::dialect`]), `Error:` lines (judged by the protocol, which sees the burst they
//! come in), fatal `!!`/`fatal:` lines, busy and wait, `start`, unknown-command echoes,
//! temperature reports, `//action:` requests; anything else is chatter.

use super::temperature::Temperatures;
use crate::dialect::{self, ResendForm};

/// What the firmware asks the host to do (`//action:...`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HostAction {
    /// Stop sending until told to resume.
    Pause,
    /// Carry on after a pause.
    Resume,
    /// Abandon the job.
    Cancel,
    /// Another action word, passed on as a message.
    Other(String),
}

/// One line from the printer, classified.
#[derive(Clone, Debug, PartialEq)]
pub enum Reply {
    /// A command was processed.
    Ok {
        /// ADVANCED_OK: the last line number the firmware received (Repetier: the line
        /// this `ok` is for).
        line: Option<u64>,
        /// ADVANCED_OK: free command-buffer slots.
        buffer: Option<u32>,
        /// Temperatures carried on the same line (`ok T:...`, the M105 reply).
        temps: Option<Temperatures>,
    },
    /// A resend request (or Repetier's `skip`), with its form.
    Resend(u64, ResendForm),
    /// An `Error:` line, the text after `Error:`.
    Error(String),
    /// A line that is fatal by its opening (`!! ...`, `fatal: ...`).
    Fatal(String),
    /// `echo:busy: processing` and friends: the printer is alive but working.
    Busy,
    /// `wait`: the firmware is idle with nothing queued.
    Wait,
    /// `start`: the firmware (re)booted.
    Start,
    /// `echo:Unknown command: "X1"`.
    UnknownCommand(String),
    /// A temperature report without `ok` (auto-report or during heating).
    Temperatures(Temperatures),
    /// `//action:...`.
    Action(HostAction),
    /// Anything else (echo lines, firmware chatter).
    Other(String),
}

impl Reply {
    /// Classifies a line (without its line ending).
    pub fn parse(raw: &str) -> Reply {
        let line = raw.trim();
        if let Some(rest) = line.strip_prefix("ok")
            && (rest.is_empty() || rest.starts_with(' '))
        {
            return parse_ok(rest);
        }
        if let Some((n, form)) = dialect::resend_request(line) {
            return Reply::Resend(n, form);
        }
        if let Some(msg) = strip_prefix_ci(line, "error:") {
            return Reply::Error(msg.trim().to_string());
        }
        if dialect::is_fatal_line(line) {
            return Reply::Fatal(line.to_string());
        }
        if line == "start" {
            return Reply::Start;
        }
        if line == "wait" {
            return Reply::Wait;
        }
        if let Some(rest) = line.strip_prefix("//action:") {
            let word = rest.split_whitespace().next().unwrap_or("");
            return Reply::Action(match word {
                "pause" | "paused" => HostAction::Pause,
                "resume" | "resumed" => HostAction::Resume,
                "cancel" => HostAction::Cancel,
                _ => HostAction::Other(rest.to_string()),
            });
        }
        let unprefixed = line.strip_prefix("echo:").map_or(line, str::trim_start);
        // Marlin `echo:busy: processing`, Repetier `busy:processing`, OctoPrint's
        // simulator `echo:busy processing`.
        if unprefixed
            .strip_prefix("busy")
            .is_some_and(|r| r.starts_with([':', ' ']))
        {
            return Reply::Busy;
        }
        if let Some(cmd) = unprefixed.strip_prefix("Unknown command:") {
            return Reply::UnknownCommand(cmd.trim().trim_matches('"').to_string());
        }
        if let Some(t) = Temperatures::parse(line) {
            return Reply::Temperatures(t);
        }
        Reply::Other(line.to_string())
    }
}

fn strip_prefix_ci<'a>(s: &'a str, prefix: &str) -> Option<&'a str> {
    let head = s.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix)
        .then(|| &s[prefix.len()..])
}

fn parse_ok(rest: &str) -> Reply {
    let mut line = None;
    let mut buffer = None;
    let mut advanced = false;
    for w in rest.split_whitespace() {
        if let Some(v) = w.strip_prefix('N') {
            advanced = true;
            line = line.or(v.parse().ok());
        } else if let Some(v) = w.strip_prefix('B') {
            buffer = buffer.or(v.parse().ok());
        } else if w.bytes().all(|b| b.is_ascii_digit()) {
            line = line.or(w.parse().ok());
        }
    }
    if advanced && buffer.is_none() {
        // ADVANCED_OK's `N` is the last line received, not the line this `ok` is for (as
        // Repetier's bare number is): with its `B` damaged, it is a plain `ok`.
        line = None;
    }
    Reply::Ok {
        line,
        buffer,
        temps: Temperatures::parse(rest),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ok_forms() {
        assert_eq!(
            Reply::parse("ok"),
            Reply::Ok {
                line: None,
                buffer: None,
                temps: None
            }
        );
        match Reply::parse("ok N12 P15 B3") {
            Reply::Ok { line, buffer, .. } => assert_eq!((line, buffer), (Some(12), Some(3))),
            r => panic!("{r:?}"),
        }
        match Reply::parse("ok N12 P15 B\u{fffd}") {
            Reply::Ok { line, buffer, .. } => assert_eq!((line, buffer), (None, None)),
            r => panic!("{r:?}"),
        }
        match Reply::parse("ok 12") {
            Reply::Ok { line, buffer, .. } => assert_eq!((line, buffer), (Some(12), None)),
            r => panic!("{r:?}"),
        }
        match Reply::parse("ok T:200.0 /200.0 B:60.0 /60.0 @:0 B@:0\r") {
            Reply::Ok { temps: Some(t), .. } => assert_eq!(t.tools[0].actual, 200.0),
            r => panic!("{r:?}"),
        }
        // Not an ok: a word that starts with the letters, or `SD card ok`.
        assert!(matches!(Reply::parse("okay"), Reply::Other(_)));
        assert!(matches!(Reply::parse("SD card ok"), Reply::Other(_)));
    }

    #[test]
    fn resends_errors_and_fatal_lines() {
        assert_eq!(
            Reply::parse("Resend: 12"),
            Reply::Resend(12, ResendForm::Resend)
        );
        assert_eq!(Reply::parse("skip 12"), Reply::Resend(12, ResendForm::Skip));
        assert_eq!(
            Reply::parse("Error: Missing checksum"),
            Reply::Error("Missing checksum".into())
        );
        assert_eq!(
            Reply::parse("!! Lost communication with MCU 'mcu'"),
            Reply::Fatal("!! Lost communication with MCU 'mcu'".into())
        );
        assert!(matches!(
            Reply::parse("fatal:Heater failure"),
            Reply::Fatal(_)
        ));
    }

    #[test]
    fn chatter_forms() {
        for busy in [
            "echo:busy: processing",
            "echo:busy: paused for user",
            "busy: processing",
            "busy:processing",
            "echo:busy processing",
        ] {
            assert_eq!(Reply::parse(busy), Reply::Busy, "{busy}");
        }
        assert_eq!(Reply::parse("wait"), Reply::Wait);
        assert_eq!(Reply::parse("start"), Reply::Start);
        assert_eq!(
            Reply::parse("echo:Unknown command: \"X123\""),
            Reply::UnknownCommand("X123".into())
        );
        assert_eq!(
            Reply::parse("//action:pause"),
            Reply::Action(HostAction::Pause)
        );
        assert_eq!(
            Reply::parse("//action:cancel"),
            Reply::Action(HostAction::Cancel)
        );
        assert!(matches!(
            Reply::parse(" T:20.0 /0.0 B:20.0 /0.0 @:0 B@:0"),
            Reply::Temperatures(_)
        ));
        assert!(matches!(Reply::parse("echo:SD init fail"), Reply::Other(_)));
        assert!(matches!(
            Reply::parse("Marlin: Virtual Marlin!"),
            Reply::Other(_)
        ));
    }
}
