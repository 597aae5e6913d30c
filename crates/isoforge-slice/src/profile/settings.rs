//! The typed settings a profile is read into, by serde, and their validation: every number
//! within the physical range [`KEYS`](super::keys::KEYS) gives it, keys that depend on each
//! other consistent, and G-code templates using only placeholders isoforge fills.

use serde::{Deserialize, Serialize};

use super::error::{ProfileError, ProfileErrorKind};
use super::keys;
use super::template;

/// The kind of printer a profile is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Technology {
    /// Filament (fused deposition): G-code.
    Fdm,
    /// Resin (masked SLA): layer images.
    Resin,
}

impl std::fmt::Display for Technology {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Technology::Fdm => "a filament (fdm)",
            Technology::Resin => "a resin",
        })
    }
}

/// The sparse infill pattern.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InfillPattern {
    /// Parallel lines, alternating 45° and 135° between layers.
    Rectilinear,
    /// Lines in both directions on every layer.
    Grid,
    /// The gyroid's cross-section, sin x cos y + sin y cos z + sin z cos x = 0.
    Gyroid,
}

/// How overhangs are held up.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SupportStyle {
    /// No supports: a part that starts in mid-air is sliced with a warning.
    None,
    /// Straight columns of grid lines under every overhang, a dense top interface and a gap.
    Grid,
    /// Branches that lean in from the bed to each overhang, a dense tip under it and a gap.
    Tree,
}

/// The pattern of top surfaces.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TopFillPattern {
    /// Parallel lines all laid in one sweep, so every line lands beside one already cooled
    /// on the same side: no visible seams where two sweeps meet.
    Monotonic,
    /// Parallel lines joined in the shortest order.
    Rectilinear,
}

/// Settings for filament (FDM) printing. The field names are the profile keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
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
    /// Part fan on short layers (at or under `min_layer_time`), 0 to 1.
    pub fan_speed: f64,
    /// Skirt loops around the first layer.
    pub skirt_loops: usize,
    /// Gap between the skirt and the part, mm.
    pub skirt_distance: f64,
    /// Bed size, mm.
    pub bed_size: [f64; 2],
    /// Printable height, mm.
    pub max_height: f64,
    /// Outer wall speed, mm/s.
    pub external_perimeter_speed: f64,
    /// Top surface speed, mm/s.
    pub top_solid_infill_speed: f64,
    /// Thin wall and gap fill speed, mm/s.
    pub gap_fill_speed: f64,
    /// Bridge and overhang speed, mm/s.
    pub bridge_speed: f64,
    /// Support speed, mm/s.
    pub support_material_speed: f64,
    /// Ironing speed, mm/s.
    pub ironing_speed: f64,
    /// Top surface line width, mm.
    pub top_infill_extrusion_width: f64,
    /// Bridge strand flow as a ratio of a nozzle-wide round strand.
    pub bridge_flow: f64,
    /// Part fan on bridges and overhangs, 0 to 1.
    pub bridge_fan_speed: f64,
    /// Print walls thinner than two lines with one or two lines of their own width.
    #[serde(deserialize_with = "flag")]
    pub thin_walls: bool,
    /// Fill gaps between walls with lines of their width.
    #[serde(deserialize_with = "flag")]
    pub gap_fill: bool,
    /// Pattern of the top surfaces.
    pub top_fill_pattern: TopFillPattern,
    /// Iron top surfaces (a second, nearly dry pass that smooths them).
    #[serde(deserialize_with = "flag")]
    pub ironing: bool,
    /// Supports under overhangs.
    pub supports: SupportStyle,
    /// Overhangs leaning further than this from vertical are supported, degrees.
    pub support_overhang_angle: f64,
    /// Gap between support and part, mm.
    pub support_z_gap: f64,
    /// Brim around the first layer, mm (0: none).
    pub brim_width: f64,
    /// Raft layers under the part (0: none).
    pub raft_layers: usize,
    /// Layers shorter than this are slowed down (and the head waits if slowing is not
    /// enough), s.
    pub min_layer_time: f64,
    /// The slowest speed cooling may slow down to, mm/s.
    pub slowdown_min_speed: f64,
    /// Below this layer time the fan rises from `min_fan_speed` toward `fan_speed`, s.
    pub fan_below_layer_time: f64,
    /// Part fan on long layers, 0 to 1.
    pub min_fan_speed: f64,
    /// The fan is off on the first layer and ramps up over this many.
    pub fan_first_layers: usize,
    /// Lift on retracted travel, mm (0: none).
    pub z_hop: f64,
    /// Wipe the nozzle back along the path it just printed while retracting.
    #[serde(deserialize_with = "flag")]
    pub wipe: bool,
    /// Keep travel inside the part, where it needs no retraction.
    #[serde(deserialize_with = "flag")]
    pub combing: bool,
    /// Acceleration while printing, mm/s².
    pub machine_max_acceleration_extruding: f64,
    /// Acceleration on travel, mm/s².
    pub machine_max_acceleration_travel: f64,
    /// Marlin's junction deviation, mm.
    pub junction_deviation: f64,
    /// Fastest Z move, mm/s.
    pub machine_max_feedrate_z: f64,
    /// One spiral outer wall, rising continuously, above the bottom layers.
    #[serde(deserialize_with = "flag")]
    pub vase_mode: bool,
    /// Copies of the model(s), arranged on the bed.
    pub copies: usize,
    /// Start G-code template (`{key}` placeholders).
    pub start_gcode: String,
    /// End G-code template.
    pub end_gcode: String,
}

/// Settings for resin (masked SLA) printing and voxel output. The field names are the
/// profile keys.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResinSettings {
    /// Layer height, mm.
    pub layer_height: f64,
    /// First layer height, mm (PrusaSlicer's `initial_layer_height`), exposed for
    /// `first_exposure_time`.
    pub first_layer_height: f64,
    /// Pixel size on the display, mm.
    pub pixel_size: f64,
    /// Display size in pixels, [width, height] (portrait: width < height); a profile may
    /// also write it as `"1440x2560"`.
    #[serde(deserialize_with = "resolution")]
    pub resolution: [u32; 2],
    /// Layer exposure, s.
    pub exposure_time: f64,
    /// How the display is mounted: the image's rows run along the display's long side in
    /// portrait.
    pub display_orientation: DisplayOrientation,
    /// The display mirrors the image in x.
    #[serde(deserialize_with = "flag")]
    pub display_mirror_x: bool,
    /// The display mirrors the image in y.
    #[serde(deserialize_with = "flag")]
    pub display_mirror_y: bool,
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

/// How a resin printer's display is mounted (PrusaSlicer's `display_orientation`).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DisplayOrientation {
    /// The image's x runs along the display's x.
    Landscape,
    /// The image is turned: its rows run along the display's x.
    Portrait,
}

/// `true`/`false`, or 1/0 as PrusaSlicer writes flags.
fn flag<'de, D: serde::Deserializer<'de>>(d: D) -> Result<bool, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Bool(bool),
        Int(i64),
    }
    match Written::deserialize(d)? {
        Written::Bool(b) => Ok(b),
        Written::Int(0) => Ok(false),
        Written::Int(1) => Ok(true),
        Written::Int(i) => Err(serde::de::Error::custom(format!(
            "{i} is not a flag: write true or false (or 1 or 0)"
        ))),
    }
}

/// `[1440, 2560]` or `"1440x2560"`.
fn resolution<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[u32; 2], D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Written {
        Pair([u32; 2]),
        Text(String),
    }
    match Written::deserialize(d)? {
        Written::Pair(p) => Ok(p),
        Written::Text(t) => t
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some([w.trim().parse().ok()?, h.trim().parse().ok()?]))
            .ok_or_else(|| {
                serde::de::Error::custom(format!(
                    "{t:?} is not a resolution: write [1440, 2560] or \"1440x2560\""
                ))
            }),
    }
}

impl FdmSettings {
    /// Filament cross-section, mm².
    pub fn filament_area(&self) -> f64 {
        std::f64::consts::PI * (self.filament_diameter / 2.0).powi(2)
    }

    /// Checks every number against its physical range, the keys that depend on each other
    /// (layers no thicker than the nozzle, lines 0.5 to 3 nozzle widths), and the G-code
    /// templates' placeholders.
    pub fn validate(&self) -> Result<(), ProfileError> {
        check_ranges(self)?;
        let nozzle = self.nozzle_diameter;
        if self.line_width < 0.5 * nozzle || self.line_width > 3.0 * nozzle {
            return Err(ProfileErrorKind::Conflict {
                key: "line_width",
                value: self.line_width,
                rule: format!(
                    "does not suit the {nozzle} mm nozzle_diameter: use 0.5 to 3 times it"
                ),
            }
            .into());
        }
        let top = self.top_infill_extrusion_width;
        if top < 0.5 * nozzle || top > 3.0 * nozzle {
            return Err(ProfileErrorKind::Conflict {
                key: "top_infill_extrusion_width",
                value: top,
                rule: format!(
                    "does not suit the {nozzle} mm nozzle_diameter: use 0.5 to 3 times it"
                ),
            }
            .into());
        }
        for (key, h) in [
            ("layer_height", self.layer_height),
            ("first_layer_height", self.first_layer_height),
        ] {
            if h > nozzle {
                return Err(ProfileErrorKind::Conflict {
                    key,
                    value: h,
                    rule: format!("is more than the {nozzle} mm nozzle_diameter can lay down"),
                }
                .into());
            }
        }
        template::check("start_gcode", &self.start_gcode)?;
        template::check("end_gcode", &self.end_gcode)?;
        Ok(())
    }
}

impl ResinSettings {
    /// How the display turns and mirrors the bed's picture.
    pub fn frame(&self) -> crate::DisplayFrame {
        crate::DisplayFrame {
            portrait: self.display_orientation == DisplayOrientation::Portrait,
            mirror_x: self.display_mirror_x,
            mirror_y: self.display_mirror_y,
        }
    }

    /// Checks every number against its physical range.
    pub fn validate(&self) -> Result<(), ProfileError> {
        check_ranges(self)
    }
}

/// Every number of `settings` (each element of a pair) against its key's range.
fn check_ranges(settings: &impl Serialize) -> Result<(), ProfileError> {
    let table = toml::Table::try_from(settings).map_err(|e| ProfileErrorKind::Invalid {
        key: "settings".into(),
        message: e.to_string(),
    })?;
    for (key, value) in &table {
        check_value(key, value)?;
    }
    Ok(())
}

/// One value against its key's range: numbers, and each number of an array. Values of
/// other types are left to serde, which says what type the key wants.
pub(crate) fn check_value(key: &str, value: &toml::Value) -> Result<(), ProfileErrorKind> {
    let Some(spec) = keys::spec(key) else {
        return Ok(());
    };
    let Some(range) = spec.range else {
        return Ok(());
    };
    let numbers: Vec<f64> = match value {
        toml::Value::Array(items) => items.iter().filter_map(number).collect(),
        other => number(other).into_iter().collect(),
    };
    for v in numbers {
        let whole_ok = !range.whole || v.fract() == 0.0;
        if !(v >= range.min && v <= range.max && whole_ok) {
            return Err(ProfileErrorKind::OutOfRange { spec, value: v });
        }
    }
    Ok(())
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        _ => None,
    }
}
