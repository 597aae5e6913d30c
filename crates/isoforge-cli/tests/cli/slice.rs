//! End-to-end tests of `isoforge slice`: a model script and a mesh to G-code (judged by the
//! slicer's own G-code checker), SL1, SVX and PNG folders (judged by their entries and keys),
//! and bad input (clear error, no output left behind).

use std::io::Read;
use std::path::Path;

use crate::{fixtures, isoforge};
use isoforge_slice::check;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn torus() -> std::path::PathBuf {
    fixtures().join("slice/torus.rhai")
}

fn generic() -> std::path::PathBuf {
    fixtures().join("printers/generic_marlin_220.toml")
}

fn sl1_profile() -> std::path::PathBuf {
    fixtures().join("printers/prusa_sl1.toml")
}

fn zip_names(path: &Path) -> Vec<String> {
    let file = std::fs::File::open(path).expect("archive written");
    let mut archive = zip::ZipArchive::new(file).expect("a zip archive");
    (0..archive.len())
        .map(|i| {
            archive
                .by_index(i)
                .expect("entry")
                .name()
                .expect("entry name")
                .to_string()
        })
        .collect()
}

fn zip_text(path: &Path, name: &str) -> String {
    let file = std::fs::File::open(path).expect("archive written");
    let mut archive = zip::ZipArchive::new(file).expect("a zip archive");
    let mut text = String::new();
    archive
        .by_name(name)
        .expect("entry present")
        .read_to_string(&mut text)
        .expect("utf-8 entry");
    text
}

/// Runs `isoforge slice ... --json`, asserts it succeeded, and returns its JSON figures.
fn slice_json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["slice"];
    all.extend_from_slice(args);
    all.push("--json");
    let run = isoforge(&all);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    serde_json::from_slice(&run.stdout).expect("one JSON object on stdout")
}

#[test]
fn script_to_gcode_is_checked_layer_by_layer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("torus.gcode");
    let json = slice_json(&[
        s(&torus()),
        "--profile",
        s(&generic()),
        "--set",
        "layer_height=0.3",
        "--set",
        "first_layer_height=0.3",
        "-o",
        s(&out),
    ]);
    for key in [
        "layers",
        "seconds",
        "filament_mm",
        "estimated_print_seconds",
    ] {
        assert!(json.get(key).is_some(), "--json lacks {key}");
    }
    // The torus is 10 mm tall: 10 / 0.3 rounds to 33 or 34 layers.
    let layers = json["layers"].as_u64().unwrap();
    assert!((33..=34).contains(&layers), "{layers} layers");

    let text = std::fs::read_to_string(&out).unwrap();
    let report = check::parse(&text).expect("the checker reads our G-code");
    assert_eq!(report.layers.len() as u64, layers);
    // Z heights climb by one layer height.
    let zs: Vec<f64> = report.layers.iter().filter_map(|(_, z)| *z).collect();
    assert_eq!(zs.len() as u64, layers);
    for pair in zs.windows(2) {
        assert!(((pair[1] - pair[0]) - 0.3).abs() < 1e-6, "{pair:?}");
    }
    // Heated before the first extrusion, and nothing leaves the 220 x 220 bed.
    assert!(report.nozzle_before_first_extrusion.unwrap_or(0.0) > 150.0);
    assert!(report.waited_for_nozzle);
    assert!(report.min[0] >= 0.0 && report.min[1] >= 0.0);
    assert!(report.max[0] <= 220.0 && report.max[1] <= 220.0);
    assert!(report.filament_mm > 100.0);
}

#[test]
fn mesh_input_slices_like_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let stl = dir.path().join("torus.stl");
    let run = isoforge(&[
        "mesh",
        s(&torus()),
        "--depth",
        "7",
        "-o",
        s(&stl),
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut layers = Vec::new();
    for input in [torus(), stl.clone()] {
        let out = dir.path().join("out.gcode");
        let json = slice_json(&[s(&input), "--profile", s(&generic()), "-o", s(&out)]);
        layers.push(json["layers"].as_u64().unwrap());
        let report = check::parse(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert!(!report.extrusions.is_empty());
    }
    // The mesh's extent differs from the field's by under a cell, so at most one layer.
    assert!(
        layers[0].abs_diff(layers[1]) <= 1,
        "model and mesh give {layers:?} layers"
    );
}

#[test]
fn sl1_archive_has_the_entries_and_keys() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("torus.sl1");
    let json = slice_json(&[
        s(&torus()),
        "--profile",
        s(&sl1_profile()),
        "--set",
        "layer_height=0.5",
        "--sl1",
        s(&out),
    ]);
    let layers = json["layers"].as_u64().unwrap() as usize;
    assert!(layers >= 20, "{layers} layers");
    let names = zip_names(&out);
    assert!(names.iter().any(|n| n == "config.ini"));
    assert!(names.iter().any(|n| n == "prusaslicer.ini"));
    assert!(
        names
            .iter()
            .any(|n| n.starts_with("thumbnail/") && n.ends_with(".png"))
    );
    let config = zip_text(&out, "config.ini");
    let key = |k: &str| {
        config
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{k} = ")))
            .unwrap_or_else(|| panic!("config.ini lacks {k}"))
            .to_string()
    };
    for k in [
        "action",
        "expTime",
        "expTimeFirst",
        "layerHeight",
        "numFade",
        "numFast",
        "numSlow",
        "printTime",
        "usedMaterial",
        "printerModel",
    ] {
        key(k);
    }
    let job = key("jobDir");
    let pngs: Vec<_> = names
        .iter()
        .filter(|n| n.starts_with(&job) && n.ends_with(".png"))
        .collect();
    assert_eq!(pngs.len(), layers);
    assert!(names.contains(&format!("{job}00000.png")));
}

#[test]
fn svx_archive_has_a_manifest_and_slices() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("torus.svx");
    let json = slice_json(&[
        s(&torus()),
        "--profile",
        s(&sl1_profile()),
        "--set",
        "layer_height=0.5",
        "--svx",
        s(&out),
    ]);
    let layers = json["layers"].as_u64().unwrap() as usize;
    let names = zip_names(&out);
    let manifest = zip_text(&out, "manifest.xml");
    for key in [
        "gridSizeX",
        "gridSizeY",
        "gridSizeZ",
        "voxelSize",
        "subvoxelBits",
        "slicesOrientation",
        "DENSITY",
    ] {
        assert!(manifest.contains(key), "manifest lacks {key}");
    }
    let slices = names
        .iter()
        .filter(|n| n.starts_with("density/slice"))
        .count();
    assert_eq!(slices, layers);
    assert!(names.iter().any(|n| n == "density/slice0000.png"));
}

#[test]
fn png_dir_holds_one_png_per_layer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("layers");
    let json = slice_json(&[
        s(&torus()),
        "--profile",
        s(&sl1_profile()),
        "--set",
        "layer_height=1",
        "--png-dir",
        s(&out),
    ]);
    let layers = json["layers"].as_u64().unwrap() as usize;
    let mut names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names.len(), layers);
    assert_eq!(names[0], "00000.png");
    let png = std::fs::read(out.join("00000.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.gcode");
    let bad_profile = dir.path().join("bad.toml");
    let generic_text = std::fs::read_to_string(generic()).unwrap();
    let negative: String = generic_text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("layer_height") {
                "layer_height = -0.2".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&bad_profile, negative).unwrap();
    let cases: Vec<(Vec<String>, &str, i32)> = vec![
        // A negative value in a profile names the key.
        (
            vec!["--profile".into(), s(&bad_profile).into()],
            "layer_height",
            1,
        ),
        // A negative override names the key; a flag value out of range is a usage error.
        (
            vec!["--set".into(), "line_width=-1".into()],
            "line_width",
            2,
        ),
        // An unknown key is refused, not ignored: a mistake in the call.
        (
            vec!["--set".into(), "no_such_key=1".into()],
            "no_such_key",
            2,
        ),
        // A model larger than the bed.
        (
            vec![
                "--param".into(),
                "R=100".into(),
                "--param".into(),
                "r=12".into(),
            ],
            "bed",
            1,
        ),
    ];
    for (extra, word, code) in cases {
        let mut args = vec!["slice".to_string(), s(&torus()).to_string()];
        args.extend(extra.iter().cloned());
        args.extend(["-o".to_string(), s(&out).to_string()]);
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        let run = isoforge(&refs);
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(code), "{extra:?}: {err}");
        assert!(
            err.contains(word),
            "{extra:?}: message {err:?} lacks {word:?}"
        );
        assert!(!out.exists(), "{extra:?} left a file");
    }
    // An open mesh: a clear message, not a G-code file of garbage.
    let open = fixtures().join("meshes/open_box.stl");
    let run = isoforge(&["slice", s(&open), "-o", s(&out)]);
    let err = String::from_utf8_lossy(&run.stderr);
    if run.status.success() {
        assert!(err.contains("open") || err.contains("warning"), "{err}");
    } else {
        assert!(err.contains("open"), "{err}");
        assert!(!out.exists());
    }
}

/// Runs `isoforge slice` of the torus to G-code with extra arguments; returns the exit code
/// and stderr, and checks that no output was written.
fn refused(extra: &[&str], dir: &Path) -> (Option<i32>, String) {
    let out = dir.join("out.gcode");
    let model = torus();
    let mut args = vec!["slice", s(&model)];
    args.extend_from_slice(extra);
    args.extend(["-o", s(&out)]);
    let run = isoforge(&args);
    let err = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(!out.exists(), "{extra:?} wrote a file: {err}");
    assert!(!err.contains("panicked"), "{extra:?}: {err}");
    (run.status.code(), err)
}

#[test]
fn profile_values_out_of_their_physical_range_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    // Each of these once wrote G-code: E inf, F0, a molten nozzle, a 1e308 mm retraction.
    for (set, range) in [
        ("filament_diameter=1e-200", "from 1 to 3.5 mm"),
        ("print_speed=1e-300", "from 1 to 1000 mm/s"),
        ("nozzle_temperature=1000", "from 0 to 400 °C"),
        ("bed_temperature=300", "from 0 to 150 °C"),
        ("retract_length=1e308", "from 0 to 20 mm"),
        ("layer_height=1e-9", "from 0.01 to 2 mm"),
        ("perimeters=1000000", "a whole number from 0 to 20"),
    ] {
        let (code, err) = refused(&["--set", set], dir.path());
        // A flag value out of range is a usage error, as `mesh --depth 40` is.
        assert_eq!(code, Some(2), "{set}: {err}");
        let key = set.split('=').next().unwrap();
        assert!(
            err.contains(&format!("--set {set}")) && err.contains(&format!("`{key}`")),
            "{set}: {err}"
        );
        assert!(err.contains(range), "{set}: {err} lacks {range:?}");
    }
}

#[test]
fn bad_profile_files_name_the_file_line_key_and_range() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(generic()).unwrap();
    let line_of = |key: &str| {
        text.lines()
            .position(|l| l.starts_with(&format!("{key} ")))
            .unwrap()
            + 1
    };
    let with = |key: &str, line: &str| -> String {
        text.lines()
            .map(|l| {
                if l.starts_with(&format!("{key} ")) {
                    line.to_string()
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    let cases = [
        (
            "nozzle_temperature",
            "nozzle_temperature = 1000",
            "from 0 to 400 °C",
        ),
        ("technology", "technology = \"laser\"", "laser"),
        (
            "perimeters",
            "perimeters = 1000000",
            "a whole number from 0 to 20",
        ),
    ];
    for (key, line, words) in cases {
        let path = dir.path().join(format!("{key}.toml"));
        std::fs::write(&path, with(key, line)).unwrap();
        let (code, err) = refused(&["--profile", s(&path)], dir.path());
        assert_eq!(code, Some(1), "{line}: {err}");
        let at = format!("{}:{}", path.display(), line_of(key));
        assert!(err.contains(&at), "{line}: {err} lacks {at}");
        assert!(
            err.contains(&format!("`{key}`")) && err.contains(words),
            "{line}: {err}"
        );
    }
    // An unknown placeholder in a template would reach the printer as written.
    let path = dir.path().join("placeholder.toml");
    std::fs::write(
        &path,
        text.replace("M109 S{nozzle_temperature}", "M109 S{nozzle_temp}"),
    )
    .unwrap();
    let (code, err) = refused(&["--profile", s(&path)], dir.path());
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("{nozzle_temp}") && err.contains("start_gcode"),
        "{err}"
    );
    // A typo of a key gets a suggestion.
    let path = dir.path().join("typo.toml");
    std::fs::write(&path, format!("{text}\nlayr_height = 0.2\n")).unwrap();
    let (code, err) = refused(&["--profile", s(&path)], dir.path());
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("did you mean `layer_height`"), "{err}");
}

#[test]
fn malformed_overrides_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    for set in ["layer_height", "=0.2", "layr_height=0.2"] {
        let (code, err) = refused(&["--set", set], dir.path());
        assert_eq!(code, Some(2), "{set}: {err}");
        assert!(err.contains(&format!("--set {set}")), "{set}: {err}");
    }
}

#[test]
fn several_models_share_the_bed_and_copies_multiply_them() {
    let dir = tempfile::tempdir().unwrap();
    let cube = fixtures().join("slice/cube.rhai");
    let pins = fixtures().join("slice/pins.rhai");
    let one = dir.path().join("one.gcode");
    let two = dir.path().join("two.gcode");
    let four = dir.path().join("four.gcode");
    let a = slice_json(&[s(&cube), "-o", s(&one)]);
    let b = slice_json(&[s(&cube), s(&pins), "-o", s(&two)]);
    let c = slice_json(&[s(&cube), "--set", "copies=4", "-o", s(&four)]);
    // The plate is as tall as its tallest object (the cube: 20 mm in 0.2 mm layers).
    assert_eq!(a["layers"].as_u64(), Some(100));
    assert_eq!(b["layers"].as_u64(), Some(100));
    let f = |v: &serde_json::Value| v["filament_mm"].as_f64().unwrap();
    // The pins add filament; four cubes take about four times one (one skirt around all).
    assert!(f(&b) > f(&a) * 1.02, "{} vs {}", f(&b), f(&a));
    assert!((f(&c) / f(&a) - 4.0).abs() < 0.2, "{} vs {}", f(&c), f(&a));
    // The copies stand apart: the part's extrusions fill four separate squares.
    let r = check::parse(&std::fs::read_to_string(&four).unwrap()).unwrap();
    let (w, h) = (r.max[0] - r.min[0], r.max[1] - r.min[1]);
    assert!(w > 40.0 && h > 40.0, "{w} x {h}");
    // Layer images take one model.
    let run = isoforge(&[
        "slice",
        s(&cube),
        s(&pins),
        "--png-dir",
        s(&dir.path().join("png")),
    ]);
    assert_eq!(run.status.code(), Some(2));
}

#[test]
fn preview_layers_draws_the_chosen_layers_in_colour() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bridge.gcode");
    let pictures = dir.path().join("pictures");
    slice_json(&[
        s(&fixtures().join("slice/bridge.rhai")),
        "-o",
        s(&out),
        "--preview-layers",
        s(&pictures),
        "--preview-at",
        "0,50",
    ]);
    let mut names: Vec<_> = std::fs::read_dir(&pictures)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["layer-00000.png", "layer-00050.png"]);
    // Layer 50 is the deck's first layer: bridge lines in their own colour.
    let bridge = isoforge_slice::preview::colour("BRIDGE");
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(pictures.join("layer-00050.png")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let px = info.color_type.samples();
    let bridged = buf[..info.buffer_size()]
        .chunks(px)
        .filter(|p| p[..3] == bridge)
        .count();
    assert!(bridged > 1000, "{bridged} bridge-coloured pixels");
    // A layer the print does not have is a usage error.
    let run = isoforge(&[
        "slice",
        s(&fixtures().join("slice/bridge.rhai")),
        "-o",
        s(&dir.path().join("b.gcode")),
        "--preview-layers",
        s(&dir.path().join("p2")),
        "--preview-at",
        "999",
    ]);
    assert_eq!(run.status.code(), Some(2));
}

/// A grayscale PNG's pixels and size.
fn gray_png(bytes: &[u8]) -> (Vec<u8>, u32, u32) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    buf.truncate(info.buffer_size());
    (buf, info.width, info.height)
}

#[test]
fn sl1_images_match_prusaslicers_own_pixel_for_pixel() {
    // PrusaSlicer's layer 10 of the letter F on the SL1 (tools/sl1-reference.sh made it).
    let reference = std::fs::read(fixtures().join("slice/letter_f_prusa_sl1_layer10.png")).unwrap();
    let (want, w, h) = gray_png(&reference);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.sl1");
    slice_json(&[
        s(&fixtures().join("slice/letter_f.rhai")),
        "--profile",
        s(&sl1_profile()),
        "--sl1",
        s(&out),
    ]);
    let file = std::fs::File::open(&out).unwrap();
    let mut archive = zip::ZipArchive::new(file).unwrap();
    let mut ours = Vec::new();
    archive
        .by_name("f00010.png")
        .unwrap()
        .read_to_end(&mut ours)
        .unwrap();
    let (got, gw, gh) = gray_png(&ours);
    assert_eq!((gw, gh), (w, h));
    assert_eq!((w, h), (1440, 2560));
    // Equal but for anti-aliasing: no pixel off by half the range or more, and edge
    // pixels only (a few per mm of the F's 84 mm outline).
    let off = |a: &[u8], b: &[u8]| {
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap_or(0);
        let edge = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.abs_diff(**y) > 16)
            .count();
        (worst, edge)
    };
    let (worst, edge) = off(&want, &got);
    assert!(worst < 128, "a pixel differs by {worst}");
    assert!(edge < 84 * 2 * 21, "{edge} pixels differ");
    // The judge sees a mirror: the same image flipped left to right is far off.
    let flipped: Vec<u8> = got
        .chunks(w as usize)
        .flat_map(|row| row.iter().rev().copied())
        .collect();
    assert!(off(&want, &flipped).0 == 255);
    let config = zip_text(&out, "prusaslicer.ini");
    for line in [
        "display_orientation = portrait",
        "display_mirror_x = 1",
        "display_pixels_x = 2560",
    ] {
        assert!(config.contains(line), "{config}");
    }
}

#[test]
fn sl1_first_layer_has_its_own_height_as_prusaslicer_counts_it() {
    // The letter F is 2 mm tall: PrusaSlicer 2.5 writes 39 layers for a 0.1 mm first layer
    // and 0.05 mm after it (and 40 when all are 0.05 mm).
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.sl1");
    let json = slice_json(&[
        s(&fixtures().join("slice/letter_f.rhai")),
        "--profile",
        s(&sl1_profile()),
        "--set",
        "first_layer_height=0.1",
        "--sl1",
        s(&out),
    ]);
    assert_eq!(json["layers"].as_u64(), Some(39));
    let pngs = zip_names(&out)
        .iter()
        .filter(|n| n.starts_with("f0") && n.ends_with(".png"))
        .count();
    assert_eq!(pngs, 39);
    assert!(zip_text(&out, "prusaslicer.ini").contains("initial_layer_height = 0.1"));
}
