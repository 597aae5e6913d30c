//! Profiles: the built-in and fixture profiles are valid, every kind of bad value is refused
//! with an error that names the key, the value, the range and where it came from, and no
//! bytes make the parser panic.

use std::path::Path;

use proptest::prelude::*;

use super::*;

const GENERIC: &str = include_str!("../../../../fixtures/printers/generic_marlin_220.toml");

/// The generic profile with one line replaced (or removed, for an empty `with`).
fn edited(key: &str, with: &str) -> String {
    GENERIC
        .lines()
        .map(|l| {
            if l.starts_with(&format!("{key} ")) {
                with.to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn fdm_error(text: &str) -> ProfileError {
    match Profile::parse(text, "my.toml").and_then(|p| p.fdm()) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e,
    }
}

fn set_error(assignments: &[&str]) -> ProfileError {
    let mut p = Profile::default_fdm();
    for a in assignments {
        if let Err(e) = p.set(a) {
            return e;
        }
    }
    match p.fdm() {
        Ok(_) => panic!("{assignments:?}: expected an error"),
        Err(e) => e,
    }
}

fn out_of_range(e: &ProfileError) -> Option<(&'static str, f64)> {
    match e.kind {
        ProfileErrorKind::OutOfRange { spec, value } => Some((spec.key, value)),
        _ => None,
    }
}

#[test]
fn builtin_profiles_are_complete_and_valid() {
    let f = Profile::default_fdm().fdm().unwrap();
    assert_eq!(f.bed_size, [220.0, 220.0]);
    let r = Profile::default_resin().resin().unwrap();
    assert_eq!(r.resolution, [1440, 2560]);
}

#[test]
fn the_fixture_profiles_are_complete_and_valid() {
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
fn every_settings_field_is_a_key_in_the_table_with_a_range_if_numeric() {
    let fdm = toml::Table::try_from(Profile::default_fdm().fdm().unwrap()).unwrap();
    let resin = toml::Table::try_from(Profile::default_resin().resin().unwrap()).unwrap();
    for (table, technology) in [(&fdm, Technology::Fdm), (&resin, Technology::Resin)] {
        for (key, value) in table {
            let spec = keys::spec(key).unwrap_or_else(|| panic!("{key} is not in KEYS"));
            assert!(spec.used_by.includes(technology), "{key}");
            let numeric = match value {
                toml::Value::Array(a) => a.iter().all(|v| v.is_integer() || v.is_float()),
                v => v.is_integer() || v.is_float(),
            };
            assert_eq!(numeric, spec.range.is_some(), "{key}: range iff numeric");
        }
    }
    for spec in keys::KEYS {
        let used = fdm.contains_key(spec.key) || resin.contains_key(spec.key);
        assert_eq!(
            used,
            spec.used_by != UsedBy::Profile,
            "{}: in the table but in no settings",
            spec.key
        );
    }
}

#[test]
fn a_missing_key_is_named_with_the_file() {
    let e = fdm_error(&edited("line_width", ""));
    assert!(
        matches!(e.kind, ProfileErrorKind::Missing { spec } if spec.key == "line_width"),
        "{e}"
    );
    assert_eq!(
        e.origin,
        Some(Origin::File {
            path: "my.toml".into(),
            line: None
        })
    );
    assert!(e.to_string().contains("`line_width`"), "{e}");
}

#[test]
fn out_of_range_values_name_key_value_range_and_line() {
    let e = fdm_error(&edited("nozzle_temperature", "nozzle_temperature = 1000"));
    assert_eq!(
        out_of_range(&e),
        Some(("nozzle_temperature", 1000.0)),
        "{e}"
    );
    let line = GENERIC
        .lines()
        .position(|l| l.starts_with("nozzle_temperature"))
        .unwrap()
        + 1;
    assert_eq!(
        e.origin,
        Some(Origin::File {
            path: "my.toml".into(),
            line: Some(line)
        })
    );
    let msg = e.to_string();
    assert!(msg.starts_with(&format!("my.toml:{line}: ")), "{msg}");
    assert!(
        msg.contains("1000 °C") && msg.contains("from 0 to 400 °C"),
        "{msg}"
    );
}

#[test]
fn the_issue_cases_are_refused() {
    // Each once wrote nonsense G-code: E inf, F0, a molten nozzle, a 1e308 retraction.
    for (set, key) in [
        ("filament_diameter=1e-200", "filament_diameter"),
        ("print_speed=1e-300", "print_speed"),
        ("nozzle_temperature=1000", "nozzle_temperature"),
        ("bed_temperature=200", "bed_temperature"),
        ("retract_length=1e308", "retract_length"),
        ("layer_height=1e-9", "layer_height"),
        ("retract_length=-1", "retract_length"),
        ("travel_speed=nan", "travel_speed"),
        ("fan_speed=inf", "fan_speed"),
        ("bed_size=[220, 0]", "bed_size"),
    ] {
        let e = set_error(&[set]);
        assert_eq!(out_of_range(&e).map(|o| o.0), Some(key), "{set}: {e}");
        assert_eq!(
            e.origin,
            Some(Origin::Override {
                assignment: set.into()
            }),
            "{set}"
        );
    }
}

#[test]
fn counts_are_whole_numbers_in_a_range() {
    for v in ["1000000", "-1", "2.5"] {
        let e = set_error(&[&format!("perimeters={v}")]);
        assert_eq!(
            out_of_range(&e).map(|o| o.0),
            Some("perimeters"),
            "{v}: {e}"
        );
        assert!(e.to_string().contains("a whole number from 0 to 20"), "{e}");
    }
    // A whole number written with a point is still a count.
    let mut p = Profile::default_fdm();
    p.set("perimeters=3.0").unwrap();
    assert_eq!(p.fdm().unwrap().perimeters, 3);
}

#[test]
fn keys_that_depend_on_each_other_are_checked() {
    let e = set_error(&["layer_height=0.5"]);
    assert!(
        matches!(e.kind, ProfileErrorKind::Conflict { key: "layer_height", value, .. } if value == 0.5),
        "{e}"
    );
    assert!(e.to_string().contains("nozzle_diameter"), "{e}");
    let e = set_error(&["line_width=2"]);
    assert!(
        matches!(
            e.kind,
            ProfileErrorKind::Conflict {
                key: "line_width",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn technology_is_fdm_or_resin() {
    let e = fdm_error(&edited("technology", "technology = \"laser\""));
    assert!(
        matches!(&e.kind, ProfileErrorKind::Invalid { key, .. } if key == "technology"),
        "{e}"
    );
    assert!(e.to_string().contains("laser"), "{e}");
    let e = Profile::default_resin().fdm().unwrap_err();
    assert!(
        matches!(
            e.kind,
            ProfileErrorKind::WrongTechnology {
                wanted: Technology::Fdm,
                found: Technology::Resin
            }
        ),
        "{e}"
    );
    // A resin key in a filament profile is a mistake, not silently ignored.
    let e = set_error(&["pixel_size=0.05"]);
    assert!(
        matches!(&e.kind, ProfileErrorKind::OtherTechnology { key, .. } if key == "pixel_size"),
        "{e}"
    );
}

#[test]
fn unknown_keys_are_named_with_a_suggestion() {
    let e = fdm_error(&format!("{GENERIC}\nlayr_height = 0.2\n"));
    assert!(
        matches!(&e.kind, ProfileErrorKind::UnknownKey { key, suggestion: Some("layer_height") } if key == "layr_height"),
        "{e}"
    );
    assert!(matches!(e.origin, Some(Origin::File { line: Some(_), .. })));
    let e = set_error(&["no_such_key=1"]);
    assert!(
        matches!(&e.kind, ProfileErrorKind::UnknownKey { key, .. } if key == "no_such_key"),
        "{e}"
    );
}

#[test]
fn unknown_placeholders_are_refused() {
    let e = set_error(&["start_gcode=M104 S{nozzle_temp}\\nG28"]);
    assert!(
        matches!(&e.kind, ProfileErrorKind::UnknownPlaceholder { key: "start_gcode", placeholder } if placeholder == "nozzle_temp"),
        "{e}"
    );
}

#[test]
fn set_overrides_and_parses_values() {
    let mut p = Profile::default_fdm();
    p.set("layer_height=0.1").unwrap();
    p.set("infill_pattern=gyroid").unwrap();
    p.set("bed_size=200,180").unwrap();
    p.set("start_gcode=G28\\nM83").unwrap();
    let s = p.fdm().unwrap();
    assert_eq!(s.layer_height, 0.1);
    assert_eq!(s.infill_pattern, InfillPattern::Gyroid);
    assert_eq!(s.bed_size, [200.0, 180.0]);
    assert_eq!(s.start_gcode, "G28\nM83");
    let e = p.set("novalue").unwrap_err();
    assert!(matches!(e.kind, ProfileErrorKind::OverrideSyntax), "{e}");
    let e = p.set("=3").unwrap_err();
    assert!(matches!(e.kind, ProfileErrorKind::OverrideSyntax), "{e}");
    let e = set_error(&["infill_pattern=zigzag"]);
    assert!(
        matches!(&e.kind, ProfileErrorKind::Invalid { key, .. } if key == "infill_pattern"),
        "{e}"
    );
    let mut r = Profile::default_resin();
    r.set("resolution=1620x2560").unwrap();
    assert_eq!(r.resin().unwrap().resolution, [1620, 2560]);
}

#[test]
fn bad_toml_says_where() {
    let e = Profile::parse("layer_height = 0.2\nnozzle = = 2\n", "x.toml").unwrap_err();
    assert!(matches!(e.kind, ProfileErrorKind::Toml(_)), "{e}");
    assert_eq!(
        e.origin,
        Some(Origin::File {
            path: "x.toml".into(),
            line: Some(2)
        })
    );
}

#[test]
#[ignore = "prints the key table for docs/profiles.md"]
fn print_the_docs_table() {
    for row in keys::markdown_rows() {
        println!("{row}");
    }
}

#[test]
fn the_docs_list_every_key_with_its_range() {
    let docs = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/profiles.md"
    ))
    .expect("docs/profiles.md");
    for row in keys::markdown_rows() {
        assert!(
            docs.lines().any(|l| l == row),
            "docs/profiles.md lacks the row:\n{row}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Random bytes: an error or a profile, never a panic.
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(p) = Profile::parse(&text, "r.toml") {
            let _ = p.fdm();
            let _ = p.resin();
        }
    }

    /// The generic profile with bytes changed: an error, or settings that pass validation.
    #[test]
    fn mutated_profiles_give_errors_or_valid_settings(
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)
    ) {
        let mut bytes = GENERIC.as_bytes().to_vec();
        for (at, b) in edits {
            let i = at.index(bytes.len());
            bytes[i] = b;
        }
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(s) = Profile::parse(&text, "m.toml").and_then(|p| p.fdm()) {
            prop_assert!(s.validate().is_ok());
            prop_assert!(s.filament_area() > 0.0 && s.print_speed >= 1.0);
        }
    }

    /// Any override: an error, or settings that pass validation.
    #[test]
    fn any_override_gives_an_error_or_valid_settings(
        key in prop::sample::select(keys::names()),
        value in prop_oneof![
            any::<f64>().prop_map(|v| v.to_string()),
            any::<i64>().prop_map(|v| v.to_string()),
            "[a-z0-9.,x{}\\[\\] -]{0,12}",
        ],
    ) {
        let mut p = Profile::default_fdm();
        if p.set(&format!("{key}={value}")).is_ok()
            && let Ok(s) = p.fdm()
        {
            prop_assert!(s.validate().is_ok());
        }
    }
}
