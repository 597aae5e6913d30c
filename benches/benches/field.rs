//! Field kernel speed: point, batch (per point), interval and simplify, on gyroid_sphere
//! (trig-heavy), colonnade.vm (808 ops, mostly min/max) and spiky_ball (atan2-heavy:
//! a radius over spherical angles, as fixtures/modern/spiky_ball.rhai).
//!
//! Run: `cargo bench -p isoforge-benches --bench field`.

use divan::counter::ItemsCount;
use divan::{Bencher, black_box};
use isoforge_field::{BatchEval, GradEval, Interval, IntervalEval, PointEval, Shape, Tape};

fn main() {
    divan::main();
}

/// `max(abs(sin(8x)cos(8y)+sin(8y)cos(8z)+sin(8z)cos(8x)) - 0.3, x^2+y^2+z^2-1)`
fn gyroid_sphere() -> Tape {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let (x8, y8, z8) = (&x * 8.0, &y * 8.0, &z * 8.0);
    let g = x8.sin() * y8.cos() + y8.sin() * z8.cos() + z8.sin() * x8.cos();
    let s = x.square() + y.square() + z.square() - 1.0;
    Tape::new(&(g.abs() - 0.3).max(&s))
}

/// `|p| - (0.8 + 0.2 (sin(5θ) cos(5φ))²)`, θ = atan2(y, x), φ = atan2(z, √(x² + y²)).
fn spiky_ball() -> Tape {
    let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
    let theta = y.atan2(&x);
    let phi = z.atan2(&(x.square() + y.square()).sqrt());
    let wave = (&theta * 5.0).sin() * (&phi * 5.0).cos();
    let r = (x.square() + y.square() + z.square()).sqrt();
    Tape::new(&(r - (wave.square() * 0.2 + 0.8)))
}

fn colonnade() -> Tape {
    let text = include_str!("../../fixtures/vm/colonnade.vm");
    Tape::new(&isoforge_field::vm::parse_vm(text).expect("colonnade.vm parses"))
}

fn tape(name: &str) -> Tape {
    match name {
        "gyroid_sphere" => gyroid_sphere(),
        "spiky_ball" => spiky_ball(),
        _ => colonnade(),
    }
}

const MODELS: [&str; 3] = ["gyroid_sphere", "colonnade", "spiky_ball"];

/// Points spread over [-1, 1]^3 (a fixed scramble, not a grid, so no branch is favoured).
fn points(n: usize) -> Vec<[f64; 3]> {
    let f = |i: usize, k: usize| ((i * [7919, 104729, 1299709][k]) % 2001) as f64 / 1000.0 - 1.0;
    (0..n).map(|i| [f(i, 0), f(i, 1), f(i, 2)]).collect()
}

/// The same points as three coordinate arrays.
fn soa(n: usize) -> [Vec<f64>; 3] {
    let p = points(n);
    [0, 1, 2].map(|k| p.iter().map(|q| q[k]).collect())
}

fn iv(lo: f64, hi: f64) -> Interval {
    Interval::try_from((lo, hi)).expect("valid interval")
}

/// A region: the whole [-1, 1]^3, or one cell of side 1/64 near the surface (as at depth 7).
fn region(name: &str, cell: bool) -> [Interval; 3] {
    if !cell {
        return [iv(-1.0, 1.0); 3];
    }
    let c = match name {
        "gyroid_sphere" => [0.6, 0.3, 0.5],
        "spiky_ball" => [0.6, 0.45, 0.3],
        _ => [0.1, -0.2, 0.05],
    };
    c.map(|v| iv(v, v + 1.0 / 64.0))
}

#[divan::bench(args = MODELS)]
fn point(b: Bencher, name: &str) {
    let t = tape(name);
    let p = points(1024);
    let mut e = PointEval::new();
    b.counter(ItemsCount::new(1024usize)).bench_local(|| {
        let mut s = 0.0;
        for q in &p {
            s += e.eval(&t, *q);
        }
        black_box(s)
    });
}

#[divan::bench(args = MODELS)]
fn batch(b: Bencher, name: &str) {
    let t = tape(name);
    let n = 4096;
    let p = soa(n);
    let mut out = vec![0.0; n];
    let mut e = BatchEval::new();
    b.counter(ItemsCount::new(n)).bench_local(|| {
        e.eval(&t, &p[0], &p[1], &p[2], &mut out);
        black_box(&out);
    });
}

#[divan::bench(args = MODELS)]
fn gradient(b: Bencher, name: &str) {
    let t = tape(name);
    let p = points(1024);
    let mut e = GradEval::new();
    b.counter(ItemsCount::new(1024usize)).bench_local(|| {
        let mut s = 0.0;
        for q in &p {
            s += e.eval(&t, *q).d[0];
        }
        black_box(s)
    });
}

#[divan::bench(args = MODELS, consts = [false, true])]
fn interval<const CELL: bool>(b: Bencher, name: &str) {
    let t = tape(name);
    let r = region(name, CELL);
    let mut e = IntervalEval::new();
    b.bench_local(|| black_box(e.eval(&t, black_box(r))));
}

#[divan::bench(args = MODELS, consts = [false, true])]
fn simplify<const CELL: bool>(b: Bencher, name: &str) {
    let t = tape(name);
    let mut e = IntervalEval::new();
    e.eval(&t, region(name, CELL));
    let choices = e.choices().to_vec();
    b.bench_local(|| black_box(t.simplify(black_box(&choices))));
}

/// Interval pass plus simplify plus one more interval pass on the shorter tape: the
/// per-cell work of an octree descent.
#[divan::bench(args = MODELS)]
fn cell_step(b: Bencher, name: &str) {
    let t = tape(name);
    let r = region(name, true);
    let mut e = IntervalEval::new();
    b.bench_local(|| {
        e.eval(&t, r);
        let short = t.simplify(e.choices());
        black_box(e.eval(&short, r))
    });
}
