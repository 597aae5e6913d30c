//! G-code, read once for the whole project: a tokenizer ([`parse_line`]: line number,
//! command, checksum, comment) and the machine state commands build up ([`Machine`]:
//! positioning and extrusion modes, units, position, feed rate, heater targets, fan, tool),
//! plus where layers start ([`LayerFinder`]).
//!
//! The slicer's G-code checker, the host (which tracks the printer's state to resume a job)
//! and the fake printer all read G-code through this crate, so they cannot disagree about
//! what a file does.
//!
//! ```
//! use isoforge_gcode::{Effect, Machine, parse_line};
//!
//! let mut machine = Machine::default();
//! for raw in ["G28", "M83", "G1 Z0.2 F600", "N7 G01 X10 E0.5*40 ; first line"] {
//!     let line = parse_line(raw)?;
//!     assert!(line.checksum.is_none_or(|c| c == line.computed));
//!     if let Some(cmd) = &line.command {
//!         if let Effect::Move(mv) = machine.apply(cmd) {
//!             println!("moved to {:?}, extruded {} mm", mv.to, mv.e);
//!         }
//!     }
//! }
//! assert_eq!(machine.position, [Some(10.0), Some(0.0), Some(0.2)]);
//! assert_eq!(machine.e, 0.5);
//! # Ok::<(), isoforge_gcode::LineError>(())
//! ```

mod command;
mod layers;
mod line;
mod machine;
#[cfg(test)]
mod proptests;

pub use command::{Code, Command, CommandError, Param};
pub use layers::{Layer, LayerFinder};
pub use line::{Framing, Line, LineError, checksum, frame, framing, lines, parse_line};
pub use machine::{Effect, Heater, MAX_TOOLS, Machine, Move, MoveKind, Units};
