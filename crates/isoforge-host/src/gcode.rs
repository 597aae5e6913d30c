//! Reading a G-code file into the commands a printer executes, and framing them for the wire.
//!
//! Comments (`; ...` and `( ... )`) and blank lines never reach the printer; each command keeps
//! the source line it came from so errors, progress and the journal can point into the file.
//! Layer starts come from `;LAYER:n` comments when the slicer wrote them, else from the Z
//! height of the first extruding move at each new height.

use std::path::Path;

use thiserror::Error;

/// Marlin's `MAX_CMD_SIZE` is 96 bytes including the terminating NUL: anything longer is cut
/// silently, so a longer framed line must be refused before it is sent.
pub(crate) const MAX_FRAMED_LEN: usize = 95;

/// One command as the printer will execute it.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    /// The command text, comments and surrounding spaces removed (e.g. `G1 X10 Y20 E0.5`).
    pub text: String,
    /// 1-based line number in the source file.
    pub source_line: usize,
}

/// Where a layer starts in the command list.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// The layer's number (from `;LAYER:n`, else counted from 0).
    pub number: u32,
    /// Index into [`Program::commands`] of the layer's first command.
    pub first_command: usize,
    /// The layer's height, when a Z move for it was seen.
    pub z: Option<f64>,
}

/// A G-code file read into commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Program {
    /// The commands in file order.
    pub commands: Vec<Command>,
    /// Layer starts, in file order.
    pub layers: Vec<Layer>,
}

/// What is wrong with a G-code file or a line to be framed.
#[derive(Debug, Error)]
pub enum GcodeError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// A line is not text the printer can take.
    #[error("line {line}: {reason}")]
    BadLine {
        /// 1-based source line.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A framed line exceeds Marlin's buffer and would be truncated by the firmware.
    #[error(
        "line {line}: framed as {framed:?} it is {len} bytes, over Marlin's {MAX_FRAMED_LEN}-byte limit (the firmware would cut it); shorten the command"
    )]
    TooLong {
        /// 1-based source line (0 when the command was not from a file).
        line: usize,
        /// The framed text.
        framed: String,
        /// Its length in bytes.
        len: usize,
    },
}

/// The XOR of every byte, as RepRap firmware computes it over `N<n> <command>`.
pub(crate) fn checksum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |acc, b| acc ^ b)
}

/// Frames a command as `N<line> <command>*<checksum>` followed by a newline.
///
/// `source_line` is only used to say where a too-long command came from.
pub fn frame(line: u64, command: &str, source_line: usize) -> Result<String, GcodeError> {
    let body = format!("N{line} {command}");
    let cs = checksum(body.as_bytes());
    let framed = format!("{body}*{cs}");
    if framed.len() > MAX_FRAMED_LEN {
        return Err(GcodeError::TooLong {
            line: source_line,
            len: framed.len(),
            framed,
        });
    }
    Ok(framed + "\n")
}

/// Removes `;` comments and `( ... )` comments and trims the rest.
///
/// Returns `None` for an unterminated `(` comment, which Marlin would also misread.
pub(crate) fn strip_comments(line: &str) -> Option<String> {
    let mut out = String::with_capacity(line.len());
    let mut depth = 0usize;
    for c in line.chars() {
        match c {
            ';' if depth == 0 => break,
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    if depth > 0 {
        return None;
    }
    Some(out.trim().to_string())
}

/// Drops a line number and checksum a file may already carry (`N12 G1 X1*34`): the host
/// numbers lines itself, and a stale checksum would be wrong after renumbering.
fn strip_framing(cmd: &str) -> &str {
    let mut rest = cmd;
    if let Some(after) = rest.strip_prefix(['N', 'n']) {
        let digits = after.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 && after[digits..].starts_with([' ', '\t']) {
            rest = after[digits..].trim_start();
        }
    }
    if let Some(star) = rest.rfind('*')
        && rest[star + 1..].bytes().all(|b| b.is_ascii_digit())
    {
        rest = rest[..star].trim_end();
    }
    rest
}

/// Reads a G-code file.
pub fn read_file(path: &Path) -> Result<Program, GcodeError> {
    let bytes = std::fs::read(path).map_err(|source| GcodeError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    parse(&text)
}

/// Parses G-code text into commands and layer starts.
///
/// Every command is checked here so that no error can surface halfway through a print: it
/// must be ASCII without `*` (the checksum marker), and framed with the largest line number
/// this job can reach it must fit `MAX_FRAMED_LEN` (95 bytes).
pub fn parse(text: &str) -> Result<Program, GcodeError> {
    let mut program = Program::default();
    let mut layers = LayerFinder::default();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        if let Some(number) = layer_comment(raw) {
            layers.comment(number, program.commands.len());
        }
        let Some(stripped) = strip_comments(raw) else {
            return Err(GcodeError::BadLine {
                line,
                reason: "a `(` comment is not closed on this line".into(),
            });
        };
        let cmd = strip_framing(&stripped);
        if cmd.is_empty() {
            continue;
        }
        if let Some(pos) = cmd.find(|c: char| !c.is_ascii() || c.is_ascii_control()) {
            return Err(GcodeError::BadLine {
                line,
                reason: format!(
                    "byte {} is not plain ASCII text, which the serial protocol cannot carry",
                    pos + 1
                ),
            });
        }
        if cmd.contains('*') {
            return Err(GcodeError::BadLine {
                line,
                reason: "`*` inside a command would be read as the checksum marker".into(),
            });
        }
        layers.command(cmd, program.commands.len());
        program.commands.push(Command {
            text: cmd.to_string(),
            source_line: line,
        });
    }
    // Resumed jobs add a short prelude, so leave room for it in the line-number width.
    let worst_line = program.commands.len() as u64 + PRELUDE_ALLOWANCE;
    for c in &program.commands {
        frame(worst_line, &c.text, c.source_line)?;
    }
    program.layers = layers.finish();
    Ok(program)
}

/// Line numbers a resume prelude may add in front of the remaining commands.
pub(crate) const PRELUDE_ALLOWANCE: u64 = 64;

impl Program {
    /// The layer that command `index` belongs to.
    pub fn layer_of(&self, index: usize) -> Option<&Layer> {
        let after = self.layers.partition_point(|l| l.first_command <= index);
        after.checked_sub(1).map(|i| &self.layers[i])
    }

    /// The layer with the given number.
    pub fn layer(&self, number: u32) -> Option<&Layer> {
        self.layers.iter().find(|l| l.number == number)
    }
}

/// `;LAYER:12` (Cura, isoforge) or `;LAYER_CHANGE` followed by nothing we can number.
fn layer_comment(raw: &str) -> Option<u32> {
    let t = raw.trim_start();
    let rest = t.strip_prefix(";LAYER:")?;
    rest.trim().parse().ok()
}

/// The value of one word (`Z` in `G1 Z0.3 F600`).
pub(crate) fn word(cmd: &str, letter: char) -> Option<f64> {
    cmd.split_ascii_whitespace()
        .skip(1)
        .find_map(|w| w.strip_prefix(letter).and_then(|v| v.parse().ok()))
}

/// The command's code (`G1`, `M104`, `T0`), upper-cased, without leading zeros.
pub(crate) fn code(cmd: &str) -> String {
    let first = cmd.split_ascii_whitespace().next().unwrap_or("");
    let mut chars = first.chars();
    let Some(letter) = chars.next() else {
        return String::new();
    };
    let num = chars.as_str();
    let num = match num.parse::<u32>() {
        Ok(n) => n.to_string(),
        Err(_) => num.to_string(),
    };
    format!("{}{num}", letter.to_ascii_uppercase())
}

/// Finds layer starts while commands stream past.
#[derive(Default)]
struct LayerFinder {
    from_comments: Vec<Layer>,
    from_z: Vec<Layer>,
    z: Option<f64>,
    z_move_at: usize,
    layer_z: Option<f64>,
    relative: bool,
    relative_e: bool,
    e: f64,
}

impl LayerFinder {
    fn comment(&mut self, number: u32, next_command: usize) {
        self.from_comments.push(Layer {
            number,
            first_command: next_command,
            z: None,
        });
    }

    fn command(&mut self, cmd: &str, index: usize) {
        match code(cmd).as_str() {
            "G90" => (self.relative, self.relative_e) = (false, false),
            "G91" => (self.relative, self.relative_e) = (true, true),
            "M82" => self.relative_e = false,
            "M83" => self.relative_e = true,
            "G92" => {
                if let Some(e) = word(cmd, 'E') {
                    self.e = e;
                }
            }
            "G0" | "G1" => {
                if let Some(z) = word(cmd, 'Z') {
                    let z = if self.relative {
                        self.z.unwrap_or(0.0) + z
                    } else {
                        z
                    };
                    self.z = Some(z);
                    self.z_move_at = index;
                    // A comment-marked layer gets its height from its first Z move.
                    if let Some(last) = self.from_comments.last_mut()
                        && last.z.is_none()
                        && last.first_command <= index
                    {
                        last.z = Some(z);
                    }
                }
                if let Some(e) = word(cmd, 'E') {
                    let extrudes = if self.relative_e { e > 0.0 } else { e > self.e };
                    self.e = if self.relative_e { self.e + e } else { e };
                    // A new layer is where extrusion first happens at a new height (z-hops
                    // move Z without extruding, so they do not count).
                    if extrudes && self.z.is_some() && self.z != self.layer_z {
                        self.layer_z = self.z;
                        self.from_z.push(Layer {
                            number: self.from_z.len() as u32,
                            first_command: self.z_move_at.min(index),
                            z: self.z,
                        });
                    }
                }
            }
            _ => {}
        }
    }

    fn finish(self) -> Vec<Layer> {
        if self.from_comments.is_empty() {
            self.from_z
        } else {
            self.from_comments
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_matches_reprap_examples() {
        // RepRap wiki: "N123 M104 S200" has checksum 68... computed by hand as XOR.
        let body = "N1 G28";
        let expect = body.bytes().fold(0u8, |a, b| a ^ b);
        assert_eq!(checksum(body.as_bytes()), expect);
        assert_eq!(frame(1, "G28", 1).unwrap(), format!("N1 G28*{expect}\n"));
        assert_eq!(frame(0, "M110 N0", 0).unwrap(), "N0 M110 N0*125\n");
    }

    #[test]
    fn comments_and_blank_lines_are_stripped() {
        let p = parse("; header\nG28 ; home\n\n  (note) G1 X1 (more) Y2  \nM104 S200\n").unwrap();
        let texts: Vec<_> = p.commands.iter().map(|c| c.text.as_str()).collect();
        assert_eq!(texts, ["G28", "G1 X1  Y2", "M104 S200"]);
        assert_eq!(p.commands[1].source_line, 4);
        assert_eq!(p.commands[2].source_line, 5);
    }

    #[test]
    fn existing_framing_is_removed() {
        let p = parse("N5 G1 X1*77\nN6 M105*12\n").unwrap();
        assert_eq!(p.commands[0].text, "G1 X1");
        assert_eq!(p.commands[1].text, "M105");
    }

    #[test]
    fn too_long_and_bad_lines_are_errors_with_line_numbers() {
        let long = format!("G28\nM117 {}\n", "A".repeat(100));
        let err = parse(&long).unwrap_err().to_string();
        assert!(err.contains("line 2") && err.contains("95"), "{err}");
        let err = parse("G1 X1\nM117 a*b\n").unwrap_err().to_string();
        assert!(err.contains("line 2") && err.contains('*'), "{err}");
        let err = parse("G1 (open\n").unwrap_err().to_string();
        assert!(err.contains("line 1"), "{err}");
        let err = parse("M117 h\u{e9}llo\n").unwrap_err().to_string();
        assert!(err.contains("ASCII"), "{err}");
    }

    #[test]
    fn frame_refuses_lines_marlin_would_truncate() {
        let cmd = "M117 ".to_string() + &"x".repeat(80);
        assert!(frame(1, &cmd, 3).is_ok());
        assert!(matches!(
            frame(1_000_000_000, &cmd, 3),
            Err(GcodeError::TooLong { line: 3, .. })
        ));
    }

    #[test]
    fn layers_from_comments() {
        let p = parse(";LAYER:0\nG1 Z0.2\nG1 X1 E1\n;LAYER:1\nG1 Z0.4\nG1 X2 E2\n").unwrap();
        assert_eq!(p.layers.len(), 2);
        assert_eq!(p.layers[1].number, 1);
        assert_eq!(p.layers[1].first_command, 2);
        assert_eq!(p.layers[1].z, Some(0.4));
        assert_eq!(p.layer_of(3).map(|l| l.number), Some(1));
        assert_eq!(p.layer_of(0).map(|l| l.number), Some(0));
    }

    #[test]
    fn layers_from_z_ignore_z_hops() {
        let g =
            "G90\nM82\nG1 Z0.2\nG1 X1 E1\nG1 Z0.6\nG1 X5\nG1 Z0.2\nG1 X6 E2\nG1 Z0.4\nG1 X7 E3\n";
        let p = parse(g).unwrap();
        let zs: Vec<_> = p.layers.iter().map(|l| (l.z, l.first_command)).collect();
        assert_eq!(zs, [(Some(0.2), 2), (Some(0.4), 8)]);
        assert_eq!(p.layers[1].first_command, 8);
    }

    #[test]
    fn codes_and_words() {
        assert_eq!(code("g01 X1"), "G1");
        assert_eq!(code("M104 S200"), "M104");
        assert_eq!(code("T1"), "T1");
        assert_eq!(word("G1 X1.5 Z-2", 'Z'), Some(-2.0));
        assert_eq!(word("G1 X1.5", 'Z'), None);
    }
}
