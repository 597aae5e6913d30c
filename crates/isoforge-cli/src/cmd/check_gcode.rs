//! `isoforge check FILE.gcode`: what a G-code file prints, from any slicer (ours,
//! PrusaSlicer's, Cura's), read by the slicer's checker: layers, retractions, filament,
//! each layer's time at the feed rates asked, and the extruded volume by feature.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result};
use isoforge_slice::check::{self, GcodeReport, features};
use serde_json::json;

use crate::common::{Global, print_json};

/// Extensions read as G-code.
pub const GCODE_EXTENSIONS: &[&str] = &["gcode", "gco", "g"];

/// The filament diameter volumes are figured with unless the file says otherwise, mm.
const DEFAULT_FILAMENT: f64 = 1.75;

/// Checks a G-code file; exit 0 when it reads, 2 when it does not.
pub fn run(path: &Path, global: &Global) -> Result<ExitCode> {
    let text = match isoforge_output::read_input_to_string(path)
        .with_context(|| format!("{}: cannot be read", path.display()))
    {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e:#}");
            return Ok(ExitCode::from(2));
        }
    };
    let report = match check::parse(&text) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {}: {e}", path.display());
            return Ok(ExitCode::from(2));
        }
    };
    let filament = filament_diameter(&text).unwrap_or(DEFAULT_FILAMENT);
    let summary = Summary::of(&report, filament);
    let name = path.display().to_string();
    if global.json {
        print_json(&summary.json(&name));
    } else if !global.quiet {
        print!("{}", summary.text(&name));
    }
    Ok(ExitCode::SUCCESS)
}

/// The filament diameter a slicer wrote in its settings comment (PrusaSlicer:
/// `; filament_diameter = 1.75`, Cura: `;Filament Diameter` is not written, isoforge:
/// `; filament_diameter = 1.75`).
fn filament_diameter(text: &str) -> Option<f64> {
    text.lines().find_map(|l| {
        let rest = l.trim_start_matches(';').trim();
        let v = rest.strip_prefix("filament_diameter")?.trim();
        let v = v.strip_prefix('=')?.trim();
        // Multi-extruder files list one per extruder.
        v.split([',', ';']).next()?.trim().parse().ok()
    })
}

/// The figures reported.
struct Summary {
    layers: usize,
    retractions: usize,
    filament_mm: f64,
    filament_diameter: f64,
    layer_times: Vec<(usize, f64)>,
    volumes: BTreeMap<String, f64>,
}

impl Summary {
    fn of(r: &GcodeReport, filament: f64) -> Summary {
        let mut volumes: BTreeMap<String, f64> = BTreeMap::new();
        let area = std::f64::consts::PI * (filament / 2.0).powi(2);
        for x in &r.extrusions {
            *volumes.entry(x.feature.clone()).or_default() += x.e * area;
        }
        Summary {
            layers: r.layers.len(),
            retractions: features::retractions(r),
            filament_mm: r.filament_mm,
            filament_diameter: filament,
            layer_times: features::layer_times(r),
            volumes,
        }
    }

    /// The shortest, median and longest layer time, s.
    fn time_range(&self) -> Option<(f64, f64, f64)> {
        let mut t: Vec<f64> = self.layer_times.iter().map(|l| l.1).collect();
        t.sort_by(f64::total_cmp);
        Some((*t.first()?, t[t.len() / 2], *t.last()?))
    }

    fn json(&self, file: &str) -> serde_json::Value {
        let range = self.time_range();
        json!({
            "file": file,
            "layers": self.layers,
            "retractions": self.retractions,
            "filament_mm": self.filament_mm,
            "filament_diameter": self.filament_diameter,
            "layer_seconds_min": range.map(|r| r.0),
            "layer_seconds_median": range.map(|r| r.1),
            "layer_seconds_max": range.map(|r| r.2),
            "print_seconds_at_feed": self.layer_times.iter().map(|l| l.1).sum::<f64>(),
            "volume_mm3": self.volumes,
        })
    }

    fn text(&self, file: &str) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(s, "{file}: G-code");
        let _ = writeln!(s, "  {:<24}{}", "layers", self.layers);
        let _ = writeln!(s, "  {:<24}{}", "retractions", self.retractions);
        let _ = writeln!(
            s,
            "  {:<24}{:.1} mm ({} mm filament)",
            "filament", self.filament_mm, self.filament_diameter
        );
        if let Some((lo, mid, hi)) = self.time_range() {
            let _ = writeln!(
                s,
                "  {:<24}{lo:.1} / {mid:.1} / {hi:.1} s (shortest / median / longest, at the feed rates asked)",
                "layer time"
            );
        }
        for (feature, v) in &self.volumes {
            let name = if feature.is_empty() {
                "(no type)"
            } else {
                feature
            };
            let _ = writeln!(s, "  volume {name:<17}{v:.1} mm³");
        }
        s
    }
}
