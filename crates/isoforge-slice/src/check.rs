//! A G-code checker: parses what the slicer (or anyone) wrote and measures what a printer
//! would do with it, so tests judge the output and not the slicer's intentions.
//!
//! It follows moves, G92, G90/G91, M82/M83, G20/G21 and G28 (through `isoforge-gcode`),
//! collects every move, every extruding move with its layer (from `;LAYER:n`, or PrusaSlicer's
//! `;LAYER_CHANGE`) and feature (`;TYPE:`), `G4` waits,
//! the temperatures set before the first extrusion, and the travel envelope.

use isoforge_gcode::{Effect, Heater, Machine};

mod bridges;
pub mod features;

/// An extruding move.
#[derive(Clone, Debug, PartialEq)]
pub struct Extrude {
    /// Start, mm.
    pub from: [f64; 3],
    /// End, mm.
    pub to: [f64; 3],
    /// Filament pushed, mm.
    pub e: f64,
    /// The layer it belongs to (`;LAYER:n`), if any was given.
    pub layer: Option<usize>,
    /// The `;TYPE:` in force.
    pub feature: String,
    /// Line number (1-based).
    pub line: usize,
}

/// Any move (G0/G1), extruding or not.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Start, mm.
    pub from: [f64; 3],
    /// End, mm.
    pub to: [f64; 3],
    /// Filament pushed (negative: pulled back), mm.
    pub e: f64,
    /// Feed rate in force, mm/s (0 before any F).
    pub feed: f64,
    /// The layer it belongs to.
    pub layer: Option<usize>,
    /// Line number (1-based).
    pub line: usize,
}

/// What a G-code file does.
#[derive(Clone, Debug, Default)]
pub struct GcodeReport {
    /// Extruding moves (retractions and primes without motion are not here).
    pub extrusions: Vec<Extrude>,
    /// Every move, in file order (the judges in [`features`] read these).
    pub moves: Vec<Motion>,
    /// Waits (`G4`), s, with their layer.
    pub dwells: Vec<(Option<usize>, f64)>,
    /// `;LAYER:n` markers with the `;Z:` that followed each, in file order.
    pub layers: Vec<(usize, Option<f64>)>,
    /// The Z of the first extrusion of each layer index.
    pub layer_print_z: Vec<(usize, f64)>,
    /// Smallest x, y, z any move reached (after homing).
    pub min: [f64; 3],
    /// Largest x, y, z any move reached.
    pub max: [f64; 3],
    /// Nozzle temperature set (M104/M109) before the first extrusion.
    pub nozzle_before_first_extrusion: Option<f64>,
    /// Bed temperature set (M140/M190) before the first extrusion.
    pub bed_before_first_extrusion: Option<f64>,
    /// True when a wait for the nozzle (M109) came before the first extrusion.
    pub waited_for_nozzle: bool,
    /// Net filament pushed, mm, over all extruding moves.
    pub filament_mm: f64,
}

/// A line the checker could not read.
#[derive(Debug, thiserror::Error)]
#[error("G-code line {line}: {message}")]
pub struct CheckError {
    /// Line number (1-based).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// Parses G-code text.
///
/// Lines are read by `isoforge-gcode`, the tokenizer and machine state the host and the fake
/// printer use too, so the checker follows the modes (Marlin's rule that `G90` also makes E
/// absolute), units and `G01`-style codes exactly as they do.
pub fn parse(text: &str) -> Result<GcodeReport, CheckError> {
    let mut r = GcodeReport {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
        ..Default::default()
    };
    let mut machine = Machine::default();
    let mut homed_or_moved = false;
    let mut layer: Option<usize> = None;
    let mut feature = String::new();
    let (mut nozzle, mut bed, mut waited) = (None, None, false);
    for (n, raw) in isoforge_gcode::lines(text) {
        let line = isoforge_gcode::parse_line(raw).map_err(|e| CheckError {
            line: n,
            message: e.to_string(),
        })?;
        let Some(cmd) = &line.command else {
            if line.text.is_empty()
                && let Some(m) = line.comment
            {
                if let Some(v) = m.strip_prefix("LAYER:") {
                    let k = v.trim().parse().map_err(|_| CheckError {
                        line: n,
                        message: format!("bad layer marker {m:?}"),
                    })?;
                    layer = Some(k);
                    r.layers.push((k, None));
                } else if m == "LAYER_CHANGE" {
                    // PrusaSlicer's and Slic3r's marker: layers counted from 0.
                    let k = r.layers.len();
                    layer = Some(k);
                    r.layers.push((k, None));
                } else if let Some(v) = m.strip_prefix("Z:") {
                    if let Some(last) = r.layers.last_mut() {
                        last.1 = v.trim().parse().ok();
                    }
                } else if let Some(v) = m.strip_prefix("TYPE:") {
                    feature = v.trim().to_string();
                }
            }
            continue;
        };
        match machine.apply(cmd) {
            Effect::Move(mv) => {
                let (pos, to, de) = (mv.from_or_zero(), mv.to_or_zero(), mv.e);
                let moved = to != pos;
                if moved {
                    homed_or_moved = true;
                }
                if moved || de != 0.0 {
                    r.moves.push(Motion {
                        from: pos,
                        to,
                        e: de,
                        feed: mv.feedrate.unwrap_or(0.0) / 60.0,
                        layer,
                        line: n,
                    });
                }
                if de > 0.0 && (to[0] != pos[0] || to[1] != pos[1]) {
                    r.filament_mm += de;
                    if r.extrusions.is_empty() {
                        r.nozzle_before_first_extrusion = nozzle;
                        r.bed_before_first_extrusion = bed;
                        r.waited_for_nozzle = waited;
                    }
                    if let Some(l) = layer
                        && r.layer_print_z.last().map(|x| x.0) != Some(l)
                    {
                        r.layer_print_z.push((l, to[2]));
                    }
                    r.extrusions.push(Extrude {
                        from: pos,
                        to,
                        e: de,
                        layer,
                        feature: feature.clone(),
                        line: n,
                    });
                }
                if homed_or_moved {
                    for (k, v) in to.iter().enumerate() {
                        r.min[k] = r.min[k].min(*v);
                        r.max[k] = r.max[k].max(*v);
                    }
                }
            }
            Effect::Home(_) => homed_or_moved = true,
            Effect::Other if cmd.code.is('G', 4) => {
                let secs = match (cmd.get('P'), cmd.get('S')) {
                    (Some(ms), _) => ms / 1000.0,
                    (None, Some(sec)) => sec,
                    _ => 0.0,
                };
                r.dwells.push((layer, secs));
            }
            Effect::Heat {
                heater: Heater::Hotend(_),
                target,
                wait,
            } => {
                if let Some(v) = target {
                    nozzle = Some(v);
                }
                if wait {
                    waited = true;
                }
            }
            Effect::Heat {
                heater: Heater::Bed,
                target: Some(v),
                ..
            } => bed = Some(v),
            _ => {}
        }
    }
    Ok(r)
}

impl GcodeReport {
    /// Extruded volume, mm³, for filament of diameter `d`, counting only moves whose
    /// feature passes `keep`.
    pub fn volume(&self, d: f64, keep: impl Fn(&str) -> bool) -> f64 {
        let a = std::f64::consts::PI * (d / 2.0).powi(2);
        self.extrusions
            .iter()
            .filter(|x| keep(&x.feature))
            .map(|x| x.e * a)
            .sum()
    }

    /// Extrusions whose samples (every `step` mm along the move) are farther than `tol`
    /// outside the part, by `outside(x, y, layer)`: the distance outside the part's
    /// section for that layer (≤ 0 inside). Returns the offending line numbers.
    pub fn outside_part(
        &self,
        step: f64,
        tol: f64,
        keep: impl Fn(&str) -> bool,
        outside: impl Fn(f64, f64, usize) -> f64,
    ) -> Vec<usize> {
        let mut bad = Vec::new();
        for x in self.extrusions.iter().filter(|x| keep(&x.feature)) {
            let Some(layer) = x.layer else {
                bad.push(x.line);
                continue;
            };
            let len = (x.to[0] - x.from[0]).hypot(x.to[1] - x.from[1]);
            let n = (len / step).ceil().max(1.0) as usize;
            let off = (0..=n).any(|k| {
                let t = k as f64 / n as f64;
                let p = [
                    x.from[0] + t * (x.to[0] - x.from[0]),
                    x.from[1] + t * (x.to[1] - x.from[1]),
                ];
                outside(p[0], p[1], layer) > tol
            });
            if off {
                bad.push(x.line);
            }
        }
        bad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prusaslicer_layer_changes_count_layers() {
        let g = "G90\nM82\nG92 E0\n;LAYER_CHANGE\n;Z:0.2\nG1 X1 Y0 E1\n;LAYER_CHANGE\n;Z:0.4\nG1 X2 E2\n";
        let r = parse(g).unwrap();
        assert_eq!(r.layers, [(0, Some(0.2)), (1, Some(0.4))]);
        assert_eq!(r.extrusions[1].layer, Some(1));
    }

    #[test]
    fn follows_absolute_and_relative_extrusion() {
        let g = "M104 S200\nM109 S200\nG28\nG90\nM82\nG92 E0\n;LAYER:0\n;Z:0.2\nG1 Z0.2\n;TYPE:FILL\nG1 X10 Y0 E1.0\nG1 E-1\nG1 E1.0\nG1 X20 E2.5\nM83\nG1 X30 E0.5\n";
        let r = parse(g).unwrap();
        assert_eq!(r.extrusions.len(), 3);
        assert!((r.filament_mm - 3.0).abs() < 1e-12);
        assert_eq!(r.nozzle_before_first_extrusion, Some(200.0));
        assert!(r.waited_for_nozzle);
        assert_eq!(r.layers, vec![(0, Some(0.2))]);
        assert_eq!(r.max[0], 30.0);
        assert_eq!(r.extrusions[0].feature, "FILL");
    }

    #[test]
    fn reads_modes_and_codes_as_the_host_does() {
        // `G90` after `M83` makes E absolute again (Marlin), and `G01` is `G1`.
        let g = "G28\nM83\nG1 X1 E1\nG90\nG01 X2 E1.5\n";
        let r = parse(g).unwrap();
        assert_eq!(r.extrusions.len(), 2);
        assert!((r.extrusions[1].e - 0.5).abs() < 1e-12);
        assert!((r.filament_mm - 1.5).abs() < 1e-12);
    }

    #[test]
    fn bad_numbers_name_the_line() {
        let err = parse("G1 X1\nG1 Xabc\n").unwrap_err();
        assert_eq!(err.line, 2);
    }
}
