//! `isoforge render` end to end: a PNG of the right size that shows something, and no
//! file at all when the model or the arguments are bad.

use crate::{fixtures, isoforge};

/// Decodes a PNG into (width, height, RGB bytes).
fn decode(path: &std::path::Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

#[test]
fn renders_a_classic_model_in_every_view() {
    let dir = tempfile::tempdir().unwrap();
    let model = fixtures().join("classic/heart.rhai");
    let mut pictures: Vec<(&str, Vec<u8>)> = Vec::new();
    for view in ["iso", "top", "front", "right"] {
        let out = dir.path().join(format!("heart_{view}.png"));
        let run = isoforge(&[
            "render",
            &model.display().to_string(),
            "-o",
            &out.display().to_string(),
            "--size",
            "96x64",
            "--view",
            view,
            "--quiet",
        ]);
        assert_eq!(
            run.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let (w, h, rgb) = decode(&out);
        assert_eq!((w, h), (96, 64));
        let background = &rgb[..3];
        let surface = rgb.chunks_exact(3).filter(|p| *p != background).count();
        // The heart fills a good part of its region, and is shaded (many tones).
        assert!(surface > 96 * 64 / 20, "{view}: {surface} surface pixels");
        let mut tones: Vec<&[u8]> = rgb.chunks_exact(3).collect();
        tones.sort();
        tones.dedup();
        assert!(tones.len() > 20, "{view}: only {} colours", tones.len());
        pictures.push((view, rgb));
    }
    // Each view is its own picture: were --view ignored, all four would be one.
    for (i, (a, pa)) in pictures.iter().enumerate() {
        for (b, pb) in &pictures[i + 1..] {
            let differ = pa
                .chunks_exact(3)
                .zip(pb.chunks_exact(3))
                .filter(|(p, q)| p != q);
            assert!(differ.count() > 96 * 64 / 20, "{a} and {b} look alike");
        }
    }
}

/// The silhouette's bounding box in pixels: (width, height) of what is not background.
fn silhouette(w: u32, h: u32, rgb: &[u8]) -> (u32, u32) {
    let background = &rgb[..3];
    let (mut x0, mut x1, mut y0, mut y1) = (w, 0, h, 0);
    for y in 0..h {
        for x in 0..w {
            let k = ((y * w + x) * 3) as usize;
            if &rgb[k..k + 3] != background {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    assert!(x1 >= x0 && y1 >= y0, "nothing drawn");
    (x1 - x0 + 1, y1 - y0 + 1)
}

#[test]
fn each_view_looks_along_its_own_axis() {
    // A 3 x 2 x 1 box: from the top it is 3 wide and 2 high, from the front 3 by 1, from
    // the right 2 by 1. The pictures are orthographic with square pixels, so the
    // silhouette's proportions say which way the camera looked.
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("box.rhai");
    std::fs::write(&model, "bounds([-2, -2, -2], [2, 2, 2]);\nPrism(3, 2, 1)\n").unwrap();
    for (view, want) in [("top", 1.5), ("front", 3.0), ("right", 2.0)] {
        let out = dir.path().join(format!("{view}.png"));
        let run = isoforge(&[
            "render",
            &model.display().to_string(),
            "-o",
            &out.display().to_string(),
            "--size",
            "120x120",
            "--view",
            view,
            "--quiet",
        ]);
        assert_eq!(
            run.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let (w, h, rgb) = decode(&out);
        let (sw, sh) = silhouette(w, h, &rgb);
        let ratio = f64::from(sw) / f64::from(sh);
        assert!(
            (ratio - want).abs() < 0.1 * want,
            "{view}: silhouette {sw} x {sh} px, ratio {ratio:.2}, want {want}"
        );
    }
}

#[test]
fn json_reports_the_picture() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.png");
    let run = isoforge(&[
        "render",
        &fixtures().join("classic/heart.rhai").display().to_string(),
        "-o",
        &out.display().to_string(),
        "--size",
        "40x30",
        "--depth",
        "8",
        "--json",
    ]);
    assert_eq!(run.status.code(), Some(0));
    let j: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(
        (j["width"].as_u64(), j["height"].as_u64()),
        (Some(40), Some(30))
    );
    assert_eq!(j["view"], "iso");
}

#[test]
fn bad_input_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("never.png");
    let script = dir.path().join("broken.rhai");
    std::fs::write(&script, "let a = ;\n").unwrap();
    let run = isoforge(&[
        "render",
        &script.display().to_string(),
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("broken.rhai"));
    assert!(!out.exists());

    let heart = fixtures().join("classic/heart.rhai").display().to_string();
    for bad in [
        ["--size", "0x10"],
        ["--size", "big"],
        ["--view", "sideways"],
        ["--depth", "99"],
    ] {
        let run = isoforge(&[
            "render",
            &heart,
            "-o",
            &out.display().to_string(),
            bad[0],
            bad[1],
        ]);
        assert_eq!(run.status.code(), Some(2), "{bad:?}");
        assert!(!out.exists());
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary left behind"
    );
}
