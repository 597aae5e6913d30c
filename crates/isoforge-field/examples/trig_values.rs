//! Prints sin x and cos x as the evaluators compute them, for `tools/trig-accuracy.py`,
//! which checks them against 70-digit decimal arithmetic: one x per input line, one
//! `x sin cos` line out (shortest round-trip form). The point and batch evaluators are
//! both run and must agree bit for bit.
//!
//! `cargo run --release -p isoforge-field --example trig_values < xs.txt`

use std::io::{BufRead, Write};

use isoforge_field::{BatchEval, PointEval, Shape, Tape};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut xs = Vec::new();
    for (n, line) in std::io::stdin().lock().lines().enumerate() {
        let line = line?;
        let x: f64 = line
            .trim()
            .parse()
            .map_err(|e| format!("line {}: {:?}: {e}", n + 1, line))?;
        xs.push(x);
    }
    let (sin, cos) = (Tape::new(&Shape::x().sin()), Tape::new(&Shape::x().cos()));
    let zeros = vec![0.0; xs.len()];
    let (mut batch_sin, mut batch_cos) = (vec![0.0; xs.len()], vec![0.0; xs.len()]);
    let mut batch = BatchEval::new();
    batch.eval(&sin, &xs, &zeros, &zeros, &mut batch_sin);
    batch.eval(&cos, &xs, &zeros, &zeros, &mut batch_cos);
    let mut point = PointEval::new();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (i, &x) in xs.iter().enumerate() {
        let (s, c) = (
            point.eval(&sin, [x, 0.0, 0.0]),
            point.eval(&cos, [x, 0.0, 0.0]),
        );
        if s.to_bits() != batch_sin[i].to_bits() || c.to_bits() != batch_cos[i].to_bits() {
            return Err(format!("x = {x:e}: the point and batch evaluators differ").into());
        }
        writeln!(out, "{x:e} {s:e} {c:e}")?;
    }
    Ok(())
}
