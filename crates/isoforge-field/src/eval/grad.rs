//! The gradient evaluator: value and partial derivatives, forward mode.
//!
//! Each register holds a value and its three partials; every instruction applies the
//! chain rule. Values are computed with the same [`crate::eval::scalar`] functions as the
//! point evaluator, so `GradEval` values equal `PointEval` values bit for bit.

use crate::eval::{scalar, trig};
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::Var;
use crate::tape::{Op, Tape};

/// A field value with its partial derivatives.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Grad {
    /// f
    pub v: f64,
    /// (df/dx, df/dy, df/dz)
    pub d: [f64; 3],
}

impl Grad {
    fn constant(v: f64) -> Grad {
        Grad { v, d: [0.0; 3] }
    }
    fn scale(self, v: f64, k: f64) -> Grad {
        Grad {
            v,
            d: self.d.map(|d| d * k),
        }
    }
}

/// The value and derivative of a unary operation at `a`.
#[inline(always)]
fn unary(op: UnaryOp, a: Grad) -> Grad {
    let x = a.v;
    // sin and cos with one reduction for the value and the slope.
    match op {
        UnaryOp::Sin => {
            let (s, c) = trig::sin_cos(x);
            return a.scale(s, c);
        }
        UnaryOp::Cos => {
            let (s, c) = trig::sin_cos(x);
            return a.scale(c, -s);
        }
        _ => {}
    }
    let v = scalar::unary(op, a.v);
    let k = match op {
        UnaryOp::Neg => -1.0,
        // abs: the derivative's sign follows the argument's (0 at a kink counts as +).
        UnaryOp::Abs => {
            if x < 0.0 {
                -1.0
            } else {
                1.0
            }
        }
        UnaryOp::Recip => -(v * v),
        UnaryOp::Sqrt => 0.5 / v,
        UnaryOp::Square => 2.0 * x,
        // (Returned above, one reduction for both; the same values again.)
        UnaryOp::Sin => trig::cos(x),
        UnaryOp::Cos => -trig::sin(x),
        UnaryOp::Tan => 1.0 + v * v,
        UnaryOp::Asin => 1.0 / (1.0 - x * x).sqrt(),
        UnaryOp::Acos => -1.0 / (1.0 - x * x).sqrt(),
        UnaryOp::Atan => 1.0 / (1.0 + x * x),
        UnaryOp::Exp => v,
        UnaryOp::Ln => 1.0 / x,
        UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round => 0.0,
        UnaryOp::PowI(n) => n as f64 * scalar::powi(x, n.saturating_sub(1)),
    };
    // Piecewise-constant functions have zero slope even where the argument's gradient is
    // infinite; do not turn that into NaN.
    if k == 0.0 && matches!(op, UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round) {
        return Grad::constant(v);
    }
    a.scale(v, k)
}

/// The value and derivative of a binary operation.
#[inline(always)]
fn binary(op: BinaryOp, a: Grad, b: Grad) -> Grad {
    let v = scalar::binary(op, a.v, b.v);
    #[inline(always)]
    fn zip(v: f64, a: &Grad, b: &Grad, f: impl Fn(f64, f64) -> f64) -> Grad {
        Grad {
            v,
            d: [f(a.d[0], b.d[0]), f(a.d[1], b.d[1]), f(a.d[2], b.d[2])],
        }
    }
    let (a, b) = (&a, &b);
    match op {
        BinaryOp::Add => zip(v, a, b, |p, q| p + q),
        BinaryOp::Sub => zip(v, a, b, |p, q| p - q),
        BinaryOp::Mul => zip(v, a, b, |p, q| p * b.v + a.v * q),
        BinaryOp::Div => zip(v, a, b, |p, q| (p * b.v - a.v * q) / (b.v * b.v)),
        BinaryOp::Min | BinaryOp::Max => {
            if v.is_nan() {
                Grad {
                    v,
                    d: [f64::NAN; 3],
                }
            } else {
                // The same side the value came from (left on ties, as scalar::min/max).
                let left = v.to_bits() == a.v.to_bits();
                Grad {
                    v,
                    d: if left { a.d } else { b.d },
                }
            }
        }
        BinaryOp::Atan2 => {
            // d atan2(y, x) = (x dy - y dx) / (x^2 + y^2)
            let r2 = a.v * a.v + b.v * b.v;
            zip(v, a, b, |dy, dx| (b.v * dy - a.v * dx) / r2)
        }
        BinaryOp::Pow => {
            // d a^b = b a^(b-1) da + a^b ln(a) db; the db term only where b varies, so a
            // constant exponent at a = 0 does not give 0 * -inf.
            let ka = b.v * a.v.powf(b.v - 1.0);
            let kb = v * a.v.ln();
            zip(
                v,
                a,
                b,
                |p, q| if q == 0.0 { ka * p } else { ka * p + kb * q },
            )
        }
        BinaryOp::Mod => {
            let f = (a.v / b.v).floor();
            zip(v, a, b, |p, q| p - f * q)
        }
    }
}

/// Evaluates value and gradient at a point. Reuse one per thread.
#[derive(Default)]
pub struct GradEval {
    regs: Vec<Grad>,
}

impl GradEval {
    /// A new evaluator.
    pub fn new() -> Self {
        Self::default()
    }
    /// Value and gradient at `p`. Where a derivative is undefined it may be NaN or infinite;
    /// callers must handle that.
    pub fn eval(&mut self, tape: &Tape, p: [f64; 3]) -> Grad {
        if self.regs.len() < tape.register_count() {
            self.regs.resize(tape.register_count(), Grad::constant(0.0));
        }
        let r = &mut self.regs[..];
        for op in tape.ops() {
            match *op {
                Op::Var { out, v } => {
                    let (i, x) = match v {
                        Var::X => (0, p[0]),
                        Var::Y => (1, p[1]),
                        Var::Z => (2, p[2]),
                    };
                    let mut g = Grad::constant(x);
                    g.d[i] = 1.0;
                    r[out as usize] = g;
                }
                Op::Const { out, c } => r[out as usize] = Grad::constant(c),
                Op::Copy { out, a } => r[out as usize] = r[a as usize],
                Op::Unary { op, out, a } => r[out as usize] = unary(op, r[a as usize]),
                Op::Binary { op, out, a, b } => {
                    r[out as usize] = binary(op, r[a as usize], r[b as usize])
                }
                Op::BinaryRI { op, out, a, imm } => {
                    r[out as usize] = binary(op, r[a as usize], Grad::constant(imm))
                }
                Op::BinaryIR { op, out, imm, b } => {
                    r[out as usize] = binary(op, Grad::constant(imm), r[b as usize])
                }
                Op::Custom { k, out, args } => {
                    let ins = args.map(|a| r[a as usize]);
                    let g = tape.customs()[k as usize].gradient(ins.map(|i| i.v));
                    // Chain rule through the node's three input fields.
                    let d = [0, 1, 2]
                        .map(|j| g[1] * ins[0].d[j] + g[2] * ins[1].d[j] + g[3] * ins[2].d[j]);
                    r[out as usize] = Grad { v: g[0], d };
                }
            }
        }
        r[tape.output()]
    }
}
