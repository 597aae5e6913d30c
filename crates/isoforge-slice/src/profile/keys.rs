//! Every profile key in one table: what it means, its unit, which printers use it, and the
//! physical range its value must lie in. Errors, the list of known keys, the range checks of
//! `validate()` and the key list in `docs/profiles.md` all come from [`KEYS`].

use super::settings::Technology;

/// The values a number may take (each element, for a pair).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// The smallest value allowed.
    pub min: f64,
    /// The largest value allowed.
    pub max: f64,
    /// Only whole numbers (counts, pixels).
    pub whole: bool,
}

/// Which printers a key is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UsedBy {
    /// The profile itself (`name`, `technology`).
    Profile,
    /// Filament printers.
    Fdm,
    /// Resin printers.
    Resin,
    /// Both kinds.
    Both,
}

impl UsedBy {
    /// True when a profile of `t` uses the key.
    pub fn includes(self, t: Technology) -> bool {
        match self {
            UsedBy::Profile | UsedBy::Both => true,
            UsedBy::Fdm => t == Technology::Fdm,
            UsedBy::Resin => t == Technology::Resin,
        }
    }
}

/// One profile key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeySpec {
    /// The key as written in a profile.
    pub key: &'static str,
    /// What it means, in a few words.
    pub meaning: &'static str,
    /// The unit of its numbers ("" for none).
    pub unit: &'static str,
    /// The range of its numbers; `None` for text and names.
    pub range: Option<Range>,
    /// Which printers use it.
    pub used_by: UsedBy,
}

const fn real(min: f64, max: f64) -> Option<Range> {
    Some(Range {
        min,
        max,
        whole: false,
    })
}

const fn whole(min: f64, max: f64) -> Option<Range> {
    Some(Range {
        min,
        max,
        whole: true,
    })
}

const fn key(
    key: &'static str,
    meaning: &'static str,
    unit: &'static str,
    range: Option<Range>,
    used_by: UsedBy,
) -> KeySpec {
    KeySpec {
        key,
        meaning,
        unit,
        range,
        used_by,
    }
}

use UsedBy::{Both, Fdm, Profile, Resin};

/// Every key a profile may hold. The ranges are what printers physically do, wide enough
/// for unusual machines and narrow enough that a typo (an extra zero, a missing point, a
/// value in the wrong unit) is caught before it reaches a printer: a temperature of 1000,
/// a 1e-200 mm filament (infinite extrusion) or a 1e-300 mm/s speed (F0).
pub const KEYS: &[KeySpec] = &[
    key("name", "the printer's name (text)", "", None, Profile),
    key("technology", "\"fdm\" or \"resin\"", "", None, Profile),
    // Resin printers go down to 10 µm; a 1.2 mm nozzle prints layers of about 0.9 mm. Below
    // 0.01 mm a 250 mm part would need more than 25,000 layers.
    key("layer_height", "layer height", "mm", real(0.01, 2.0), Both),
    key(
        "first_layer_height",
        "first layer height",
        "mm",
        real(0.01, 2.0),
        Both,
    ),
    // From 0.1 mm micro nozzles to 2 mm volcano-style ones.
    key(
        "nozzle_diameter",
        "nozzle diameter",
        "mm",
        real(0.1, 2.0),
        Fdm,
    ),
    key("line_width", "extrusion width", "mm", real(0.05, 6.0), Fdm),
    // 1.75, 2.85 and 3 mm filament exist.
    key(
        "filament_diameter",
        "filament diameter",
        "mm",
        real(1.0, 3.5),
        Fdm,
    ),
    // From foaming PLA (~0.6) to metal-filled filament (~4).
    key(
        "filament_density",
        "filament density",
        "g/cm³",
        real(0.5, 5.0),
        Fdm,
    ),
    key("perimeters", "perimeter loops", "", whole(0.0, 20.0), Fdm),
    key(
        "top_layers",
        "solid layers at the top",
        "",
        whole(0.0, 100.0),
        Fdm,
    ),
    key(
        "bottom_layers",
        "solid layers at the bottom",
        "",
        whole(0.0, 100.0),
        Fdm,
    ),
    key(
        "infill_density",
        "sparse infill density",
        "",
        real(0.0, 1.0),
        Fdm,
    ),
    key(
        "infill_pattern",
        "\"rectilinear\", \"grid\" or \"gyroid\"",
        "",
        None,
        Fdm,
    ),
    // The fastest consumer printers move at about 500-1000 mm/s; below 1 mm/s a print never
    // ends (and the G-code would say F0).
    key("print_speed", "print speed", "mm/s", real(1.0, 1000.0), Fdm),
    key(
        "first_layer_speed",
        "first layer speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "travel_speed",
        "travel speed",
        "mm/s",
        real(1.0, 1500.0),
        Fdm,
    ),
    // Long Bowden tubes retract up to about 10 mm.
    key(
        "retract_length",
        "retraction length",
        "mm",
        real(0.0, 20.0),
        Fdm,
    ),
    key(
        "retract_speed",
        "retraction speed",
        "mm/s",
        real(1.0, 200.0),
        Fdm,
    ),
    key(
        "retract_min_travel",
        "travel that triggers a retraction",
        "mm",
        real(0.0, 100.0),
        Fdm,
    ),
    // All-metal hotends reach 300-400 °C (PEEK, PEI); beds reach about 120 °C (PC, PEI
    // sheets). 0 leaves the heater off.
    key(
        "nozzle_temperature",
        "nozzle temperature",
        "°C",
        real(0.0, 400.0),
        Fdm,
    ),
    key(
        "bed_temperature",
        "bed temperature",
        "°C",
        real(0.0, 150.0),
        Fdm,
    ),
    key(
        "fan_speed",
        "part fan on short layers",
        "",
        real(0.0, 1.0),
        Fdm,
    ),
    key("skirt_loops", "skirt loops", "", whole(0.0, 20.0), Fdm),
    key(
        "skirt_distance",
        "skirt distance from the part",
        "mm",
        real(0.0, 50.0),
        Fdm,
    ),
    key("bed_size", "bed size [x, y]", "mm", real(10.0, 2000.0), Fdm),
    key(
        "max_height",
        "printable height",
        "mm",
        real(1.0, 2000.0),
        Both,
    ),
    // Print quality (names as PrusaSlicer's where it has one). Speeds share print_speed's
    // range; angles are degrees from vertical.
    key(
        "external_perimeter_speed",
        "outer wall speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "top_solid_infill_speed",
        "top surface speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "gap_fill_speed",
        "thin wall and gap fill speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "bridge_speed",
        "bridge and overhang speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "support_material_speed",
        "support speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "ironing_speed",
        "ironing speed",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    // Top surfaces are often printed a little narrower than the nozzle for a smooth finish;
    // the same 0.5 to 3 nozzle widths as line_width are checked in validate().
    key(
        "top_infill_extrusion_width",
        "top surface line width",
        "mm",
        real(0.05, 6.0),
        Fdm,
    ),
    // Bridges are laid as round strands; their flow is a ratio of a nozzle-wide strand's.
    // Below 0.5 strands break, above 2 they sag into a blob.
    key(
        "bridge_flow",
        "bridge strand flow ratio",
        "",
        real(0.5, 2.0),
        Fdm,
    ),
    key(
        "bridge_fan_speed",
        "part fan on bridges and overhangs",
        "",
        real(0.0, 1.0),
        Fdm,
    ),
    key(
        "thin_walls",
        "walls thinner than two lines printed (bool)",
        "",
        None,
        Fdm,
    ),
    key(
        "gap_fill",
        "gaps between walls filled (bool)",
        "",
        None,
        Fdm,
    ),
    key(
        "top_fill_pattern",
        "\"monotonic\" or \"rectilinear\"",
        "",
        None,
        Fdm,
    ),
    key("ironing", "top surfaces ironed (bool)", "", None, Fdm),
    key("supports", "\"none\", \"grid\" or \"tree\"", "", None, Fdm),
    // 0 supports every downward surface, 90 nothing.
    key(
        "support_overhang_angle",
        "overhang supported beyond this",
        "°",
        real(0.0, 90.0),
        Fdm,
    ),
    // PrusaSlicer's contact distance: 0.1 to 0.3 mm peels off well with PLA; 0 welds.
    key(
        "support_z_gap",
        "gap between support and part",
        "mm",
        real(0.0, 2.0),
        Fdm,
    ),
    key(
        "brim_width",
        "brim around the first layer",
        "mm",
        real(0.0, 50.0),
        Fdm,
    ),
    key(
        "raft_layers",
        "raft layers under the part",
        "",
        whole(0.0, 10.0),
        Fdm,
    ),
    // Cooling: PLA wants 5-15 s a layer; two minutes covers any material.
    key(
        "min_layer_time",
        "slow down below this layer time",
        "s",
        real(0.0, 120.0),
        Fdm,
    ),
    key(
        "slowdown_min_speed",
        "slowest speed cooling may use",
        "mm/s",
        real(1.0, 1000.0),
        Fdm,
    ),
    key(
        "fan_below_layer_time",
        "fan rises above min_fan_speed below this layer time",
        "s",
        real(0.0, 1000.0),
        Fdm,
    ),
    key(
        "min_fan_speed",
        "part fan on long layers",
        "",
        real(0.0, 1.0),
        Fdm,
    ),
    key(
        "fan_first_layers",
        "layers over which the fan ramps up (first layer off)",
        "",
        whole(0.0, 100.0),
        Fdm,
    ),
    // Travel: lifts of a few tenths clear a bumpy top; 10 mm is a generous ceiling.
    key(
        "z_hop",
        "lift on retracted travel",
        "mm",
        real(0.0, 10.0),
        Fdm,
    ),
    key(
        "wipe",
        "wipe the nozzle along the path on retraction (bool)",
        "",
        None,
        Fdm,
    ),
    key(
        "combing",
        "travel inside the part without retracting (bool)",
        "",
        None,
        Fdm,
    ),
    // The planner's limits (Marlin's M201/M204/M205 J): hobby printers accelerate at
    // 500-5000 mm/s²; junction deviation is 0.01-0.1 mm.
    key(
        "machine_max_acceleration_extruding",
        "acceleration while printing",
        "mm/s²",
        real(10.0, 100_000.0),
        Fdm,
    ),
    key(
        "machine_max_acceleration_travel",
        "acceleration on travel",
        "mm/s²",
        real(10.0, 100_000.0),
        Fdm,
    ),
    key(
        "junction_deviation",
        "Marlin's junction deviation",
        "mm",
        real(0.001, 1.0),
        Fdm,
    ),
    // Lead screws move Z at 5-25 mm/s.
    key(
        "machine_max_feedrate_z",
        "fastest Z move",
        "mm/s",
        real(0.5, 100.0),
        Fdm,
    ),
    key(
        "vase_mode",
        "one spiral outer wall, no top (bool)",
        "",
        None,
        Fdm,
    ),
    key(
        "copies",
        "copies arranged on the bed",
        "",
        whole(1.0, 100.0),
        Fdm,
    ),
    key("start_gcode", "start G-code template", "", None, Fdm),
    key("end_gcode", "end G-code template", "", None, Fdm),
    // Resin displays have pixels of about 20-80 µm.
    key(
        "pixel_size",
        "display pixel size",
        "mm",
        real(0.005, 1.0),
        Resin,
    ),
    // 12K displays are 11520 x 5120; one 16384 x 16384 layer is already 256 MB.
    key(
        "resolution",
        "layer image [width, height]",
        "px",
        whole(1.0, 16384.0),
        Resin,
    ),
    key(
        "exposure_time",
        "layer exposure",
        "s",
        real(0.1, 600.0),
        Resin,
    ),
    key(
        "first_exposure_time",
        "first layers' exposure",
        "s",
        real(0.1, 600.0),
        Resin,
    ),
    key(
        "faded_layers",
        "layers fading from first to normal exposure",
        "",
        whole(0.0, 200.0),
        Resin,
    ),
    // How the display shows the image (PrusaSlicer's names): the SL1 is portrait and
    // mirrored in x.
    key(
        "display_orientation",
        "\"portrait\" or \"landscape\"",
        "",
        None,
        Resin,
    ),
    key(
        "display_mirror_x",
        "image mirrored in x (bool)",
        "",
        None,
        Resin,
    ),
    key(
        "display_mirror_y",
        "image mirrored in y (bool)",
        "",
        None,
        Resin,
    ),
    key(
        "printer_model",
        "printer model written to SL1 (text)",
        "",
        None,
        Resin,
    ),
    key(
        "material_name",
        "resin name written to SL1 (text)",
        "",
        None,
        Resin,
    ),
];

/// The key's entry, if it is one.
pub fn spec(key: &str) -> Option<&'static KeySpec> {
    KEYS.iter().find(|s| s.key == key)
}

/// Every key's name.
pub fn names() -> Vec<&'static str> {
    KEYS.iter().map(|s| s.key).collect()
}

/// A known key close to `key` (a typo), if there is one.
pub fn suggestion(key: &str) -> Option<&'static str> {
    KEYS.iter()
        .map(|s| (strsim::levenshtein(key, s.key), s.key))
        .filter(|&(d, k)| d <= 3.min(k.len() / 3).max(1))
        .min_by_key(|&(d, _)| d)
        .map(|(_, k)| k)
}

/// The key list as Markdown table rows (key, unit, range, default): the source of the table
/// in `docs/profiles.md`, which a test keeps in step with [`KEYS`].
pub fn markdown_rows() -> Vec<String> {
    let fdm = super::Profile::default_fdm();
    let resin = super::Profile::default_resin();
    KEYS.iter()
        .map(|s| {
            let is_flag = matches!(
                fdm.raw(s.key).or(resin.raw(s.key)),
                Some(toml::Value::Boolean(_))
            );
            let range = match s.range {
                Some(r) => super::error::range_text(&r, ""),
                None if is_flag => "true or false".to_string(),
                None => "text".to_string(),
            };
            let show = |v: &toml::Value| match v {
                toml::Value::String(t) if t.contains('\n') => "(template)".to_string(),
                other => other.to_string(),
            };
            let default = match (fdm.raw(s.key), resin.raw(s.key)) {
                (Some(f), Some(r)) if f != r => format!("{}; resin {}", show(f), show(r)),
                (Some(v), _) | (None, Some(v)) => show(v),
                (None, None) => "—".to_string(),
            };
            let unit = if s.unit.is_empty() { "—" } else { s.unit };
            format!(
                "| `{}` | {} | {unit} | {range} | {default} |",
                s.key, s.meaning
            )
        })
        .collect()
}
