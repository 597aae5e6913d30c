//! Mesh files and the checker on a million triangles:
//! `cargo bench -p isoforge-benches --bench meshio`.
//!
//! The mesh is a UV sphere of 1000 slices by 501 stacks (1,000,000 triangles, 499,002
//! vertices), standing in for a depth-9 mesher output.

use std::sync::OnceLock;

use divan::Bencher;
use isoforge_mesh::io::{decode, encode};
use isoforge_mesh::{Mesh, MeshFormat, check, samples};

fn main() {
    divan::main();
}

fn million() -> &'static Mesh {
    static MESH: OnceLock<Mesh> = OnceLock::new();
    MESH.get_or_init(|| samples::uv_sphere(50.0, 1000, 501))
}

fn encoded(format: MeshFormat) -> Vec<u8> {
    let mut out = Vec::new();
    encode(million(), format, &mut out).expect("encoding to memory cannot fail");
    out
}

const FORMATS: [MeshFormat; 5] = [
    MeshFormat::Stl,
    MeshFormat::StlAscii,
    MeshFormat::Obj,
    MeshFormat::Ply,
    MeshFormat::ThreeMf,
];

#[divan::bench(sample_count = 5)]
fn check_1m(bencher: Bencher) {
    let mesh = million();
    bencher.bench(|| check(divan::black_box(mesh)));
}

#[divan::bench(args = FORMATS, sample_count = 3)]
fn write_1m(bencher: Bencher, format: MeshFormat) {
    let mesh = million();
    bencher.bench(|| {
        let mut out = Vec::with_capacity(64 << 20);
        encode(mesh, format, &mut out).expect("in memory");
        out
    });
}

#[divan::bench(args = FORMATS, sample_count = 3)]
fn read_1m(bencher: Bencher, format: MeshFormat) {
    let bytes = encoded(format);
    bencher.bench(|| decode(divan::black_box(&bytes), format).expect("valid"));
}
