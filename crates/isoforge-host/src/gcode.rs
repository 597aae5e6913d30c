//! Reading a G-code file into the commands a printer executes, and framing them for the wire.
//!
//! Lines are read by `isoforge-gcode` (the tokenizer the slicer's checker and the fake printer
//! use): comments and blank lines never reach the printer; a line number and checksum the file
//! may carry are dropped (the host numbers lines itself); each command keeps the source line it
//! came from so errors, progress and the journal can point into the file. Layer starts come
//! from `;LAYER:n` comments when the slicer wrote them, else from the height of the first
//! extruding move at each new Z.
//!
//! The host owns line numbering: an `M110` in the file would reset the printer's count in the
//! middle of the job (a later line could then run twice or never), so it is left out, and the
//! [`Program`] says which lines were.

use std::path::Path;

use isoforge_gcode::{LayerFinder, Machine, parse_line};
use thiserror::Error;

pub use isoforge_gcode::Layer;

/// Marlin's `MAX_CMD_SIZE` is 96 bytes including the terminating NUL: anything longer is cut
/// silently, so a longer framed line must be refused before it is sent.
pub(crate) const MAX_FRAMED_LEN: usize = 95;

/// Longest piece of a line quoted back in an error, in characters.
const EXCERPT: usize = 48;

/// One command as the printer will execute it.
#[derive(Clone, Debug, PartialEq)]
pub struct Command {
    /// The command text, comments and surrounding spaces removed (e.g. `G1 X10 Y20 E0.5`).
    pub text: String,
    /// 1-based line number in the source file.
    pub source_line: usize,
}

/// A line of the file that is not sent, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct Dropped {
    /// 1-based source line.
    pub line: usize,
    /// The command.
    pub text: String,
    /// Why it is not sent.
    pub why: &'static str,
}

/// A G-code file read into commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Program {
    /// The commands in file order.
    pub commands: Vec<Command>,
    /// Layer starts, in file order.
    pub layers: Vec<Layer>,
    /// Commands of the file that are not sent (`M110`).
    pub dropped: Vec<Dropped>,
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
        /// What is wrong (the column is in it).
        reason: String,
    },
    /// A framed line exceeds Marlin's buffer and would be truncated by the firmware.
    #[error(
        "line {line}: the command {excerpt:?} is {len} bytes framed for the wire, over Marlin's {MAX_FRAMED_LEN}-byte limit (the firmware would cut it); shorten the command"
    )]
    TooLong {
        /// 1-based source line (0 when the command was not from a file).
        line: usize,
        /// The start of the command.
        excerpt: String,
        /// The framed length in bytes.
        len: usize,
    },
}

/// The first [`EXCERPT`] characters of `text`, with `...` when there is more.
pub(crate) fn excerpt(text: &str) -> String {
    let mut out: String = text.chars().take(EXCERPT).collect();
    if text.chars().count() > EXCERPT {
        out.push_str("...");
    }
    out
}

/// The XOR of every byte, as RepRap firmware computes it over `N<n> <command>`.
#[cfg(test)]
pub(crate) fn checksum(bytes: &[u8]) -> u8 {
    isoforge_gcode::checksum(bytes)
}

/// Frames a command as `N<line> <command>*<checksum>` followed by a newline.
///
/// `source_line` is only used to say where a too-long command came from.
pub fn frame(line: u64, command: &str, source_line: usize) -> Result<String, GcodeError> {
    // `N<digits> ` + command + `*<3 digits>`: refuse before building a huge string.
    let len = command.len() + line.to_string().len() + 2 + 4;
    if len > MAX_FRAMED_LEN + 2 {
        return Err(GcodeError::TooLong {
            line: source_line,
            excerpt: excerpt(command),
            len,
        });
    }
    let framed = isoforge_gcode::frame(line, command);
    if framed.len() > MAX_FRAMED_LEN {
        return Err(GcodeError::TooLong {
            line: source_line,
            excerpt: excerpt(command),
            len: framed.len(),
        });
    }
    Ok(framed + "\n")
}

/// Reads a G-code file.
pub fn read_file(path: &Path) -> Result<Program, GcodeError> {
    let bytes = isoforge_output::read_input(path).map_err(|source| GcodeError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    parse(&text)
}

/// Parses G-code text into commands and layer starts.
///
/// Every command is checked here so that no error can surface halfway through a print: it
/// must be ASCII text with well-formed words, and framed with the largest line number this
/// job can reach it must fit `MAX_FRAMED_LEN` (95 bytes).
pub fn parse(text: &str) -> Result<Program, GcodeError> {
    let mut program = Program::default();
    let mut layers = LayerFinder::default();
    let mut machine = Machine::default();
    for (n, raw) in isoforge_gcode::lines(text) {
        let line = parse_line(raw).map_err(|e| GcodeError::BadLine {
            line: n,
            reason: e.to_string(),
        })?;
        if let Some(comment) = line.comment {
            layers.comment(comment, program.commands.len());
        }
        if line.text.is_empty() {
            continue;
        }
        if let Some(cmd) = &line.command {
            if cmd.code.is('M', 110) {
                program.dropped.push(Dropped {
                    line: n,
                    text: excerpt(&line.text),
                    why: "the host numbers the lines itself; an M110 would reset the \
                          printer's count in the middle of the job",
                });
                continue;
            }
            let effect = machine.apply(cmd);
            layers.command(cmd, &effect, program.commands.len());
        }
        program.commands.push(Command {
            text: line.text.into_owned(),
            source_line: n,
        });
    }
    // Resumed jobs add a short prelude, and the host its own lines (probes, renumbering):
    // leave room for them in the line-number width.
    let worst_line = program.commands.len() as u64 * 2 + PRELUDE_ALLOWANCE;
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

/// The command's code (`G1`, `M104`, `T0`), upper-cased, without leading zeros; empty for
/// text that is not a G, M or T command.
pub(crate) fn code(cmd: &str) -> String {
    match isoforge_gcode::Command::parse(cmd) {
        Ok(Some(c)) => c.code.to_string(),
        _ => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_matches_reprap_examples() {
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
    fn m110_in_the_file_is_dropped_and_reported() {
        let p = parse("M110 N0\nG28\nM110 N100\nG1 X1\nN7 M110*90\n").unwrap();
        let texts: Vec<_> = p.commands.iter().map(|c| c.text.as_str()).collect();
        assert_eq!(texts, ["G28", "G1 X1"]);
        let lines: Vec<_> = p.dropped.iter().map(|d| d.line).collect();
        assert_eq!(lines, [1, 3, 5]);
        assert_eq!(p.commands[1].source_line, 4);
    }

    #[test]
    fn cr_only_and_crlf_line_endings() {
        for text in ["G28\rG1 X1\rM84\r", "G28\r\nG1 X1\r\nM84\r\n"] {
            let p = parse(text).unwrap();
            let texts: Vec<_> = p.commands.iter().map(|c| c.text.as_str()).collect();
            assert_eq!(texts, ["G28", "G1 X1", "M84"], "{text:?}");
            assert_eq!(p.commands[2].source_line, 3);
        }
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
        let err = parse("G1 Xabc\n").unwrap_err().to_string();
        assert!(err.contains("line 1") && err.contains("column 4"), "{err}");
    }

    #[test]
    fn a_huge_line_is_not_quoted_whole() {
        let huge = format!("M117 {}\n", "x".repeat(10_000_000));
        let err = parse(&huge).unwrap_err().to_string();
        assert!(err.len() < 300, "{} bytes", err.len());
        let huge = format!("G1 X{}\n", "y".repeat(10_000_000));
        let err = parse(&huge).unwrap_err().to_string();
        assert!(err.len() < 300, "{} bytes", err.len());
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
    }

    #[test]
    fn codes() {
        assert_eq!(code("g01 X1"), "G1");
        assert_eq!(code("M104 S200"), "M104");
        assert_eq!(code("T1"), "T1");
        assert_eq!(code("X10"), "");
    }
}

#[cfg(test)]
mod proptests {
    use proptest::prelude::*;

    use super::*;

    /// A small whole job (start code, layers, end code): the seed mutations start from.
    fn sample() -> String {
        include_str!("../../../fixtures/gcode/square-tube.gcode").to_string()
    }

    /// What every program `parse` accepts must hold: commands with text and a source line,
    /// each of which frames within the limit, layers in order pointing inside the program.
    fn assert_valid(p: &Program) {
        let worst_line = p.commands.len() as u64 * 2 + PRELUDE_ALLOWANCE;
        for c in &p.commands {
            assert!(!c.text.is_empty());
            assert!(c.source_line >= 1);
            assert!(frame(worst_line, &c.text, c.source_line).is_ok());
        }
        for pair in p.layers.windows(2) {
            assert!(pair[0].first_command <= pair[1].first_command);
        }
        for l in &p.layers {
            assert!(l.first_command <= p.commands.len());
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        #[test]
        fn random_bytes_give_a_program_or_a_located_error(
            bytes in proptest::collection::vec(any::<u8>(), 0..600),
        ) {
            match parse(&String::from_utf8_lossy(&bytes)) {
                Ok(p) => assert_valid(&p),
                Err(e) => prop_assert!(e.to_string().contains("line"), "{e}"),
            }
        }

        #[test]
        fn mutated_slicer_files_give_a_program_or_a_located_error(
            edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
            cut in any::<prop::sample::Index>(),
        ) {
            let mut bytes = sample().into_bytes();
            for (at, byte) in edits {
                let i = at.index(bytes.len());
                bytes[i] = byte;
            }
            bytes.truncate(cut.index(bytes.len() + 1));
            match parse(&String::from_utf8_lossy(&bytes)) {
                Ok(p) => assert_valid(&p),
                Err(e) => prop_assert!(e.to_string().contains("line"), "{e}"),
            }
        }
    }
}
