//! Marlin-flavour G-code from ordered layer paths.
//!
//! Extrusion is computed from volume: a line `w` wide, `h` high and `L` long needs
//! E = w·h·L / (π·(d/2)²) mm of filament of diameter d. E is absolute (`M82`) and reset with
//! `G92 E0` at each layer. Each layer opens with `;LAYER:n`, `;Z:z` and an `M73` progress
//! line; the header gives the filament used (mm, g) and an estimated time.

use std::fmt::Write as _;

use crate::geom::{Contour, Point, dist, segments_cross};
use crate::paths::{Extrusion, Role};
use crate::profile::{FdmSettings, fill_template};

/// One layer, ready to emit.
#[derive(Clone, Debug, Default)]
pub struct LayerPlan {
    /// Top of the layer above the bed, mm.
    pub top: f64,
    /// Thickness, mm.
    pub height: f64,
    /// Extrusions in print order.
    pub paths: Vec<Extrusion>,
    /// The layer's outline contours: a travel across one retracts (it would string over
    /// a visible surface).
    pub barriers: Vec<Contour>,
}

/// Totals of a G-code file.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct GcodeStats {
    /// Layers.
    pub layers: usize,
    /// Filament pushed, mm.
    pub filament_mm: f64,
    /// Filament mass, g.
    pub filament_g: f64,
    /// Estimated print time, s (moves at their feed rate; heating and acceleration not
    /// counted).
    pub seconds: f64,
}

struct Emitter<'a> {
    s: &'a FdmSettings,
    out: String,
    pos: Point,
    e: f64,
    retracted: bool,
    filament: f64,
    seconds: f64,
}

impl Emitter<'_> {
    fn travel(&mut self, to: Point, barriers: &[Contour]) {
        let d = dist(self.pos, to);
        if d < 1e-9 {
            return;
        }
        let retract = self.s.retract_length > 0.0
            && (d > self.s.retract_min_travel || crosses(self.pos, to, barriers));
        if retract {
            self.set_retracted(true);
        }
        let _ = writeln!(
            self.out,
            "G0 X{:.3} Y{:.3} F{:.0}",
            to[0],
            to[1],
            self.s.travel_speed * 60.0
        );
        self.seconds += d / self.s.travel_speed;
        self.pos = to;
    }

    fn unretract(&mut self) {
        self.set_retracted(false);
    }

    /// Pulls the filament back (or pushes it again) by the retract length, once.
    fn set_retracted(&mut self, retracted: bool) {
        if self.retracted == retracted {
            return;
        }
        let length = self.s.retract_length;
        self.e += if retracted { -length } else { length };
        let _ = writeln!(
            self.out,
            "G1 E{:.5} F{:.0}",
            self.e,
            self.s.retract_speed * 60.0
        );
        self.seconds += length / self.s.retract_speed;
        self.retracted = retracted;
    }

    fn extrude(&mut self, path: &Extrusion, h: f64, speed: f64, barriers: &[Contour]) {
        let Some(&first) = path.points.first() else {
            return;
        };
        self.travel(first, barriers);
        self.unretract();
        let _ = writeln!(self.out, ";TYPE:{}", path.role.name());
        let per_mm = self.s.line_width * h / self.s.filament_area();
        let mut feed_written = false;
        for &p in &path.points[1..] {
            let d = dist(self.pos, p);
            if d < 1e-6 {
                continue;
            }
            let de = d * per_mm;
            self.e += de;
            self.filament += de;
            self.seconds += d / speed;
            if feed_written {
                let _ = writeln!(self.out, "G1 X{:.3} Y{:.3} E{:.5}", p[0], p[1], self.e);
            } else {
                let _ = writeln!(
                    self.out,
                    "G1 X{:.3} Y{:.3} E{:.5} F{:.0}",
                    p[0],
                    p[1],
                    self.e,
                    speed * 60.0
                );
                feed_written = true;
            }
            self.pos = p;
        }
    }
}

/// True when the travel `a`-`b` crosses an edge of any contour.
fn crosses(a: Point, b: Point, barriers: &[Contour]) -> bool {
    let (lo, hi) = (
        [a[0].min(b[0]), a[1].min(b[1])],
        [a[0].max(b[0]), a[1].max(b[1])],
    );
    barriers.iter().any(|c| {
        let n = c.len();
        (0..n).any(|i| {
            let (p, q) = (c[i], c[(i + 1) % n]);
            if p[0].max(q[0]) < lo[0]
                || p[0].min(q[0]) > hi[0]
                || p[1].max(q[1]) < lo[1]
                || p[1].min(q[1]) > hi[1]
            {
                return false;
            }
            segments_cross(a, b, p, q)
        })
    })
}

/// Writes the whole file: header, start template, layers, end template.
pub fn write_gcode(plans: &[LayerPlan], s: &FdmSettings) -> (String, GcodeStats) {
    let mut em = Emitter {
        s,
        out: String::new(),
        pos: [0.0, 0.0],
        e: 0.0,
        retracted: false,
        filament: 0.0,
        seconds: 0.0,
    };
    // Layers first (the header needs their totals), each remembering its start time.
    let mut bodies: Vec<(String, f64)> = Vec::with_capacity(plans.len());
    for (n, plan) in plans.iter().enumerate() {
        let started = em.seconds;
        em.out.clear();
        em.e = 0.0;
        let _ = writeln!(em.out, "G92 E0");
        if em.retracted {
            // The retraction carried over: E counts from the retracted position now.
            em.e = -s.retract_length;
            let _ = writeln!(em.out, "G92 E{:.5}", em.e);
        }
        let _ = writeln!(
            em.out,
            "G1 Z{:.3} F{:.0}",
            plan.top,
            s.travel_speed.min(15.0) * 60.0
        );
        if n == 0 {
            let _ = writeln!(em.out, "M107");
        } else if n == 1 && s.fan_speed > 0.0 {
            let _ = writeln!(em.out, "M106 S{:.0}", s.fan_speed * 255.0);
        }
        let speed = if n == 0 {
            s.first_layer_speed
        } else {
            s.print_speed
        };
        for path in &plan.paths {
            let sp = if path.role == Role::Skirt {
                s.first_layer_speed
            } else {
                speed
            };
            em.extrude(path, plan.height, sp, &plan.barriers);
        }
        bodies.push((std::mem::take(&mut em.out), started));
    }
    let total = em.seconds;
    let stats = GcodeStats {
        layers: plans.len(),
        filament_mm: em.filament,
        filament_g: em.filament * s.filament_area() * s.filament_density / 1000.0,
        seconds: total,
    };

    let mut out =
        String::with_capacity(bodies.iter().map(|b| b.0.len() + 64).sum::<usize>() + 4096);
    let _ = writeln!(out, "; generated by isoforge {}", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(out, ";FLAVOR:Marlin");
    let _ = writeln!(out, ";TIME:{:.0}", total);
    let _ = writeln!(out, ";Filament used: {:.5}m", stats.filament_mm / 1000.0);
    let _ = writeln!(out, ";Layer height: {}", s.layer_height);
    let _ = writeln!(out, "; filament used [mm] = {:.2}", stats.filament_mm);
    let _ = writeln!(out, "; filament used [g] = {:.2}", stats.filament_g);
    let _ = writeln!(
        out,
        "; estimated printing time (normal mode) = {}",
        hms(total)
    );
    let _ = writeln!(
        out,
        "; layer_height = {}, first_layer_height = {}, line_width = {}, perimeters = {}, infill = {} {:?}",
        s.layer_height,
        s.first_layer_height,
        s.line_width,
        s.perimeters,
        s.infill_density,
        s.infill_pattern
    );
    let start = fill_template(&s.start_gcode, s);
    // Temperatures must be set before anything extrudes, whatever the template holds.
    if !start.contains("M109") {
        let _ = writeln!(out, "M104 S{:.0}", s.nozzle_temperature);
        let _ = writeln!(out, "M140 S{:.0}", s.bed_temperature);
        let _ = writeln!(out, "M190 S{:.0}", s.bed_temperature);
        let _ = writeln!(out, "M109 S{:.0}", s.nozzle_temperature);
    }
    out.push_str(start.trim_end());
    out.push('\n');
    let _ = writeln!(
        out,
        "G21 ; millimetres\nG90 ; absolute positions\nM82 ; absolute extrusion\nG92 E0"
    );
    let _ = writeln!(out, ";LAYER_COUNT:{}", plans.len());
    for (n, ((body, started), plan)) in bodies.iter().zip(plans).enumerate() {
        let done = if total > 0.0 { started / total } else { 0.0 };
        let _ = writeln!(out, ";LAYER:{n}");
        let _ = writeln!(out, ";Z:{:.3}", plan.top);
        let _ = writeln!(
            out,
            "M73 P{:.0} R{:.0}",
            (done * 100.0).floor(),
            ((total - started) / 60.0).ceil()
        );
        out.push_str(body);
    }
    let _ = writeln!(out, "M73 P100 R0");
    out.push_str(fill_template(&s.end_gcode, s).trim_end());
    out.push('\n');
    (out, stats)
}

fn hms(seconds: f64) -> String {
    let t = seconds.max(0.0).round() as u64;
    let (h, m, s) = (t / 3600, t / 60 % 60, t % 60);
    if h > 0 {
        format!("{h}h {m}m {s}s")
    } else {
        format!("{m}m {s}s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::Profile;

    #[test]
    fn extrusion_follows_the_volume_formula() {
        let s = Profile::default_fdm().fdm().unwrap();
        let plan = LayerPlan {
            top: 0.2,
            height: 0.2,
            paths: vec![Extrusion {
                role: Role::Fill,
                points: vec![[10.0, 10.0], [110.0, 10.0]],
            }],
            barriers: vec![],
        };
        let (text, stats) = write_gcode(&[plan], &s);
        let want = s.line_width * 0.2 * 100.0
            / (std::f64::consts::PI * (s.filament_diameter / 2.0).powi(2));
        assert!((stats.filament_mm - want).abs() < 1e-9);
        assert!(text.contains(&format!("E{want:.5}")), "{text}");
        assert!(text.contains(";LAYER:0") && text.contains(";Z:0.200") && text.contains("M73 P0"));
        assert!(text.contains("M109 S205"));
    }

    #[test]
    fn long_travel_retracts_and_short_one_does_not() {
        let s = Profile::default_fdm().fdm().unwrap();
        let line = |a: Point, b: Point| Extrusion {
            role: Role::Fill,
            points: vec![a, b],
        };
        let plan = LayerPlan {
            top: 0.2,
            height: 0.2,
            paths: vec![
                line([0.0, 0.0], [10.0, 0.0]),
                line([10.0, 0.5], [0.0, 0.5]),
                line([50.0, 50.0], [60.0, 50.0]),
            ],
            barriers: vec![],
        };
        let (text, _) = write_gcode(&[plan], &s);
        let retracts = text
            .lines()
            .filter(|l| l.starts_with("G1 E") && l.contains("E-"))
            .count();
        assert_eq!(retracts, 1, "{text}");
    }
}
