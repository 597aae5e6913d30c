//! Plain f64 math for each operation: the reference every other evaluator is checked against.

use crate::op::{BinaryOp, UnaryOp};

/// Applies a unary operation to a number.
pub fn unary(op: UnaryOp, a: f64) -> f64 {
    match op {
        UnaryOp::Neg => -a,
        UnaryOp::Abs => a.abs(),
        UnaryOp::Recip => 1.0 / a,
        UnaryOp::Sqrt => a.sqrt(),
        UnaryOp::Square => a * a,
        UnaryOp::Sin => a.sin(),
        UnaryOp::Cos => a.cos(),
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

/// Applies a binary operation to two numbers.
pub fn binary(op: BinaryOp, a: f64, b: f64) -> f64 {
    match op {
        BinaryOp::Add => a + b,
        BinaryOp::Sub => a - b,
        BinaryOp::Mul => a * b,
        BinaryOp::Div => a / b,
        // NaN propagates: a NaN side must not be silently dropped by min/max.
        BinaryOp::Min => {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.min(b)
            }
        }
        BinaryOp::Max => {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        }
        BinaryOp::Atan2 => a.atan2(b),
        BinaryOp::Pow => a.powf(b),
        BinaryOp::Mod => a - b * (a / b).floor(),
    }
}
