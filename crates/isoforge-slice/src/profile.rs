//! Printer profiles: a flat TOML table of settings, overridden by `--set KEY=VALUE`, read
//! into typed settings for filament printers ([`FdmSettings`]) or resin printers
//! ([`ResinSettings`]). Every key the chosen output needs must be present and valid: a
//! missing or negative value is an error naming the key and the file.

use std::path::{Path, PathBuf};

use crate::SliceError;

/// Every key a profile may hold, with what it means (shown in errors).
pub const KEYS: &[(&str, &str)] = &[
    ("name", "the printer's name (text)"),
    ("technology", "\"fdm\" or \"resin\""),
    ("layer_height", "layer height, mm"),
    ("first_layer_height", "first layer height, mm"),
    ("nozzle_diameter", "nozzle diameter, mm"),
    ("line_width", "extrusion width, mm"),
    ("filament_diameter", "filament diameter, mm"),
    ("filament_density", "filament density, g/cm³"),
    ("perimeters", "number of perimeter loops"),
    ("top_layers", "solid layers at the top"),
    ("bottom_layers", "solid layers at the bottom"),
    ("infill_density", "sparse infill density, 0 to 1"),
    ("infill_pattern", "\"rectilinear\", \"grid\" or \"gyroid\""),
    ("print_speed", "print speed, mm/s"),
    ("first_layer_speed", "first layer speed, mm/s"),
    ("travel_speed", "travel speed, mm/s"),
    ("retract_length", "retraction length, mm"),
    ("retract_speed", "retraction speed, mm/s"),
    (
        "retract_min_travel",
        "travel that triggers a retraction, mm",
    ),
    ("nozzle_temperature", "nozzle temperature, °C"),
    ("bed_temperature", "bed temperature, °C"),
    ("fan_speed", "part fan from layer 2 on, 0 to 1"),
    ("skirt_loops", "skirt loops"),
    ("skirt_distance", "skirt distance from the part, mm"),
    ("bed_size", "bed size [x, y], mm"),
    ("max_height", "printable height, mm"),
    ("start_gcode", "start G-code template"),
    ("end_gcode", "end G-code template"),
    ("pixel_size", "resin display pixel size, mm"),
    ("resolution", "resin display [width, height], pixels"),
    ("exposure_time", "layer exposure, s"),
    ("first_exposure_time", "first layers' exposure, s"),
    (
        "faded_layers",
        "layers fading from first to normal exposure",
    ),
    ("printer_model", "resin printer model written to SL1 (text)"),
    ("material_name", "resin name written to SL1 (text)"),
];

/// A profile as read: the TOML table, where it came from, and any `--set` overrides.
#[derive(Clone, Debug)]
pub struct Profile {
    table: toml::Table,
    source: String,
}

/// The sparse infill pattern.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum InfillPattern {
    /// Parallel lines, alternating 45° and 135° between layers.
    Rectilinear,
    /// Lines in both directions on every layer.
    Grid,
    /// The gyroid's cross-section, sin x cos y + sin y cos z + sin z cos x = 0.
    Gyroid,
}

/// Settings for filament (FDM) printing.
#[derive(Clone, Debug, PartialEq)]
pub struct FdmSettings {
    /// Layer height, mm.
    pub layer_height: f64,
    /// First layer height, mm.
    pub first_layer_height: f64,
    /// Nozzle diameter, mm.
    pub nozzle_diameter: f64,
    /// Extrusion width, mm.
    pub line_width: f64,
    /// Filament diameter, mm.
    pub filament_diameter: f64,
    /// Filament density, g/cm³.
    pub filament_density: f64,
    /// Perimeter loops.
    pub perimeters: usize,
    /// Solid layers at the top.
    pub top_layers: usize,
    /// Solid layers at the bottom.
    pub bottom_layers: usize,
    /// Sparse infill density, 0 to 1.
    pub infill_density: f64,
    /// Sparse infill pattern.
    pub infill_pattern: InfillPattern,
    /// Print speed, mm/s.
    pub print_speed: f64,
    /// First layer speed, mm/s.
    pub first_layer_speed: f64,
    /// Travel speed, mm/s.
    pub travel_speed: f64,
    /// Retraction length, mm of filament.
    pub retract_length: f64,
    /// Retraction speed, mm/s.
    pub retract_speed: f64,
    /// Travel longer than this retracts, mm.
    pub retract_min_travel: f64,
    /// Nozzle temperature, °C.
    pub nozzle_temperature: f64,
    /// Bed temperature, °C.
    pub bed_temperature: f64,
    /// Part fan from the second layer on, 0 to 1.
    pub fan_speed: f64,
    /// Skirt loops around the first layer.
    pub skirt_loops: usize,
    /// Gap between the skirt and the part, mm.
    pub skirt_distance: f64,
    /// Bed size, mm.
    pub bed_size: [f64; 2],
    /// Printable height, mm.
    pub max_height: f64,
    /// Start G-code template (`{key}` placeholders).
    pub start_gcode: String,
    /// End G-code template.
    pub end_gcode: String,
}

/// Settings for resin (masked SLA) printing and voxel output.
#[derive(Clone, Debug, PartialEq)]
pub struct ResinSettings {
    /// Layer height, mm.
    pub layer_height: f64,
    /// Pixel size on the display, mm.
    pub pixel_size: f64,
    /// Display size in pixels, [width, height] (portrait: width < height).
    pub resolution: [u32; 2],
    /// Layer exposure, s.
    pub exposure_time: f64,
    /// Exposure of the first layers, s.
    pub first_exposure_time: f64,
    /// Layers over which exposure fades from the first to the normal time.
    pub faded_layers: usize,
    /// Printer model named in the SL1 archive.
    pub printer_model: String,
    /// Material named in the SL1 archive.
    pub material_name: String,
    /// Printable height, mm.
    pub max_height: f64,
}

impl Profile {
    /// Parses a profile from TOML text; `source` names it in errors (a path).
    pub fn parse(text: &str, source: &str) -> Result<Profile, SliceError> {
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let at = e
                .span()
                .map(|s| {
                    let line = text[..s.start.min(text.len())].lines().count().max(1);
                    format!(" (line {line}, byte {})", s.start)
                })
                .unwrap_or_default();
            SliceError::Profile(format!("{source}{at}: {}", e.message()))
        })?;
        for key in table.keys() {
            if !KEYS.iter().any(|(k, _)| k == key) {
                return Err(SliceError::Profile(format!(
                    "{source}: unknown key `{key}` (known keys: {})",
                    key_list()
                )));
            }
        }
        Ok(Profile {
            table,
            source: source.to_string(),
        })
    }

    /// Reads a profile file.
    pub fn load(path: &Path) -> Result<Profile, SliceError> {
        let text = std::fs::read_to_string(path).map_err(|e| SliceError::Io {
            path: PathBuf::from(path),
            source: e,
        })?;
        Profile::parse(&text, &path.display().to_string())
    }

    /// The built-in generic 220×220 Marlin profile (fixtures/printers/generic_marlin_220.toml).
    pub fn default_fdm() -> Profile {
        Profile::builtin(
            include_str!("../../../fixtures/printers/generic_marlin_220.toml"),
            "built-in generic_marlin_220",
        )
    }

    /// The built-in resin profile (fixtures/printers/prusa_sl1.toml).
    pub fn default_resin() -> Profile {
        Profile::builtin(
            include_str!("../../../fixtures/printers/prusa_sl1.toml"),
            "built-in prusa_sl1",
        )
    }

    fn builtin(text: &str, source: &str) -> Profile {
        // The built-in texts are tested to parse (profile::tests); an empty table would only
        // make every later lookup report the missing key.
        Profile::parse(text, source).unwrap_or(Profile {
            table: toml::Table::new(),
            source: source.to_string(),
        })
    }

    /// Where the profile came from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// True when the profile is for a resin printer (`technology = "resin"`).
    pub fn is_resin(&self) -> bool {
        self.table.get("technology").and_then(|v| v.as_str()) == Some("resin")
    }

    /// Applies one `KEY=VALUE` override. VALUE is TOML (`0.2`, `"gyroid"`, `[200, 200]`),
    /// or bare text for text keys, or comma-separated numbers for lists.
    pub fn set(&mut self, assignment: &str) -> Result<(), SliceError> {
        let Some((key, value)) = assignment.split_once('=') else {
            return Err(SliceError::Profile(format!(
                "--set {assignment:?}: expected KEY=VALUE"
            )));
        };
        let key = key.trim();
        if !KEYS.iter().any(|(k, _)| *k == key) {
            return Err(SliceError::Profile(format!(
                "--set {assignment:?}: unknown key `{key}` (known keys: {})",
                key_list()
            )));
        }
        let value = value.trim();
        let parsed = format!("v = {value}")
            .parse::<toml::Table>()
            .ok()
            .and_then(|mut t| t.remove("v"))
            .or_else(|| {
                // `200,200` for a list; anything else is text.
                let nums: Option<Vec<toml::Value>> = value
                    .split(',')
                    .map(|s| s.trim().parse::<f64>().ok().map(toml::Value::Float))
                    .collect();
                match nums {
                    Some(n) if n.len() > 1 => Some(toml::Value::Array(n)),
                    _ => Some(toml::Value::String(value.replace("\\n", "\n"))),
                }
            })
            .unwrap_or_else(|| toml::Value::String(value.to_string()));
        self.table.insert(key.to_string(), parsed);
        if !self.source.ends_with(" + --set") {
            self.source.push_str(" + --set");
        }
        Ok(())
    }

    fn missing(&self, key: &str) -> SliceError {
        let what = KEYS
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, w)| *w)
            .unwrap_or("");
        SliceError::Profile(format!(
            "{}: missing key `{key}` ({what}); add it to the profile or pass --set {key}=VALUE",
            self.source
        ))
    }

    fn bad(&self, key: &str, why: &str) -> SliceError {
        SliceError::Profile(format!("{}: `{key}` {why}", self.source))
    }

    /// A number, required, finite and at least `min` (with `strict` it must exceed `min`).
    fn number(&self, key: &str, min: f64, strict: bool) -> Result<f64, SliceError> {
        let v = self.table.get(key).ok_or_else(|| self.missing(key))?;
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            other => {
                return Err(self.bad(key, &format!("must be a number, not {other}")));
            }
        };
        if !x.is_finite() {
            return Err(self.bad(key, "must be a finite number"));
        }
        if x < min || (strict && x <= min) {
            let rel = if strict { "greater than" } else { "at least" };
            return Err(self.bad(key, &format!("is {x}; it must be {rel} {min}")));
        }
        Ok(x)
    }

    fn positive(&self, key: &str) -> Result<f64, SliceError> {
        self.number(key, 0.0, true)
    }

    fn non_negative(&self, key: &str) -> Result<f64, SliceError> {
        self.number(key, 0.0, false)
    }

    fn count(&self, key: &str) -> Result<usize, SliceError> {
        let x = self.non_negative(key)?;
        if x.fract() != 0.0 || x > 10_000.0 {
            return Err(self.bad(key, &format!("is {x}; it must be a whole number")));
        }
        Ok(x as usize)
    }

    fn fraction(&self, key: &str) -> Result<f64, SliceError> {
        let x = self.non_negative(key)?;
        if x > 1.0 {
            return Err(self.bad(key, &format!("is {x}; it must be between 0 and 1")));
        }
        Ok(x)
    }

    fn text(&self, key: &str) -> Result<String, SliceError> {
        match self.table.get(key).ok_or_else(|| self.missing(key))? {
            toml::Value::String(s) => Ok(s.clone()),
            other => Err(self.bad(key, &format!("must be text, not {other}"))),
        }
    }

    fn pair(&self, key: &str) -> Result<[f64; 2], SliceError> {
        let v = self.table.get(key).ok_or_else(|| self.missing(key))?;
        let nums: Option<Vec<f64>> = v.as_array().and_then(|a| {
            a.iter()
                .map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                .collect()
        });
        match nums.as_deref() {
            Some(&[a, b]) if a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0 => Ok([a, b]),
            _ => Err(self.bad(key, "must be two positive numbers, e.g. [220, 220]")),
        }
    }

    /// The filament-printer settings; every key they need must be present and valid.
    pub fn fdm(&self) -> Result<FdmSettings, SliceError> {
        if self.is_resin() {
            return Err(SliceError::Profile(format!(
                "{} is a resin profile; G-code needs a filament printer profile \
                 (e.g. fixtures/printers/generic_marlin_220.toml)",
                self.source
            )));
        }
        let pattern = match self.text("infill_pattern")?.as_str() {
            "rectilinear" => InfillPattern::Rectilinear,
            "grid" => InfillPattern::Grid,
            "gyroid" => InfillPattern::Gyroid,
            other => {
                return Err(self.bad(
                    "infill_pattern",
                    &format!("is {other:?}; use \"rectilinear\", \"grid\" or \"gyroid\""),
                ));
            }
        };
        let s = FdmSettings {
            layer_height: self.positive("layer_height")?,
            first_layer_height: self.positive("first_layer_height")?,
            nozzle_diameter: self.positive("nozzle_diameter")?,
            line_width: self.positive("line_width")?,
            filament_diameter: self.positive("filament_diameter")?,
            filament_density: self.positive("filament_density")?,
            perimeters: self.count("perimeters")?,
            top_layers: self.count("top_layers")?,
            bottom_layers: self.count("bottom_layers")?,
            infill_density: self.fraction("infill_density")?,
            infill_pattern: pattern,
            print_speed: self.positive("print_speed")?,
            first_layer_speed: self.positive("first_layer_speed")?,
            travel_speed: self.positive("travel_speed")?,
            retract_length: self.non_negative("retract_length")?,
            retract_speed: self.positive("retract_speed")?,
            retract_min_travel: self.non_negative("retract_min_travel")?,
            nozzle_temperature: self.non_negative("nozzle_temperature")?,
            bed_temperature: self.non_negative("bed_temperature")?,
            fan_speed: self.fraction("fan_speed")?,
            skirt_loops: self.count("skirt_loops")?,
            skirt_distance: self.non_negative("skirt_distance")?,
            bed_size: self.pair("bed_size")?,
            max_height: self.positive("max_height")?,
            start_gcode: self.text("start_gcode")?,
            end_gcode: self.text("end_gcode")?,
        };
        if s.line_width < 0.5 * s.nozzle_diameter || s.line_width > 3.0 * s.nozzle_diameter {
            return Err(self.bad(
                "line_width",
                &format!(
                    "is {} mm for a {} mm nozzle; use 0.5 to 3 times the nozzle diameter",
                    s.line_width, s.nozzle_diameter
                ),
            ));
        }
        for (key, h) in [
            ("layer_height", s.layer_height),
            ("first_layer_height", s.first_layer_height),
        ] {
            if h > s.nozzle_diameter {
                return Err(self.bad(
                    key,
                    &format!(
                        "is {h} mm, more than the {} mm nozzle can lay down",
                        s.nozzle_diameter
                    ),
                ));
            }
        }
        Ok(s)
    }

    /// The resin-printer settings; every key they need must be present and valid.
    pub fn resin(&self) -> Result<ResinSettings, SliceError> {
        let res = self.pair("resolution")?;
        if res[0].fract() != 0.0 || res[1].fract() != 0.0 || res[0] > 65536.0 || res[1] > 65536.0 {
            return Err(self.bad("resolution", "must be two whole pixel counts"));
        }
        Ok(ResinSettings {
            layer_height: self.positive("layer_height")?,
            pixel_size: self.positive("pixel_size")?,
            resolution: [res[0] as u32, res[1] as u32],
            exposure_time: self.positive("exposure_time")?,
            first_exposure_time: self.positive("first_exposure_time")?,
            faded_layers: self.count("faded_layers")?,
            printer_model: self.text("printer_model")?,
            material_name: self.text("material_name")?,
            max_height: self.positive("max_height")?,
        })
    }
}

fn key_list() -> String {
    KEYS.iter().map(|(k, _)| *k).collect::<Vec<_>>().join(", ")
}

impl FdmSettings {
    /// Filament cross-section, mm².
    pub fn filament_area(&self) -> f64 {
        std::f64::consts::PI * (self.filament_diameter / 2.0).powi(2)
    }
}

/// Fills `{key}` placeholders in a G-code template from the settings.
pub fn fill_template(template: &str, s: &FdmSettings) -> String {
    let values: [(&str, String); 9] = [
        ("nozzle_temperature", fmt_num(s.nozzle_temperature)),
        ("bed_temperature", fmt_num(s.bed_temperature)),
        ("layer_height", fmt_num(s.layer_height)),
        ("first_layer_height", fmt_num(s.first_layer_height)),
        ("bed_x", fmt_num(s.bed_size[0])),
        ("bed_y", fmt_num(s.bed_size[1])),
        ("max_height", fmt_num(s.max_height)),
        ("filament_diameter", fmt_num(s.filament_diameter)),
        ("travel_speed", fmt_num(s.travel_speed * 60.0)),
    ];
    let mut out = template.to_string();
    for (k, v) in values {
        out = out.replace(&format!("{{{k}}}"), &v);
    }
    out
}

fn fmt_num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e9 {
        format!("{}", x as i64)
    } else {
        format!("{x}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_profiles_are_complete() {
        let f = Profile::default_fdm().fdm().unwrap();
        assert_eq!(f.bed_size, [220.0, 220.0]);
        let r = Profile::default_resin().resin().unwrap();
        assert_eq!(r.resolution, [1440, 2560]);
    }

    #[test]
    fn the_fixture_profiles_are_complete() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/printers");
        for name in ["generic_marlin_220.toml", "prusa_mk3.toml"] {
            let p = Profile::load(&Path::new(dir).join(name)).unwrap();
            p.fdm().unwrap();
        }
        Profile::load(&Path::new(dir).join("prusa_sl1.toml"))
            .unwrap()
            .resin()
            .unwrap();
    }

    #[test]
    fn missing_key_is_named_with_the_file() {
        let text = include_str!("../../../fixtures/printers/generic_marlin_220.toml");
        let cut: String = text
            .lines()
            .filter(|l| !l.starts_with("line_width"))
            .collect::<Vec<_>>()
            .join("\n");
        let err = Profile::parse(&cut, "my.toml").unwrap().fdm().unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("my.toml") && msg.contains("`line_width`"),
            "{msg}"
        );
    }

    #[test]
    fn negative_value_is_refused() {
        let mut p = Profile::default_fdm();
        p.set("retract_length=-1").unwrap();
        let msg = p.fdm().unwrap_err().to_string();
        assert!(
            msg.contains("`retract_length`") && msg.contains("-1"),
            "{msg}"
        );
    }

    #[test]
    fn set_overrides_and_parses_values() {
        let mut p = Profile::default_fdm();
        p.set("layer_height=0.1").unwrap();
        p.set("infill_pattern=gyroid").unwrap();
        p.set("bed_size=200,180").unwrap();
        let s = p.fdm().unwrap();
        assert_eq!(s.layer_height, 0.1);
        assert_eq!(s.infill_pattern, InfillPattern::Gyroid);
        assert_eq!(s.bed_size, [200.0, 180.0]);
        assert!(p.set("no_such_key=1").is_err());
        assert!(p.set("novalue").is_err());
    }

    #[test]
    fn bad_toml_says_where() {
        let msg = Profile::parse("layer_height = = 2\n", "x.toml")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("x.toml") && msg.contains("line 1"), "{msg}");
    }
}
