//! Plain f64 math for each operation: the reference every other evaluator is checked against.
//!
//! Every evaluator calls these same functions per point, so point, batch and gradient values
//! agree bit for bit.

use crate::eval::trig;
use crate::op::{BinaryOp, UnaryOp};

/// Applies a unary operation to a number.
#[inline(always)]
pub fn unary(op: UnaryOp, a: f64) -> f64 {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Recip => 1.0 / a,
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Square => a * a,
        UnaryOp::Sin => trig::sin(a),
        UnaryOp::Cos => trig::cos(a),
        UnaryOp::Tan => a.tan(),
        UnaryOp::Asin => a.asin(),
        UnaryOp::Acos => a.acos(),
        UnaryOp::Atan => a.atan(),
        UnaryOp::Exp => a.exp(),
        UnaryOp::Ln => a.ln(),
        UnaryOp::Floor => a.floor(),
        UnaryOp::Ceil => a.ceil(),
        UnaryOp::Round => a.round(),
        UnaryOp::PowI(n) => a.powi(n),
    }
}

/// The smaller of two numbers; NaN if either is NaN (a NaN side must not be silently
/// dropped). On a tie (`-0` vs `+0`) the left one, so every evaluator agrees bitwise.
#[inline(always)]
pub fn min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if b < a {
        b
    } else {
        a
    }
}

/// The larger of two numbers; NaN if either is NaN. On a tie the left one.
#[inline(always)]
pub fn max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if b > a {
        b
    } else {
        a
    }
}

/// `a - b * floor(a / b)`: the remainder with the sign of `b`.
#[inline(always)]
pub fn modulo(a: f64, b: f64) -> f64 {
    a - b * (a / b).floor()
}

/// Applies a binary operation to two numbers.
#[inline(always)]
pub fn binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        BinaryOp::Min => min(a, b),
        BinaryOp::Max => max(a, b),
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Pow => a.powf(b),
        BinaryOp::Mod => modulo(a, b),
    }
}
