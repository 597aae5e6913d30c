//! Every fixture script loads, has something inside its region, and (where its region is
//! meant to enclose it) is outside at the region's corners.

use std::path::{Path, PathBuf};

use isoforge_field::find_bounds;
use isoforge_field::{Bounds, PointEval, Tape};
use isoforge_script::load_file;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

fn scripts(folder: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(fixtures().join(folder))
        .expect("fixture folder exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "rhai" || e == "vm"))
        .collect();
    files.sort();
    files
}

/// The grid points of `b`, `n` per axis, corners included.
fn grid(b: &Bounds, n: usize) -> impl Iterator<Item = [f64; 3]> + '_ {
    let t = move |i: usize, k: usize| b.min[k] + (b.max[k] - b.min[k]) * i as f64 / (n - 1) as f64;
    (0..n * n * n).map(move |i| [t(i % n, 0), t(i / n % n, 1), t(i / (n * n), 2)])
}

fn corners(b: &Bounds) -> Vec<[f64; 3]> {
    (0..8)
        .map(|k| [0, 1, 2].map(|i| if k >> i & 1 == 0 { b.min[i] } else { b.max[i] }))
        .collect()
}

#[test]
fn classic_and_bench_fixtures_load_and_have_an_inside() {
    let mut count = 0;
    for path in scripts("classic").into_iter().chain(scripts("bench")) {
        let name = path.display().to_string();
        let model = load_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        let region = model
            .bounds
            .unwrap_or_else(|| panic!("{name} declares bounds"));
        let tape = Tape::new(&model.shape);
        let mut eval = PointEval::new();
        let inside: Vec<[f64; 3]> = grid(&region, 41)
            .filter(|&p| eval.eval(&tape, p) < 0.0)
            .collect();
        assert!(!inside.is_empty(), "{name}: nothing inside");
        for c in corners(&region) {
            let v = eval.eval(&tape, c);
            assert!(v > 0.0, "{name}: corner {c:?} is not outside ({v})");
        }
        count += 1;
    }
    assert_eq!(count, 9 + 6, "nine classic and six benchmark scripts");
}

#[test]
fn found_bounds_enclose_what_is_inside() {
    for name in [
        "classic/heart.rhai",
        "classic/sphere_circle.rhai",
        "classic/curve_cyl.rhai",
        "classic/drope_block.rhai",
        "classic/spaceship.rhai",
        "bench/spheres_chain.rhai",
    ] {
        let model = load_file(&fixtures().join(name), &[]).unwrap_or_else(|e| panic!("{e}"));
        let declared = model.bounds.expect("declared bounds");
        let found = find_bounds(&model.shape).unwrap_or_else(|e| panic!("{name}: {e}"));
        let tape = Tape::new(&model.shape);
        let mut eval = PointEval::new();
        for p in grid(&declared, 41).filter(|&p| eval.eval(&tape, p) < 0.0) {
            assert!(
                (0..3).all(|i| found.min[i] <= p[i] && p[i] <= found.max[i]),
                "{name}: inside point {p:?} is outside the found bounds {found:?}"
            );
        }
        // Tight: no wider than the declared region plus padding.
        for i in 0..3 {
            let slack = 0.25 * (declared.max[i] - declared.min[i]);
            assert!(found.min[i] >= declared.min[i] - slack, "{name}: {found:?}");
            assert!(found.max[i] <= declared.max[i] + slack, "{name}: {found:?}");
        }
    }
}

#[test]
fn vm_fixtures_load() {
    let files = scripts("vm");
    assert_eq!(files.len(), 4);
    for path in files {
        let model = load_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
        let tape = Tape::new(&model.shape);
        assert!(PointEval::new().eval(&tape, [0.1, 0.2, 0.3]).is_finite());
    }
    let colonnade = load_file(&fixtures().join("vm/colonnade.vm"), &[]).unwrap();
    let b = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
    let tape = Tape::new(&colonnade.shape);
    let mut eval = PointEval::new();
    assert!(grid(&b, 21).any(|p| eval.eval(&tape, p) < 0.0));
}
