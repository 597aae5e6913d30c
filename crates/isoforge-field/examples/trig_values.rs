//! Prints sin, cos and atan2 as the evaluators compute them, for `tools/trig-accuracy.py`,
//! which checks them against 70-digit decimal arithmetic. Each input line is `x` (out:
//! `x sin cos`) or `y x` (out: `y x atan2`), numbers in shortest round-trip form. The
//! point and batch evaluators are both run and must agree bit for bit.
//!
//! `cargo run --release -p isoforge-field --example trig_values < numbers.txt`

use std::io::{BufRead, Write};

use isoforge_field::{BatchEval, PointEval, Shape, Tape};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (n, line) in std::io::stdin().lock().lines().enumerate() {
        let line = line?;
        let row = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<Vec<f64>, _>>()
            .map_err(|e| format!("line {}: {:?}: {e}", n + 1, line))?;
        if !(row.len() == 1 || row.len() == 2) {
            return Err(format!("line {}: one or two numbers, not {:?}", n + 1, line).into());
        }
        rows.push(row);
    }
    let (x, y) = (Shape::x(), Shape::y());
    let tapes = [
        Tape::new(&x.sin()),
        Tape::new(&x.cos()),
        Tape::new(&y.atan2(&x)),
    ];
    // Per row: (x, y) as the tapes read them; one number is x, two are y then x.
    let xs: Vec<f64> = rows.iter().map(|r| r[r.len() - 1]).collect();
    let ys: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    let zs = vec![0.0; rows.len()];
    let mut batch = BatchEval::new();
    let batched: Vec<Vec<f64>> = tapes
        .iter()
        .map(|t| {
            let mut out = vec![0.0; rows.len()];
            batch.eval(t, &xs, &ys, &zs, &mut out);
            out
        })
        .collect();
    let mut point = PointEval::new();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (i, row) in rows.iter().enumerate() {
        let which: &[usize] = if row.len() == 1 { &[0, 1] } else { &[2] };
        let mut values = Vec::new();
        for &k in which {
            let v = point.eval(&tapes[k], [xs[i], ys[i], 0.0]);
            if v.to_bits() != batched[k][i].to_bits() && !(v.is_nan() && batched[k][i].is_nan()) {
                return Err(format!("{row:?}: the point and batch evaluators differ").into());
            }
            values.push(v);
        }
        let numbers: Vec<String> = row
            .iter()
            .chain(&values)
            .map(|v| format!("{v:e}"))
            .collect();
        writeln!(out, "{}", numbers.join(" "))?;
    }
    Ok(())
}
