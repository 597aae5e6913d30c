//! The state a printer builds up command by command: positioning modes, units, position,
//! extruder, feed rate, heater targets, fan and tool, and what each command did.
//!
//! The modes follow Marlin (1.1 to 2.1), the firmware most files are written for:
//! - `G90`/`G91` set every axis, the extruder included; `M82`/`M83` then set the extruder
//!   alone. So `M83` then `G90` leaves E absolute, and `G91` then `M82` leaves XYZ relative
//!   with E absolute.
//! - `G20`/`G21` switch inches/millimetres for positions, extrusion and feed rates (never
//!   for temperatures); the state keeps millimetres.
//! - `G92` sets the axes it names; with none named it changes nothing.
//! - `G28` homes the axes it names, or all three, to 0.
//! - A relative move on an axis whose position is still unknown starts from 0.
//! - `M104`/`M109` set a hotend (its `T`, else the active tool), `M140`/`M190` the bed,
//!   from `S` (or `R`, the wait-either-way form); negative targets are 0 (off).
//! - `M106 [P0] S` sets the part fan (255 without `S`), `M107` turns it off.

use crate::command::Command;

/// Tools a machine can have (`T0` to `T7`); a higher `T` is ignored.
pub const MAX_TOOLS: usize = 8;

/// Millimetres per inch.
const INCH: f64 = 25.4;

/// Length units of positions and feed rates in the commands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    /// `G21`, the default.
    Millimeters,
    /// `G20`.
    Inches,
}

impl Units {
    fn scale(self) -> f64 {
        match self {
            Units::Millimeters => 1.0,
            Units::Inches => INCH,
        }
    }
}

/// The printer state. Positions, extruder and feed are millimetres (per minute).
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    /// `G20`/`G21`.
    pub units: Units,
    /// `G90` (true) or `G91` for X, Y and Z.
    pub absolute: bool,
    /// Absolute (true) or relative extrusion.
    pub absolute_e: bool,
    /// X, Y, Z, each unknown until homed, set or moved to.
    pub position: [Option<f64>; 3],
    /// The extruder position as the firmware counts it.
    pub e: f64,
    /// The last feed rate, mm/min.
    pub feedrate: Option<f64>,
    /// Hotend targets by tool, °C (at least one).
    pub hotends: Vec<f64>,
    /// Bed target, °C.
    pub bed: f64,
    /// Part-cooling fan, 0 to 255.
    pub fan: f64,
    /// The active tool.
    pub tool: usize,
}

impl Default for Machine {
    fn default() -> Self {
        Machine {
            units: Units::Millimeters,
            absolute: true,
            absolute_e: true,
            position: [None; 3],
            e: 0.0,
            feedrate: None,
            hotends: vec![0.0],
            bed: 0.0,
            fan: 0.0,
            tool: 0,
        }
    }
}

/// What kind of motion a move command is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MoveKind {
    /// `G0`.
    Rapid,
    /// `G1`.
    Linear,
    /// `G2`/`G3` (only the end point is followed).
    Arc,
}

/// A move, in millimetres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// `G0`, `G1` or an arc.
    pub kind: MoveKind,
    /// Where it starts (unknown axes are `None`).
    pub from: [Option<f64>; 3],
    /// Where it ends.
    pub to: [Option<f64>; 3],
    /// Filament pushed (negative: retracted), mm.
    pub e: f64,
    /// The feed rate in force for the move, mm/min.
    pub feedrate: Option<f64>,
}

impl Move {
    /// The start, with unknown axes at 0.
    pub fn from_or_zero(&self) -> [f64; 3] {
        self.from.map(|v| v.unwrap_or(0.0))
    }

    /// The end, with unknown axes at 0.
    pub fn to_or_zero(&self) -> [f64; 3] {
        self.to.map(|v| v.unwrap_or(0.0))
    }
}

/// A heater a command sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heater {
    /// A hotend by tool number.
    Hotend(usize),
    /// The bed.
    Bed,
}

/// What one command did to the machine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Effect {
    /// A move (`G0`-`G3`).
    Move(Move),
    /// `G28`: these axes (X, Y, Z) are now at 0.
    Home([bool; 3]),
    /// `G92`: positions declared.
    SetPosition,
    /// A heater target set, and whether the command waits for it (`M109`, `M190`).
    Heat {
        /// Which heater.
        heater: Heater,
        /// The new target, if the command gave one.
        target: Option<f64>,
        /// True when the firmware waits for the temperature.
        wait: bool,
    },
    /// The part fan's new value.
    Fan(f64),
    /// The active tool changed.
    Tool(usize),
    /// A mode changed (`G90`, `G91`, `M82`, `M83`, `G20`, `G21`).
    Mode,
    /// Nothing the machine state follows.
    Other,
}

impl Machine {
    /// Updates the state for one executed command and says what it did.
    pub fn apply(&mut self, cmd: &Command) -> Effect {
        let code = cmd.code;
        match (code.letter, code.number, code.sub) {
            ('G', n @ 0..=3, None) => self.motion(cmd, n),
            ('G', 20, None) => {
                self.units = Units::Inches;
                Effect::Mode
            }
            ('G', 21, None) => {
                self.units = Units::Millimeters;
                Effect::Mode
            }
            ('G', 28, None) => self.home(cmd),
            ('G', 90, None) => {
                (self.absolute, self.absolute_e) = (true, true);
                Effect::Mode
            }
            ('G', 91, None) => {
                (self.absolute, self.absolute_e) = (false, false);
                Effect::Mode
            }
            ('G', 92, None) => self.set_position(cmd),
            ('M', 82, None) => {
                self.absolute_e = true;
                Effect::Mode
            }
            ('M', 83, None) => {
                self.absolute_e = false;
                Effect::Mode
            }
            ('M', n @ (104 | 109), None) => self.hotend(cmd, n == 109),
            ('M', n @ (140 | 190), None) => {
                let target = heat_target(cmd, n == 190);
                if let Some(t) = target {
                    self.bed = t;
                }
                Effect::Heat {
                    heater: Heater::Bed,
                    target,
                    wait: n == 190,
                }
            }
            ('M', 106, None) => self.fan(cmd, Some(cmd.get('S').unwrap_or(255.0))),
            ('M', 107, None) => self.fan(cmd, Some(0.0)),
            ('T', n, None) => {
                let n = n as usize;
                if n >= MAX_TOOLS {
                    return Effect::Other;
                }
                self.tool = n;
                self.ensure_hotend(n);
                Effect::Tool(n)
            }
            _ => Effect::Other,
        }
    }

    fn motion(&mut self, cmd: &Command, n: u32) -> Effect {
        let scale = self.units.scale();
        let from = self.position;
        for (axis, letter) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(v) = cmd.get(letter) {
                let v = v * scale;
                self.position[axis] = Some(if self.absolute {
                    v
                } else {
                    self.position[axis].unwrap_or(0.0) + v
                });
            }
        }
        let mut e = 0.0;
        if let Some(v) = cmd.get('E') {
            let v = v * scale;
            e = if self.absolute_e { v - self.e } else { v };
            self.e = if self.absolute_e { v } else { self.e + v };
        }
        if let Some(f) = cmd.get('F') {
            self.feedrate = Some(f * scale);
        }
        Effect::Move(Move {
            kind: match n {
                0 => MoveKind::Rapid,
                1 => MoveKind::Linear,
                _ => MoveKind::Arc,
            },
            from,
            to: self.position,
            e,
            feedrate: self.feedrate,
        })
    }

    fn home(&mut self, cmd: &Command) -> Effect {
        let named = ['X', 'Y', 'Z'].map(|l| cmd.has(l));
        let all = !named.iter().any(|&n| n);
        let mut homed = [false; 3];
        for axis in 0..3 {
            if all || named[axis] {
                self.position[axis] = Some(0.0);
                homed[axis] = true;
            }
        }
        Effect::Home(homed)
    }

    fn set_position(&mut self, cmd: &Command) -> Effect {
        let scale = self.units.scale();
        for (axis, letter) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(v) = cmd.get(letter) {
                self.position[axis] = Some(v * scale);
            }
        }
        if let Some(v) = cmd.get('E') {
            self.e = v * scale;
        }
        Effect::SetPosition
    }

    fn hotend(&mut self, cmd: &Command, wait: bool) -> Effect {
        let tool = match cmd.get('T') {
            Some(t) if t >= 0.0 && (t as usize) < MAX_TOOLS => t as usize,
            Some(_) => return Effect::Other,
            None => self.tool,
        };
        let target = heat_target(cmd, wait);
        if let Some(t) = target {
            self.ensure_hotend(tool);
            self.hotends[tool] = t;
        }
        Effect::Heat {
            heater: Heater::Hotend(tool),
            target,
            wait,
        }
    }

    fn fan(&mut self, cmd: &Command, value: Option<f64>) -> Effect {
        // Only the part fan (index 0) is followed.
        if cmd.get('P').is_some_and(|p| p != 0.0) {
            return Effect::Other;
        }
        let v = value.unwrap_or(0.0).clamp(0.0, 255.0);
        self.fan = v;
        Effect::Fan(v)
    }

    fn ensure_hotend(&mut self, tool: usize) {
        if self.hotends.len() <= tool {
            self.hotends.resize(tool + 1, 0.0);
        }
    }
}

/// `S`, or for the waiting forms also `R`; negative means off.
fn heat_target(cmd: &Command, wait: bool) -> Option<f64> {
    cmd.get('S')
        .or_else(|| wait.then(|| cmd.get('R')).flatten())
        .map(|t| t.max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(lines: &[&str]) -> Machine {
        let mut m = Machine::default();
        for l in lines {
            if let Some(c) = Command::parse(l).unwrap() {
                m.apply(&c);
            }
        }
        m
    }

    #[test]
    fn g90_after_m83_makes_e_absolute_as_marlin_does() {
        let m = run(&["M83", "G90"]);
        assert!(m.absolute_e);
        let m = run(&["G90", "M83"]);
        assert!(!m.absolute_e);
        let m = run(&["G91", "M82"]);
        assert!(!m.absolute && m.absolute_e);
    }

    #[test]
    fn relative_moves_and_extrusion() {
        let m = run(&["G28", "G91", "G1 X1 Y2 Z0.2 E1", "G1 X1 E0.5", "G01 Z0.2"]);
        assert_eq!(m.position, [Some(2.0), Some(2.0), Some(0.4)]);
        assert_eq!(m.e, 1.5);
    }

    #[test]
    fn absolute_extrusion_reports_the_delta() {
        let mut m = run(&["G92 E5"]);
        let c = Command::parse("G1 X1 E7.5").unwrap().unwrap();
        match m.apply(&c) {
            Effect::Move(mv) => {
                assert_eq!(mv.e, 2.5);
                assert_eq!(mv.from[0], None);
                assert_eq!(mv.to[0], Some(1.0));
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn inches_scale_positions_and_feed_not_temperatures() {
        let m = run(&["G20", "G1 X1 F10", "M104 S200"]);
        assert_eq!(m.position[0], Some(25.4));
        assert_eq!(m.feedrate, Some(254.0));
        assert_eq!(m.hotends, [200.0]);
        let m = run(&["G20", "G92 X1", "G21", "G91", "G1 X1"]);
        assert_eq!(m.position[0], Some(26.4));
    }

    #[test]
    fn g92_and_g28_set_what_they_name() {
        let m = run(&["G92"]);
        assert_eq!(m.position, [None; 3]);
        let m = run(&["G28 X", "G92 Y5 E2"]);
        assert_eq!(m.position, [Some(0.0), Some(5.0), None]);
        assert_eq!(m.e, 2.0);
        let m = run(&["G1 X5 Y5 Z5", "G28"]);
        assert_eq!(m.position, [Some(0.0); 3]);
    }

    #[test]
    fn heaters_fan_and_tools() {
        let m = run(&[
            "M140 S60",
            "M104 S200",
            "T1",
            "M104 S210",
            "M109 T0 R190",
            "M106",
            "M106 P1 S10",
        ]);
        assert_eq!(m.bed, 60.0);
        assert_eq!(m.hotends, [190.0, 210.0]);
        assert_eq!(m.tool, 1);
        assert_eq!(m.fan, 255.0);
        let m = run(&["M106 S128", "M107", "T9", "M104 S-5"]);
        assert_eq!(m.fan, 0.0);
        assert_eq!(m.tool, 0);
        assert_eq!(m.hotends, [0.0]);
    }
}
