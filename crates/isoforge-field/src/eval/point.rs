//! The single-point evaluator.

use crate::eval::scalar;
use crate::shape::Var;
use crate::tape::{Op, Tape};

/// Evaluates a tape at one point. Holds its registers, so reuse one per thread.
#[derive(Default)]
pub struct PointEval {
    regs: Vec<f64>,
}

impl PointEval {
    /// A new evaluator.
    pub fn new() -> Self {
        Self::default()
    }
    /// The field's value at `p`; NaN where it is undefined.
    pub fn eval(&mut self, tape: &Tape, p: [f64; 3]) -> f64 {
        if self.regs.len() < tape.register_count() {
            self.regs.resize(tape.register_count(), 0.0);
        }
        let r = &mut self.regs[..];
        for op in tape.ops() {
            match *op {
                Op::Var { out, v } => {
                    r[out as usize] = match v {
                        Var::X => p[0],
                        Var::Y => p[1],
                        Var::Z => p[2],
                    }
                }
                Op::Const { out, c } => r[out as usize] = c,
                Op::Unary { op, out, a } => r[out as usize] = scalar::unary(op, r[a as usize]),
                Op::Binary { op, out, a, b } => {
                    r[out as usize] = scalar::binary(op, r[a as usize], r[b as usize])
                }
                Op::BinaryRI { op, out, a, imm } => {
                    r[out as usize] = scalar::binary(op, r[a as usize], imm)
                }
                Op::BinaryIR { op, out, imm, b } => {
                    r[out as usize] = scalar::binary(op, imm, r[b as usize])
                }
                Op::Custom { k, out, args } => {
                    let q = args.map(|a| r[a as usize]);
                    r[out as usize] = tape.customs()[k as usize].value(q)
                }
            }
        }
        r[tape.output()]
    }
}
