//! Classifying one line from the printer.
//!
//! Forms follow Marlin (`ok`, `ok N12 P15 B3` with ADVANCED_OK, `Resend: N`, `Error:...`,
//! `echo:busy: processing`, `echo:Unknown command: "X"`, `start`, `//action:pause`), with the
//! variants other RepRap firmwares print (`Resend:N`, `rs N`, Teacup's `rs N2 Expected
//! checksum 67`, `wait`).

use super::temperature::Temperatures;

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
        /// ADVANCED_OK: the last line number the firmware received.
        line: Option<u64>,
        /// ADVANCED_OK: free planner blocks.
        planner: Option<u32>,
        /// ADVANCED_OK: free command-buffer slots.
        buffer: Option<u32>,
        /// Temperatures carried on the same line (`ok T:...`, the M105 reply).
        temps: Option<Temperatures>,
    },
    /// Send again from this line number.
    Resend(u64),
    /// Marlin rejected a line: `Error:Line Number is not Last Line Number+1, Last Line: N`,
    /// `Error:checksum mismatch, Last Line: N`, `Error:No Checksum with line number, Last
    /// Line: N`, `Error:No Line Number with checksum, Last Line: N`.
    LineError {
        /// The last line number the firmware accepted.
        last_line: u64,
        /// The message.
        message: String,
    },
    /// Any other `Error:` line (`Printer halted. kill() called!`).
    Error(String),
    /// `echo:busy: processing` and friends: the printer is alive but working.
    Busy,
    /// `wait`: an idle firmware waiting for commands.
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
        if let Some(n) = resend_number(line) {
            return Reply::Resend(n);
        }
        if let Some(msg) = strip_prefix_ci(line, "error:") {
            let msg = msg.trim().to_string();
            if let Some(last_line) = last_line_number(&msg) {
                return Reply::LineError {
                    last_line,
                    message: msg,
                };
            }
            return Reply::Error(msg);
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
        if let Some(echo) = line.strip_prefix("echo:") {
            let echo = echo.trim_start();
            if echo.starts_with("busy:") {
                return Reply::Busy;
            }
            if let Some(cmd) = echo.strip_prefix("Unknown command:") {
                return Reply::UnknownCommand(cmd.trim().trim_matches('"').to_string());
            }
        }
        if line.starts_with("busy:") {
            return Reply::Busy;
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
    let mut planner = None;
    let mut buffer = None;
    for w in rest.split_whitespace() {
        if let Some(v) = w.strip_prefix('N') {
            line = line.or(v.parse().ok());
        } else if let Some(v) = w.strip_prefix('P') {
            planner = planner.or(v.parse().ok());
        } else if let Some(v) = w.strip_prefix('B') {
            buffer = buffer.or(v.parse().ok());
        }
    }
    Reply::Ok {
        line,
        planner,
        buffer,
        temps: Temperatures::parse(rest),
    }
}

/// `Resend: 12`, `Resend:12`, `rs 12`, `rs N12 Expected checksum 67`.
fn resend_number(line: &str) -> Option<u64> {
    let rest = strip_prefix_ci(line, "resend:").or_else(|| {
        line.strip_prefix("rs ")
            .or_else(|| line.strip_prefix("rs:"))
    })?;
    let rest = rest.trim_start();
    let rest = rest.strip_prefix('N').unwrap_or(rest);
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    // A number followed by garbage is a damaged line, not a request to act on.
    let after = &rest[digits.len()..];
    if !(after.is_empty() || after.starts_with(' ')) {
        return None;
    }
    digits.parse().ok()
}

/// `..., Last Line: 41`.
fn last_line_number(msg: &str) -> Option<u64> {
    let at = msg.find("Last Line:")?;
    let digits = msg[at + "Last Line:".len()..].trim();
    digits.parse().ok()
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
                planner: None,
                buffer: None,
                temps: None
            }
        );
        match Reply::parse("ok N12 P15 B3") {
            Reply::Ok {
                line,
                planner,
                buffer,
                ..
            } => {
                assert_eq!((line, planner, buffer), (Some(12), Some(15), Some(3)));
            }
            r => panic!("{r:?}"),
        }
        match Reply::parse("ok T:200.0 /200.0 B:60.0 /60.0 @:0 B@:0\r") {
            Reply::Ok { temps: Some(t), .. } => assert_eq!(t.tools[0].actual, 200.0),
            r => panic!("{r:?}"),
        }
        // Not an ok: a word that starts with the letters.
        assert!(matches!(Reply::parse("okay"), Reply::Other(_)));
    }

    #[test]
    fn resend_forms() {
        assert_eq!(Reply::parse("Resend: 12"), Reply::Resend(12));
        assert_eq!(Reply::parse("Resend:12"), Reply::Resend(12));
        assert_eq!(Reply::parse("rs 12"), Reply::Resend(12));
        assert_eq!(Reply::parse("rs N2 Expected checksum 67"), Reply::Resend(2));
        assert!(matches!(
            Reply::parse("Resend: 1\u{fffd}2"),
            Reply::Other(_)
        ));
    }

    #[test]
    fn error_forms() {
        for (line, n) in [
            (
                "Error:Line Number is not Last Line Number+1, Last Line: 41",
                41,
            ),
            ("Error:checksum mismatch, Last Line: 7", 7),
            ("Error:No Checksum with line number, Last Line: 0", 0),
            ("Error:No Line Number with checksum, Last Line: 3", 3),
        ] {
            match Reply::parse(line) {
                Reply::LineError { last_line, .. } => assert_eq!(last_line, n),
                r => panic!("{line}: {r:?}"),
            }
        }
        assert_eq!(
            Reply::parse("Error:Printer halted. kill() called!"),
            Reply::Error("Printer halted. kill() called!".into())
        );
    }

    #[test]
    fn chatter_forms() {
        assert_eq!(Reply::parse("echo:busy: processing"), Reply::Busy);
        assert_eq!(Reply::parse("echo:busy: paused for user"), Reply::Busy);
        assert_eq!(Reply::parse("busy: processing"), Reply::Busy);
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
            Reply::parse("//action:resume"),
            Reply::Action(HostAction::Resume)
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
    }
}
