//! The `.vm` text format of the published benchmark models (one operation per line).
//!
//! ```text
//! # comment
//! _0 var-x
//! _1 const 2.5
//! _2 mul _0 _1
//! ```
//! Each line names a value; arguments name earlier lines; the last line is the result.

use std::collections::HashMap;

use crate::shape::Shape;

/// What went wrong reading a `.vm` file, with the 1-based line.
#[derive(Debug, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct VmError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub message: String,
}

/// `compare(a, b)`: -1, 0 or 1 by the sign of `a - b` (NaN if either is NaN), built from
/// exact operations: with `c = clamp(a - b, -0.5, 0.5)`, `ceil(c) + floor(c)` is 1 for
/// c in (0, 0.5], 0 for c = 0 and -1 for c in [-0.5, 0). `a - b` is 0 only when a == b
/// and keeps its sign otherwise (it may overflow to ±inf, which clamps the same way).
/// The one difference from a comparison: a == b == ±inf gives NaN.
fn compare(a: &Shape, b: &Shape) -> Shape {
    let c = (a - b)
        .max(&Shape::constant(-0.5))
        .min(&Shape::constant(0.5));
    c.ceil() + c.floor()
}

/// Parses a `.vm` model into a shape.
pub fn parse_vm(text: &str) -> Result<Shape, VmError> {
    let mut names: HashMap<&str, Shape> = HashMap::new();
    let mut last: Option<Shape> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let err = |message: String| VmError { line, message };
        let trimmed = raw.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            continue;
        }
        let mut words = trimmed.split_whitespace();
        let (Some(name), Some(opcode)) = (words.next(), words.next()) else {
            return Err(err(format!(
                "expected `NAME OPCODE ARGS...`, found `{trimmed}`"
            )));
        };
        let args: Vec<&str> = words.collect();
        let arity = |n: usize| -> Result<(), VmError> {
            if args.len() == n {
                Ok(())
            } else {
                Err(err(format!(
                    "`{opcode}` takes {n} argument(s), found {}",
                    args.len()
                )))
            }
        };
        let arg = |k: usize| -> Result<&Shape, VmError> {
            names
                .get(args[k])
                .ok_or_else(|| err(format!("`{}` is not defined on an earlier line", args[k])))
        };
        let shape = match opcode {
            "const" => {
                arity(1)?;
                let v: f64 = args[0]
                    .parse()
                    .map_err(|_| err(format!("`{}` is not a number", args[0])))?;
                Shape::constant(v)
            }
            "var-x" | "var-y" | "var-z" => {
                arity(0)?;
                match opcode {
                    "var-x" => Shape::x(),
                    "var-y" => Shape::y(),
                    _ => Shape::z(),
                }
            }
            "abs" | "neg" | "sqrt" | "square" | "floor" | "ceil" | "round" | "sin" | "cos"
            | "tan" | "asin" | "acos" | "atan" | "ln" | "exp" | "not" | "recip" => {
                arity(1)?;
                let a = arg(0)?;
                match opcode {
                    "abs" => a.abs(),
                    "neg" => -a,
                    "sqrt" => a.sqrt(),
                    "square" => a.square(),
                    "floor" => a.floor(),
                    "ceil" => a.ceil(),
                    "round" => a.round(),
                    "sin" => a.sin(),
                    "cos" => a.cos(),
                    "tan" => a.tan(),
                    "asin" => a.asin(),
                    "acos" => a.acos(),
                    "atan" => a.atan(),
                    "ln" => a.ln(),
                    "exp" => a.exp(),
                    "recip" => a.recip(),
                    // not(a) = 1 if a == 0 else 0: 1 - compare(a, 0)^2, exact.
                    _ => 1.0 - compare(a, &Shape::constant(0.0)).square(),
                }
            }
            "add" | "sub" | "mul" | "div" | "min" | "max" | "atan2" | "mod" | "compare" => {
                arity(2)?;
                let (a, b) = (arg(0)?, arg(1)?);
                match opcode {
                    "add" => a + b,
                    "sub" => a - b,
                    "mul" => a * b,
                    "div" => a / b,
                    "min" => a.min(b),
                    "max" => a.max(b),
                    "atan2" => a.atan2(b),
                    "mod" => a.modulo(b),
                    _ => compare(a, b),
                }
            }
            "and" | "or" => {
                return Err(err(format!(
                    "`{opcode}` is not supported: it picks one argument by whether the other \
                     is zero, which no exact arithmetic on the available operations reproduces"
                )));
            }
            other => return Err(err(format!("unknown opcode `{other}`"))),
        };
        names.insert(name, shape.clone());
        last = Some(shape);
    }
    last.ok_or_else(|| VmError {
        line: text.lines().count().max(1),
        message: "no operations".into(),
    })
}
