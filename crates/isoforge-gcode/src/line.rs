//! One line of G-code taken apart: line number, command text, checksum, comment.
//!
//! `N12 G1 X10 (fast) Y2*87 ; perimeter` has the line number 12, the command text
//! `G1 X10 Y2`, the checksum 87 (the XOR of every byte before the `*`) and the comment
//! `perimeter`. A file's lines and a wire's lines are read the same way.

use std::borrow::Cow;

use thiserror::Error;

use crate::command::{Command, CommandError};

/// The XOR of every byte, as RepRap firmware computes it over `N<n> <command>`.
pub fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |acc, b| acc ^ b)
}

/// `N<line> <command>*<checksum>`, without a line ending.
pub fn frame(line: u64, command: &str) -> String {
    let body = format!("N{line} {command}");
    let cs = checksum(body.as_bytes());
    format!("{body}*{cs}")
}

/// The lines of a text, ended by `\n`, `\r\n` or a lone `\r` (old Mac files), each with its
/// 1-based number.
pub fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut rest = text;
    let mut number = 0;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let end = rest.find(['\n', '\r']).unwrap_or(rest.len());
        let line = &rest[..end];
        let after = &rest[end..];
        rest = if let Some(r) = after.strip_prefix("\r\n") {
            r
        } else if after.is_empty() {
            after
        } else {
            &after[1..]
        };
        Some((number, line))
    })
}

/// What the line number and checksum of a received line say, read as leniently as a firmware
/// reads them: this never fails, so a damaged line can still be judged.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Framing<'a> {
    /// The `N` word that opens the line, if it has digits.
    pub number: Option<u64>,
    /// True when the line opens with `N` (with or without digits).
    pub has_number_word: bool,
    /// The digits after the last `*`, if they form a byte.
    pub checksum: Option<u8>,
    /// True when the line has a `*`.
    pub has_checksum_mark: bool,
    /// The XOR of the bytes before the last `*` (of the whole line without one).
    pub computed: u8,
    /// Between the line number and the `*`, trimmed; comments are still in.
    pub body: &'a str,
}

impl Framing<'_> {
    /// True when a checksum is given and equals the computed one.
    pub fn checksum_matches(&self) -> bool {
        self.checksum == Some(self.computed)
    }
}

/// Reads the framing of a line (its `;` comment, if any, already removed or not: a `*` after
/// a `;` is not a checksum).
pub fn framing(raw: &str) -> Framing<'_> {
    let code = match raw.find(';') {
        Some(at) => &raw[..at],
        None => raw,
    };
    let (head, checksum, has_mark) = match code.rfind('*') {
        Some(star) => {
            let digits = code[star + 1..].trim();
            let value = (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
                .then(|| digits.parse::<u8>().ok())
                .flatten();
            (&code[..star], value, true)
        }
        None => (code, None, false),
    };
    let computed = checksum_of(head);
    let trimmed = head.trim_start();
    let (number, has_word, body) = match trimmed.strip_prefix(['N', 'n']) {
        Some(after) => {
            let digits = after.bytes().take_while(u8::is_ascii_digit).count();
            let number = after[..digits].parse().ok();
            (number, true, after[digits..].trim())
        }
        None => (None, false, trimmed.trim()),
    };
    Framing {
        number,
        has_number_word: has_word,
        checksum,
        has_checksum_mark: has_mark,
        computed,
        body,
    }
}

fn checksum_of(s: &str) -> u8 {
    checksum(s.as_bytes())
}

/// One line read strictly: everything a printer would execute, or why it cannot be.
#[derive(Clone, Debug, PartialEq)]
pub struct Line<'a> {
    /// The line number the line carries (`N12`), if any.
    pub number: Option<u64>,
    /// The checksum the line carries (`*87`), if any.
    pub checksum: Option<u8>,
    /// The checksum computed over the bytes before the `*`.
    pub computed: u8,
    /// The command text, comments and framing removed, trimmed (`G1 X10 Y2`); empty for a
    /// blank or comment-only line.
    pub text: Cow<'a, str>,
    /// The text after the first `;`, trimmed.
    pub comment: Option<&'a str>,
    /// The command, when the text opens with a G, M or T code; `None` for an empty line or
    /// text of another kind (`X10 Y2`, firmware-specific words), which is kept as text.
    pub command: Option<Command>,
}

/// Why a line cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
pub enum LineError {
    /// A `(` comment is not closed on its line.
    #[error("column {column}: a `(` comment is not closed on this line")]
    UnclosedComment {
        /// 1-based column of the `(`.
        column: usize,
    },
    /// A byte in the command that the serial protocol cannot carry.
    #[error("column {column}: {what} in the command, which a printer cannot take")]
    NotText {
        /// 1-based column.
        column: usize,
        /// What it is, in words.
        what: String,
    },
    /// The `N` word is not a line number.
    #[error("column {column}: `N` must be followed by a line number")]
    BadLineNumber {
        /// 1-based column.
        column: usize,
    },
    /// The checksum after `*` is not a number from 0 to 255.
    #[error("column {column}: the checksum after `*` must be a number from 0 to 255")]
    BadChecksum {
        /// 1-based column.
        column: usize,
    },
    /// The command itself is malformed.
    #[error("column {column}: {source}")]
    Command {
        /// 1-based column of the problem.
        column: usize,
        /// What is wrong.
        source: CommandError,
    },
}

/// Reads one line (without its line ending).
pub fn parse_line(raw: &str) -> Result<Line<'_>, LineError> {
    let (code, comment) = split_comment(raw);
    let (code, checksum_at) = match code.rfind('*') {
        Some(star) => (&code[..star], Some(star)),
        None => (code, None),
    };
    let checksum = match checksum_at {
        Some(star) => {
            let digits = raw[star + 1..code_end(raw)].trim();
            match digits.parse::<u8>() {
                Ok(v) if digits.bytes().all(|b| b.is_ascii_digit()) => Some(v),
                _ => return Err(LineError::BadChecksum { column: star + 1 }),
            }
        }
        None => None,
    };
    let computed = checksum_of(code);
    let without_parens = strip_parens(code)?;
    let leading = without_parens.len() - without_parens.trim_start().len();
    let trimmed = without_parens.trim();
    let (number, body, body_at) = match trimmed.strip_prefix(['N', 'n']) {
        Some(after) => {
            let digits = after.bytes().take_while(u8::is_ascii_digit).count();
            let rest = &after[digits..];
            // `N` alone, or `N12X`: not a line number. A command text never starts with N.
            if digits == 0 || !(rest.is_empty() || rest.starts_with([' ', '\t'])) {
                return Err(LineError::BadLineNumber {
                    column: leading + 1,
                });
            }
            let number = after[..digits]
                .parse()
                .map_err(|_| LineError::BadLineNumber {
                    column: leading + 1,
                })?;
            let body = rest.trim();
            let at = leading + 1 + digits + (rest.len() - rest.trim_start().len());
            (Some(number), body, at)
        }
        None => (None, trimmed, leading),
    };
    if let Some((i, c)) = body
        .char_indices()
        .find(|&(_, c)| !(c.is_ascii() && (!c.is_ascii_control() || c == '\t')))
    {
        // Columns count characters in the original line only approximately once `( )`
        // comments were removed; they are exact for every line without one.
        let what = if c.is_ascii() {
            format!("the control character {:?}", c)
        } else {
            format!("the non-ASCII character {c:?}")
        };
        return Err(LineError::NotText {
            column: body_at + body[..i].chars().count() + 1,
            what,
        });
    }
    let command = Command::parse(body).map_err(|(offset, source)| LineError::Command {
        column: body_at + offset + 1,
        source,
    })?;
    let text = match without_parens {
        Cow::Borrowed(_) => Cow::Borrowed(body_in(raw, body)),
        Cow::Owned(_) => Cow::Owned(body.to_string()),
    };
    Ok(Line {
        number,
        checksum,
        computed,
        text,
        comment,
        command,
    })
}

/// `body` is a subslice of `raw` when no `( )` comment was removed; return it as such so
/// the line borrows instead of allocating.
fn body_in<'a>(raw: &'a str, body: &str) -> &'a str {
    let start = body.as_ptr() as usize - raw.as_ptr() as usize;
    &raw[start..start + body.len()]
}

/// The end of the code part (before the first `;` outside parentheses).
fn code_end(raw: &str) -> usize {
    split_comment(raw).0.len()
}

/// Splits at the first `;` that is not inside a `( )` comment.
fn split_comment(raw: &str) -> (&str, Option<&str>) {
    let mut depth = 0usize;
    for (i, c) in raw.char_indices() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            ';' if depth == 0 => return (&raw[..i], Some(raw[i + 1..].trim())),
            _ => {}
        }
    }
    (raw, None)
}

/// Removes `( ... )` comments (they may nest).
fn strip_parens(code: &str) -> Result<Cow<'_, str>, LineError> {
    if !code.contains('(') {
        return Ok(Cow::Borrowed(code));
    }
    let mut out = String::with_capacity(code.len());
    let mut depth = 0usize;
    let mut opened_at = 0;
    for (i, c) in code.char_indices() {
        match c {
            '(' => {
                if depth == 0 {
                    opened_at = i;
                }
                depth += 1;
            }
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    if depth > 0 {
        return Err(LineError::UnclosedComment {
            column: code[..opened_at].chars().count() + 1,
        });
    }
    Ok(Cow::Owned(out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_framed_line_with_comments() {
        let raw = "N12 G1 X10 (fast) Y2*87 ; perimeter";
        let l = parse_line(raw).unwrap();
        assert_eq!(l.number, Some(12));
        assert_eq!(l.checksum, Some(87));
        assert_eq!(l.computed, checksum(b"N12 G1 X10 (fast) Y2"));
        assert_eq!(l.text, "G1 X10  Y2");
        assert_eq!(l.comment, Some("perimeter"));
        let c = l.command.unwrap();
        assert_eq!(c.get('X'), Some(10.0));
        assert_eq!(c.get('Y'), Some(2.0));
    }

    #[test]
    fn frame_and_framing_agree() {
        let f = frame(7, "G28");
        assert_eq!(f, format!("N7 G28*{}", checksum(b"N7 G28")));
        let r = framing(&f);
        assert_eq!(r.number, Some(7));
        assert!(r.checksum_matches());
        assert_eq!(r.body, "G28");
        assert_eq!(frame(0, "M110 N0"), "N0 M110 N0*125");
    }

    #[test]
    fn framing_reads_damaged_lines_without_failing() {
        let r = framing("N1x G1 X1*2a");
        assert_eq!(r.number, Some(1));
        assert_eq!(r.checksum, None);
        assert!(r.has_checksum_mark && !r.checksum_matches());
        let r = framing("G1 X1");
        assert!(!r.has_number_word && !r.has_checksum_mark);
        let r = framing("N5 G1 X1*999");
        assert_eq!(r.checksum, None);
    }

    #[test]
    fn blank_and_comment_lines_have_no_command() {
        for raw in ["", "   ", "; just a comment", "(only this)"] {
            let l = parse_line(raw).unwrap();
            assert!(l.text.is_empty() && l.command.is_none(), "{raw:?}");
        }
    }

    #[test]
    fn errors_say_the_column() {
        assert_eq!(
            parse_line("G1 (open").unwrap_err(),
            LineError::UnclosedComment { column: 4 }
        );
        assert!(matches!(
            parse_line("M117 h\u{e9}llo").unwrap_err(),
            LineError::NotText { column: 7, .. }
        ));
        assert!(matches!(
            parse_line("N G1").unwrap_err(),
            LineError::BadLineNumber { column: 1 }
        ));
        assert!(matches!(
            parse_line("G1 X1*300").unwrap_err(),
            LineError::BadChecksum { column: 6 }
        ));
        assert!(matches!(
            parse_line("G1 Xabc").unwrap_err(),
            LineError::Command { column: 4, .. }
        ));
    }

    #[test]
    fn line_endings_of_every_kind() {
        let got: Vec<_> = lines("a\nb\r\nc\rd").collect();
        assert_eq!(got, [(1, "a"), (2, "b"), (3, "c"), (4, "d")]);
        let got: Vec<_> = lines("a\r\r\nb\n").collect();
        assert_eq!(got, [(1, "a"), (2, ""), (3, "b")]);
        assert_eq!(lines("").count(), 0);
    }

    #[test]
    fn a_star_in_a_comment_is_not_a_checksum() {
        let l = parse_line("G1 X1 ; 2*3").unwrap();
        assert_eq!(l.checksum, None);
        assert_eq!(l.text, "G1 X1");
        assert!(!framing("G1 X1 ; 2*3").has_checksum_mark);
    }
}
