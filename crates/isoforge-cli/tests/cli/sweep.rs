//! Parameter ranges end to end: `render --param t=0..1:N --frames DIR --gif FILE` and
//! `mesh --param t=0..1:N`, on the lava lamp (whose balls rise with t and wrap round, so
//! t = 0 and t = 1 are the same picture and the same mesh, and t = 0.5 differs).

use std::path::Path;

use image::AnimationDecoder as _;

use crate::{fixtures, isoforge};

fn lamp() -> String {
    fixtures()
        .join("modern/lava_lamp.rhai")
        .display()
        .to_string()
}

fn ok(out: &std::process::Output) {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The RGB bytes of a PNG, with its size.
fn png_rgb(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut reader = png::Decoder::new(file).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn render_writes_numbered_frames_and_a_looping_gif() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("frames");
    let gif = dir.path().join("lamp.gif");
    let run = isoforge(&[
        "render",
        &lamp(),
        "--param",
        "t=0..1:3",
        "--frames",
        &frames.display().to_string(),
        "--gif",
        &gif.display().to_string(),
        "--fps",
        "5",
        "--size",
        "48x64",
        "--json",
    ]);
    ok(&run);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(report["frames"], 3);
    assert_eq!(report["values"], serde_json::json!([0.0, 0.5, 1.0]));

    let mut names: Vec<String> = std::fs::read_dir(&frames)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["000.png", "001.png", "002.png"]);
    let pictures: Vec<_> = names.iter().map(|n| png_rgb(&frames.join(n))).collect();
    for (w, h, rgb) in &pictures {
        assert_eq!((*w, *h), (48, 64));
        let background = &rgb[..3];
        assert!(
            rgb.chunks_exact(3).any(|p| p != background),
            "a blank frame"
        );
    }
    // t moves the balls: the middle frame differs; t = 0 and t = 1 are one picture.
    assert_ne!(pictures[0].2, pictures[1].2, "t did not change the picture");
    assert_eq!(pictures[0].2, pictures[2].2);

    // The GIF: three frames of the size asked, shown 200 ms each, colours near the PNGs'.
    let file = std::io::BufReader::new(std::fs::File::open(&gif).unwrap());
    let decoder = image::codecs::gif::GifDecoder::new(file).unwrap();
    let gif_frames: Vec<_> = decoder.into_frames().collect::<Result<_, _>>().unwrap();
    assert_eq!(gif_frames.len(), 3);
    for (f, (_, _, rgb)) in gif_frames.iter().zip(&pictures) {
        assert_eq!(f.buffer().dimensions(), (48, 64));
        assert_eq!(f.delay().numer_denom_ms(), (200, 1));
        let far = f
            .buffer()
            .pixels()
            .zip(rgb.chunks_exact(3))
            .filter(|(g, p)| (0..3).any(|k| (g.0[k] as i32 - p[k] as i32).abs() > 24))
            .count();
        assert!(far < 48 * 64 / 20, "{far} GIF pixels far from the PNG's");
    }
}

#[test]
fn mesh_writes_one_closed_mesh_per_step() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lamp.stl");
    let run = isoforge(&[
        "mesh",
        &lamp(),
        "--param",
        "t=0..1:3",
        "--depth",
        "5",
        "-o",
        &out.display().to_string(),
        "--json",
    ]);
    ok(&run);
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(report["parameter"], "t");
    let steps = report["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 3);
    let mut volumes = Vec::new();
    for (i, step) in steps.iter().enumerate() {
        let file = dir.path().join(format!("lamp-00{i}.stl"));
        assert_eq!(step["file"], file.display().to_string());
        assert_eq!(step["value"], [0.0, 0.5, 1.0][i]);
        // The file on disk is closed and manifold by `isoforge check` too.
        let check = isoforge(&["check", &file.display().to_string(), "--json"]);
        ok(&check);
        let checked: serde_json::Value = serde_json::from_slice(&check.stdout).unwrap();
        // The two sum the same triangles around different points (the region's centre, the
        // vertices' box's centre), so they may part in the last bits, no more.
        let (meshed, read) = (
            step["volume"].as_f64().unwrap(),
            checked["volume"].as_f64().unwrap(),
        );
        assert!(
            (meshed - read).abs() <= 1e-12 * meshed.abs(),
            "{meshed} vs {read}"
        );
        volumes.push(meshed);
    }
    assert!(!out.exists(), "the unnumbered file was written too");
    assert_eq!(volumes[0], volumes[2]);
    assert!((volumes[0] - volumes[1]).abs() > 1.0, "{volumes:?}");
}

#[test]
fn ranges_are_refused_where_they_mean_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let frames = dir.path().join("f").display().to_string();
    let cases: [&[&str]; 6] = [
        // A range needs somewhere to put the frames; frames need a range.
        &["render", &lamp(), "--param", "t=0..1:3"],
        &["render", &lamp(), "--frames", &frames],
        // -o names one picture.
        &[
            "render",
            &lamp(),
            "--param",
            "t=0..1:3",
            "--frames",
            &frames,
            "-o",
            "x.png",
        ],
        // Commands that make one thing.
        &["info", &lamp(), "--param", "t=0..1:3"],
        // Malformed or doubled ranges.
        &["mesh", &lamp(), "--param", "t=0..1"],
        &[
            "mesh",
            &lamp(),
            "--param",
            "t=0..1:3",
            "--param",
            "t=0..1:4",
        ],
    ];
    for args in cases {
        let out = isoforge(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("--"), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn a_frame_that_fails_leaves_no_frames_and_no_gif() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("breaks.rhai");
    std::fs::write(
        &model,
        "let t = param(\"t\", 0, 0, 1);\nif t > 0.6 { throw \"t too large\" }\nsphere(1 + t)",
    )
    .unwrap();
    let frames = dir.path().join("frames");
    let gif = dir.path().join("a.gif");
    let run = isoforge(&[
        "render",
        &model.display().to_string(),
        "--param",
        "t=0..1:3",
        "--frames",
        &frames.display().to_string(),
        "--gif",
        &gif.display().to_string(),
        "--size",
        "16x16",
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    // The third frame (t = 1) names itself and the script's line.
    assert!(err.contains("frame 2 (t=1)"), "{err}");
    assert!(err.contains("breaks.rhai:2:"), "{err}");
    assert!(!frames.exists() && !gif.exists(), "partial output left");
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "{left:?}");
}
