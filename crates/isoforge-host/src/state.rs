//! The printer state a job has built up, as the journal records it: heater targets,
//! positioning modes, units, position, fan.
//!
//! The state itself is `isoforge-gcode`'s machine model (the same one the slicer's checker
//! and the fake printer follow), tracked command by command as lines are acknowledged, so
//! the journal can say what a resumed job must restore, and recomputed from the file for
//! `--from-layer`.

use isoforge_gcode::{Command, Machine, Units};

/// What a resumed job must restore. Field names are the journal's keys.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MachineState {
    /// Hotend targets by tool, °C.
    pub hotends: Vec<f64>,
    /// Bed target, °C.
    pub bed: f64,
    /// The active tool.
    pub tool: usize,
    /// G90 (true) or G91.
    pub absolute: bool,
    /// M82 (true) or M83.
    pub absolute_e: bool,
    /// Last commanded position (unknown until set).
    pub x: Option<f64>,
    /// Last commanded Y.
    pub y: Option<f64>,
    /// Last commanded Z.
    pub z: Option<f64>,
    /// The extruder position as the firmware counts it.
    pub e: f64,
    /// Last feed rate, mm/min.
    pub feedrate: Option<f64>,
    /// Part-cooling fan, 0-255.
    pub fan: f64,
    /// G20 (true) or G21: the units of the file's coordinates (journals written before this
    /// key existed are millimetres).
    #[serde(default)]
    pub inches: bool,
}

impl Default for MachineState {
    fn default() -> Self {
        MachineState {
            hotends: vec![0.0],
            bed: 0.0,
            tool: 0,
            absolute: true,
            absolute_e: true,
            x: None,
            y: None,
            z: None,
            e: 0.0,
            feedrate: None,
            fan: 0.0,
            inches: false,
        }
    }
}

impl MachineState {
    /// The state a machine model is in.
    pub(crate) fn of(m: &Machine) -> MachineState {
        MachineState {
            hotends: m.hotends.clone(),
            bed: m.bed,
            tool: m.tool,
            absolute: m.absolute,
            absolute_e: m.absolute_e,
            x: m.position[0],
            y: m.position[1],
            z: m.position[2],
            e: m.e,
            feedrate: m.feedrate,
            fan: m.fan,
            inches: m.units == Units::Inches,
        }
    }

    /// A machine model in this state.
    pub(crate) fn machine(&self) -> Machine {
        Machine {
            units: if self.inches {
                Units::Inches
            } else {
                Units::Millimeters
            },
            absolute: self.absolute,
            absolute_e: self.absolute_e,
            position: [self.x, self.y, self.z],
            e: self.e,
            feedrate: self.feedrate,
            hotends: self.hotends.clone(),
            bed: self.bed,
            fan: self.fan,
            tool: self.tool,
        }
    }

    /// The state after `commands` ran from power-on.
    pub(crate) fn replay<'a>(commands: impl IntoIterator<Item = &'a str>) -> MachineState {
        let mut m = Machine::default();
        for c in commands {
            apply(&mut m, c);
        }
        MachineState::of(&m)
    }
}

/// Updates `m` for one executed command (text that is not a command changes nothing).
pub(crate) fn apply(m: &mut Machine, cmd: &str) {
    if let Ok(Some(c)) = Command::parse(cmd) {
        m.apply(&c);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracks_modes_positions_and_targets() {
        let s = MachineState::replay([
            "M140 S60",
            "M104 S200",
            "G28",
            "G90",
            "M83",
            "G1 Z0.3 F600",
            "G1 X10 Y20 E1.5 F1200",
            "G1 X12 E0.5",
            "M106 S128",
            "G91",
            "G1 Z1",
        ]);
        assert_eq!(s.bed, 60.0);
        assert_eq!(s.hotends, [200.0]);
        assert_eq!((s.x, s.y, s.z), (Some(12.0), Some(20.0), Some(1.3)));
        assert_eq!(s.e, 2.0);
        assert!(!s.absolute && !s.absolute_e);
        assert_eq!(s.fan, 128.0);
        assert_eq!(s.feedrate, Some(1200.0));
    }

    #[test]
    fn g92_and_absolute_extrusion() {
        let s = MachineState::replay([
            "M82",
            "G1 X1 E5",
            "G92 E0",
            "G1 X2 E0.7",
            "T1",
            "M104 T1 S210",
        ]);
        assert!(s.absolute_e);
        assert_eq!(s.e, 0.7);
        assert_eq!(s.tool, 1);
        assert_eq!(s.hotends, [0.0, 210.0]);
    }
}
