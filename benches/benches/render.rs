//! Preview renders: `cargo bench -p isoforge-benches --bench render`.

use divan::Bencher;
use isoforge_render::{RenderSettings, render};

fn main() {
    divan::main();
}

/// The README's kind of picture: a classic model at 400 x 300, iso view.
#[divan::bench(args = ["heart", "spaceship", "sinus_sphere"], sample_count = 3)]
fn render_400x300(bencher: Bencher, model: &str) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fixtures/classic")
        .join(format!("{model}.rhai"));
    let loaded = isoforge_script::load_file(&path, &[]).expect("fixture loads");
    let bounds = loaded.bounds.expect("fixture declares bounds");
    let settings = RenderSettings::new(400, 300);
    bencher.bench(|| render(&loaded.shape, &bounds, &settings));
}
