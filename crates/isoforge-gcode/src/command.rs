//! A command's words: its code (`G1`, `M104`, `T0`, `G29.1`) and parameters (`X10`, `S200`,
//! a bare `X` as in `G28 X`), or the free text of a message command (`M117 Printing...`).
//!
//! Numbers are plain decimals with an optional sign (`-1.5`, `.3`, `+2`); there is no
//! exponent, so `X1e3` reads as `X1` followed by `E3`, as G-code has always been written.
//! Spaces between words are optional (`G1X10Y2` is `G1 X10 Y2`); letters are read
//! case-insensitively.

use std::fmt;

use thiserror::Error;

/// Commands whose argument is free text (file names, messages), not words.
const TEXT_COMMANDS: [(char, u32); 9] = [
    ('M', 0),
    ('M', 1),
    ('M', 23),
    ('M', 28),
    ('M', 30),
    ('M', 32),
    ('M', 117),
    ('M', 118),
    ('M', 928),
];

/// A command code: `G1`, `M104`, `T0`, `G29.1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Code {
    /// `G`, `M` or `T`.
    pub letter: char,
    /// The number (`G01` and `G1` are both 1).
    pub number: u32,
    /// The sub-code after a dot (`G29.1`).
    pub sub: Option<u32>,
}

impl Code {
    /// True for `letter` + `number` with no sub-code.
    pub fn is(&self, letter: char, number: u32) -> bool {
        self.letter == letter && self.number == number && self.sub.is_none()
    }
}

impl fmt::Display for Code {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.letter, self.number)?;
        if let Some(s) = self.sub {
            write!(f, ".{s}")?;
        }
        Ok(())
    }
}

/// One parameter word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Param {
    /// The letter, upper case.
    pub letter: char,
    /// Its value; `None` for a bare letter (`G28 X`).
    pub value: Option<f64>,
}

/// A parsed command.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    /// The code.
    pub code: Code,
    /// The parameter words in order (empty for a text command).
    pub params: Vec<Param>,
    /// The free text of a message or file command (`M117 Hello`), trimmed.
    pub text: Option<String>,
}

/// What is wrong with a command's words.
#[derive(Clone, Debug, PartialEq, Eq, Error)]
pub enum CommandError {
    /// A G, M or T without a number, or with a number that is not a whole number.
    #[error("`{letter}` must be followed by a command number, found {found:?}")]
    BadCode {
        /// The code letter.
        letter: char,
        /// What followed it.
        found: String,
    },
    /// A parameter whose value is not a number.
    #[error("`{letter}` must be followed by a number, found {found:?}")]
    BadNumber {
        /// The parameter letter.
        letter: char,
        /// What followed it.
        found: String,
    },
    /// A character that starts no word.
    #[error("unexpected {found:?}; a word is a letter and a number")]
    Unexpected {
        /// The character.
        found: char,
    },
}

/// Longest text quoted back in an error message, in characters.
const SHOWN: usize = 24;

fn shown(s: &str) -> String {
    let mut out: String = s.chars().take(SHOWN).collect();
    if s.chars().count() > SHOWN {
        out.push_str("...");
    }
    out
}

impl Command {
    /// The value of parameter `letter` (upper case), when it has one.
    pub fn get(&self, letter: char) -> Option<f64> {
        self.params
            .iter()
            .find(|p| p.letter == letter)
            .and_then(|p| p.value)
    }

    /// True when parameter `letter` appears, with or without a value.
    pub fn has(&self, letter: char) -> bool {
        self.params.iter().any(|p| p.letter == letter)
    }

    /// Parses command text (no line number, checksum or comment). `Ok(None)` for empty text
    /// or text that does not open with a G, M or T code. An error carries the byte offset of
    /// the problem in `text`.
    pub fn parse(text: &str) -> Result<Option<Command>, (usize, CommandError)> {
        let bytes = text.as_bytes();
        let mut i = skip_space(bytes, 0);
        let Some(&first) = bytes.get(i) else {
            return Ok(None);
        };
        let letter = first.to_ascii_uppercase() as char;
        if !matches!(letter, 'G' | 'M' | 'T') {
            return Ok(None);
        }
        let code_at = i;
        i += 1;
        let digits = count_digits(bytes, i);
        let number = text[i..i + digits].parse::<u32>().ok();
        let mut end = i + digits;
        let mut sub = None;
        if bytes.get(end) == Some(&b'.') {
            let sub_digits = count_digits(bytes, end + 1);
            sub = text[end + 1..end + 1 + sub_digits].parse::<u32>().ok();
            if sub.is_none() {
                return Err(bad_code(text, code_at, letter));
            }
            end += 1 + sub_digits;
        }
        let Some(number) = number else {
            return Err(bad_code(text, code_at, letter));
        };
        if bytes
            .get(end)
            .is_some_and(|b| !(b.is_ascii_whitespace() || b.is_ascii_alphabetic()))
        {
            return Err(bad_code(text, code_at, letter));
        }
        let code = Code {
            letter,
            number,
            sub,
        };
        if sub.is_none() && TEXT_COMMANDS.contains(&(letter, number)) {
            let rest = text[end..].trim();
            return Ok(Some(Command {
                code,
                params: Vec::new(),
                text: (!rest.is_empty()).then(|| rest.to_string()),
            }));
        }
        let params = parse_params(text, end)?;
        Ok(Some(Command {
            code,
            params,
            text: None,
        }))
    }
}

fn bad_code(text: &str, at: usize, letter: char) -> (usize, CommandError) {
    let found = text[at + 1..]
        .split(|c: char| c.is_ascii_whitespace())
        .next()
        .unwrap_or("");
    (
        at,
        CommandError::BadCode {
            letter,
            found: shown(found),
        },
    )
}

fn skip_space(bytes: &[u8], mut i: usize) -> usize {
    while bytes.get(i).is_some_and(u8::is_ascii_whitespace) {
        i += 1;
    }
    i
}

fn count_digits(bytes: &[u8], from: usize) -> usize {
    bytes[from.min(bytes.len())..]
        .iter()
        .take_while(|b| b.is_ascii_digit())
        .count()
}

/// Parameter words from byte `i` on.
fn parse_params(text: &str, mut i: usize) -> Result<Vec<Param>, (usize, CommandError)> {
    let bytes = text.as_bytes();
    let mut params = Vec::new();
    loop {
        i = skip_space(bytes, i);
        let Some(&b) = bytes.get(i) else {
            return Ok(params);
        };
        if !b.is_ascii_alphabetic() {
            let found = text[i..].chars().next().unwrap_or(' ');
            return Err((i, CommandError::Unexpected { found }));
        }
        let letter = b.to_ascii_uppercase() as char;
        let start = i + 1;
        let len = number_len(bytes, start);
        if len > 0 {
            let value = text[start..start + len]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite());
            let next = bytes.get(start + len);
            let clean_end = next.is_none_or(|n| n.is_ascii_whitespace() || n.is_ascii_alphabetic());
            match value {
                Some(v) if clean_end => {
                    params.push(Param {
                        letter,
                        value: Some(v),
                    });
                    i = start + len;
                    continue;
                }
                _ => return Err(bad_number(text, i, letter)),
            }
        }
        // No number: a bare letter (`G28 X Y`, `G28 XY`). A letter followed by more letters
        // is only read as bare letters when the whole word is upper-case flags, so that
        // `Xabc` is reported rather than read as X, A, B, C.
        match bytes.get(start) {
            None => {}
            Some(n) if n.is_ascii_whitespace() => {}
            Some(n) if n.is_ascii_alphabetic() && is_flag_word(text, i) => {}
            _ => return Err(bad_number(text, i, letter)),
        }
        params.push(Param {
            letter,
            value: None,
        });
        i = start;
    }
}

/// The word starting at `at` is made of upper-case letters only (`XY`, `XYZ`).
fn is_flag_word(text: &str, at: usize) -> bool {
    text[at..]
        .split(|c: char| c.is_ascii_whitespace())
        .next()
        .is_some_and(|w| w.bytes().all(|b| b.is_ascii_uppercase()))
}

fn bad_number(text: &str, at: usize, letter: char) -> (usize, CommandError) {
    let found = text[at + 1..]
        .split(|c: char| c.is_ascii_whitespace())
        .next()
        .unwrap_or("");
    (
        at,
        CommandError::BadNumber {
            letter,
            found: shown(found),
        },
    )
}

/// Length of what starts a number at `i`: `[+-]? digits? [. digits?]`, or 0 when nothing
/// there looks like one. A sign or a dot alone counts too, so it is reported as malformed
/// (the caller's parse fails on it).
fn number_len(bytes: &[u8], i: usize) -> usize {
    let mut j = i;
    if matches!(bytes.get(j), Some(b'+' | b'-')) {
        j += 1;
    }
    j += count_digits(bytes, j);
    if bytes.get(j) == Some(&b'.') {
        j += 1;
        j += count_digits(bytes, j);
    }
    j - i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Command {
        Command::parse(text).unwrap().unwrap()
    }

    #[test]
    fn codes_in_every_spelling() {
        assert_eq!(parse("G01 X1").code, parse("G1 X1").code);
        assert_eq!(parse("g1 x1").code.to_string(), "G1");
        assert_eq!(parse("G29.1").code.to_string(), "G29.1");
        assert_eq!(
            parse("T1").code,
            Code {
                letter: 'T',
                number: 1,
                sub: None
            }
        );
        assert!(parse("M104 S200").code.is('M', 104));
    }

    #[test]
    fn words_with_and_without_spaces() {
        let c = parse("G1X10.5Y-2E.3F+1200");
        assert_eq!(c.get('X'), Some(10.5));
        assert_eq!(c.get('Y'), Some(-2.0));
        assert_eq!(c.get('E'), Some(0.3));
        assert_eq!(c.get('F'), Some(1200.0));
        let c = parse("G28 X Y");
        assert!(c.has('X') && c.has('Y') && !c.has('Z'));
        assert_eq!(c.get('X'), None);
        let c = parse("G28 XY");
        assert!(c.has('X') && c.has('Y'));
        // No exponent: `1e3` is 1 and then E3.
        let c = parse("G1 X1e3");
        assert_eq!((c.get('X'), c.get('E')), (Some(1.0), Some(3.0)));
    }

    #[test]
    fn message_commands_keep_their_text() {
        let c = parse("M117 Layer 3 of 10: X1");
        assert!(c.params.is_empty());
        assert_eq!(c.text.as_deref(), Some("Layer 3 of 10: X1"));
        assert_eq!(parse("M117").text, None);
    }

    #[test]
    fn other_text_is_not_a_command() {
        assert_eq!(Command::parse("").unwrap(), None);
        assert_eq!(Command::parse("X10 Y2").unwrap(), None);
    }

    #[test]
    fn malformed_words_are_errors_with_offsets() {
        for (text, at) in [
            ("G1 Xabc", 3),
            ("G1 X1.2.3", 3),
            ("G1 X-", 3),
            ("G1 X.", 3),
            ("G1 X10#", 3),
            ("M", 0),
            ("G1.x", 0),
            ("Gx1", 0),
            ("G1 #", 3),
        ] {
            let (offset, _) = Command::parse(text).expect_err(text);
            assert_eq!(offset, at, "{text}");
        }
        let long = format!("G1 X{}", "9".repeat(400));
        assert!(
            Command::parse(&long).is_err(),
            "an infinite value is refused"
        );
    }

    #[test]
    fn error_messages_quote_a_bounded_excerpt() {
        let text = format!("G1 X{}", "q".repeat(10_000));
        let (_, e) = Command::parse(&text).unwrap_err();
        assert!(e.to_string().len() < 100, "{e}");
    }
}
