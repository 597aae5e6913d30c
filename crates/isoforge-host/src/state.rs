//! The printer state a job has built up: heater targets, positioning modes, position, fan.
//!
//! Tracked command by command as lines are acknowledged, so the journal can say what a
//! resumed job must restore, and recomputed from the file for `--from-layer`.

use crate::gcode::{code, word};

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
        }
    }
}

impl MachineState {
    /// The state after `commands` ran from power-on.
    pub(crate) fn replay<'a>(commands: impl IntoIterator<Item = &'a str>) -> MachineState {
        let mut s = MachineState::default();
        for c in commands {
            s.apply(c);
        }
        s
    }

    /// Updates the state for one executed command.
    pub(crate) fn apply(&mut self, cmd: &str) {
        let c = code(cmd);
        match c.as_str() {
            "G0" | "G1" | "G2" | "G3" => {
                let abs = self.absolute;
                for (letter, axis) in [('X', &mut self.x), ('Y', &mut self.y), ('Z', &mut self.z)] {
                    if let Some(v) = word(cmd, letter) {
                        *axis = Some(if abs { v } else { axis.unwrap_or(0.0) + v });
                    }
                }
                if let Some(e) = word(cmd, 'E') {
                    self.e = if self.absolute_e { e } else { self.e + e };
                }
                if let Some(f) = word(cmd, 'F') {
                    self.feedrate = Some(f);
                }
            }
            // Marlin's G90/G91 set every axis, the extruder included; M82/M83 then
            // override the extruder alone.
            "G90" => (self.absolute, self.absolute_e) = (true, true),
            "G91" => (self.absolute, self.absolute_e) = (false, false),
            "M82" => self.absolute_e = true,
            "M83" => self.absolute_e = false,
            "G92" => {
                let mut any = false;
                for (letter, axis) in [('X', &mut self.x), ('Y', &mut self.y), ('Z', &mut self.z)] {
                    if let Some(v) = word(cmd, letter) {
                        *axis = Some(v);
                        any = true;
                    }
                }
                if let Some(e) = word(cmd, 'E') {
                    self.e = e;
                    any = true;
                }
                if !any {
                    (self.x, self.y, self.z, self.e) = (Some(0.0), Some(0.0), Some(0.0), 0.0);
                }
            }
            "G28" => {
                let named: Vec<char> = ['X', 'Y', 'Z']
                    .into_iter()
                    .filter(|l| {
                        cmd.split_ascii_whitespace()
                            .skip(1)
                            .any(|w| w.starts_with(*l))
                    })
                    .collect();
                let all = named.is_empty();
                if all || named.contains(&'X') {
                    self.x = Some(0.0);
                }
                if all || named.contains(&'Y') {
                    self.y = Some(0.0);
                }
                if all || named.contains(&'Z') {
                    self.z = Some(0.0);
                }
            }
            "M104" | "M109" => {
                let tool = word(cmd, 'T')
                    .map_or(self.tool, |t| t.max(0.0) as usize)
                    .min(7);
                if let Some(s) = word(cmd, 'S').or_else(|| word(cmd, 'R')) {
                    if self.hotends.len() <= tool {
                        self.hotends.resize(tool + 1, 0.0);
                    }
                    self.hotends[tool] = s;
                }
            }
            "M140" | "M190" => {
                if let Some(s) = word(cmd, 'S').or_else(|| word(cmd, 'R')) {
                    self.bed = s;
                }
            }
            "M106" => self.fan = word(cmd, 'S').unwrap_or(255.0),
            "M107" => self.fan = 0.0,
            t if t.starts_with('T') => {
                if let Ok(n) = t[1..].parse::<usize>() {
                    self.tool = n.min(7);
                    if self.hotends.len() <= self.tool {
                        self.hotends.resize(self.tool + 1, 0.0);
                    }
                }
            }
            _ => {}
        }
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
