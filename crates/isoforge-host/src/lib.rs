//! Printing over serial: the RepRap/Marlin host protocol as a state machine without I/O
//! ([`protocol`]), the job streamer over `serialport` ([`streamer`]), the job journal that
//! lets an interrupted print resume ([`journal`]), and a fake Marlin-like printer on a
//! pseudo-terminal for tests and demos ([`fake`]).
//!
//! The main call: read a file, open a port, stream.
//!
//! ```no_run
//! use isoforge_host::{gcode, protocol::Config, streamer};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let program = gcode::read_file("part.gcode".as_ref())?;
//! let mut port = streamer::open_port("/dev/ttyUSB0", 115_200)?;
//! let job = streamer::Job { program: &program, start: 0, prelude: vec![], journal: None };
//! let report = streamer::stream(&mut *port, job, Config::default(), &streamer::Control::new(), |_| {});
//! assert!(report.completed);
//! # Ok(()) }
//! ```

pub mod dialect;
pub mod fake;
pub mod gcode;
pub mod journal;
pub mod protocol;
pub mod sample;
pub mod state;
pub mod streamer;

#[cfg(test)]
mod sim;
