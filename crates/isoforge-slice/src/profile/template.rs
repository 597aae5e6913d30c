//! G-code templates: text with `{name}` placeholders that isoforge fills from the settings.
//! A placeholder isoforge does not know is an error when the profile is checked, so it can
//! never reach a printer as written.

use super::error::{ProfileError, ProfileErrorKind};
use super::settings::FdmSettings;

/// The placeholders a template may use.
pub const PLACEHOLDERS: [&str; 9] = [
    "nozzle_temperature",
    "bed_temperature",
    "layer_height",
    "first_layer_height",
    "bed_x",
    "bed_y",
    "max_height",
    "filament_diameter",
    "travel_speed",
];

/// A piece of a template.
enum Piece<'a> {
    Text(&'a str),
    /// A placeholder's name.
    Placeholder(&'a str),
}

/// The template in pieces; `Err(byte)` for a `{` that is never closed.
fn pieces(template: &str) -> impl Iterator<Item = Result<Piece<'_>, usize>> {
    let mut rest = 0;
    std::iter::from_fn(move || {
        if rest >= template.len() {
            return None;
        }
        let tail = &template[rest..];
        let Some(open) = tail.find('{') else {
            rest = template.len();
            return Some(Ok(Piece::Text(tail)));
        };
        if open > 0 {
            rest += open;
            return Some(Ok(Piece::Text(&tail[..open])));
        }
        let start = rest;
        match tail.find('}') {
            Some(close) => {
                rest += close + 1;
                Some(Ok(Piece::Placeholder(&tail[1..close])))
            }
            None => {
                rest = template.len();
                Some(Err(start))
            }
        }
    })
}

/// Checks that every placeholder of the template under `key` is one isoforge fills.
pub(crate) fn check(key: &'static str, template: &str) -> Result<(), ProfileError> {
    for piece in pieces(template) {
        match piece {
            Ok(Piece::Placeholder(name)) if !PLACEHOLDERS.contains(&name) => {
                return Err(ProfileErrorKind::UnknownPlaceholder {
                    key,
                    placeholder: name.to_string(),
                }
                .into());
            }
            Err(byte) => {
                return Err(ProfileErrorKind::UnclosedPlaceholder { key, byte }.into());
            }
            Ok(_) => {}
        }
    }
    Ok(())
}

/// The value a placeholder stands for.
fn value(name: &str, s: &FdmSettings) -> Option<f64> {
    Some(match name {
        "nozzle_temperature" => s.nozzle_temperature,
        "bed_temperature" => s.bed_temperature,
        "layer_height" => s.layer_height,
        "first_layer_height" => s.first_layer_height,
        "bed_x" => s.bed_size[0],
        "bed_y" => s.bed_size[1],
        "max_height" => s.max_height,
        "filament_diameter" => s.filament_diameter,
        // G-code feed rates are per minute.
        "travel_speed" => s.travel_speed * 60.0,
        _ => return None,
    })
}

/// Fills the template's placeholders from the settings. The settings are validated before
/// any G-code is written, so every placeholder is known; one that is not (settings built in
/// code and never validated) is left as written.
pub(crate) fn fill(template: &str, s: &FdmSettings) -> String {
    let mut out = String::with_capacity(template.len() + 32);
    for piece in pieces(template) {
        match piece {
            Ok(Piece::Text(t)) => out.push_str(t),
            Ok(Piece::Placeholder(name)) => match value(name, s) {
                Some(v) => out.push_str(&fmt_num(v)),
                None => {
                    out.push('{');
                    out.push_str(name);
                    out.push('}');
                }
            },
            Err(byte) => out.push_str(&template[byte..]),
        }
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
    fn every_placeholder_has_a_value() {
        let s = super::super::Profile::default_fdm().fdm().unwrap();
        for p in PLACEHOLDERS {
            assert!(value(p, &s).is_some(), "{p}");
        }
    }

    #[test]
    fn unknown_and_unclosed_placeholders_are_errors() {
        assert!(check("start_gcode", "M104 S{nozzle_temperature}\nG28").is_ok());
        let e = check("start_gcode", "M104 S{nozzle_temp}").unwrap_err();
        assert!(
            matches!(&e.kind, ProfileErrorKind::UnknownPlaceholder { key: "start_gcode", placeholder } if placeholder == "nozzle_temp"),
            "{e}"
        );
        let e = check("end_gcode", "G1 X0\nM104 S{bed").unwrap_err();
        assert!(
            matches!(
                e.kind,
                ProfileErrorKind::UnclosedPlaceholder {
                    key: "end_gcode",
                    byte: 12
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn filling_replaces_each_placeholder_once() {
        let s = super::super::Profile::default_fdm().fdm().unwrap();
        let out = fill(
            "M140 S{bed_temperature}\nG1 Y{bed_y} F{travel_speed} ; }",
            &s,
        );
        assert_eq!(out, "M140 S60\nG1 Y220 F9000 ; }");
    }
}
