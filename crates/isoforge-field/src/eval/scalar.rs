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
        UnaryOp::PowI(n) => powi(a, n),
    }
}

/// `a^n` by binary powering: square the base for each bit of |n|, multiply the bits that
/// are set into the result, and take the reciprocal for negative n; the algorithm
/// `f64::powi` calls at run time (compiler-builtins' `__powidf2`), written out so the
/// batch evaluator can run each step over a whole block ([`powi_block`]) with the same
/// roundings: as a call per point, heart's powers were 8 % of its meshing time.
#[inline]
pub fn powi(a: f64, n: i32) -> f64 {
    let (mut base, mut bits, mut r) = (a, n.unsigned_abs(), 1.0);
    loop {
        if bits & 1 != 0 {
            r *= base;
        }
        bits >>= 1;
        if bits == 0 {
            break;
        }
        base *= base;
    }
    if n < 0 { 1.0 / r } else { r }
}

/// [`powi`] over a block of lanes at once, step for step: each lane's result is the same.
#[inline(always)]
pub fn powi_block<const N: usize>(out: &mut [f64; N], a: &[f64; N], n: i32) {
    let mut base = *a;
    let mut bits = n.unsigned_abs();
    out.fill(1.0);
    loop {
        if bits & 1 != 0 {
            for (o, b) in out.iter_mut().zip(&base) {
                *o *= b;
            }
        }
        bits >>= 1;
        if bits == 0 {
            break;
        }
        for b in base.iter_mut() {
            *b *= *b;
        }
    }
    if n < 0 {
        for o in out.iter_mut() {
            *o = 1.0 / *o;
        }
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
        BinaryOp::Atan2 => trig::atan2(a, b),
        BinaryOp::Pow => a.powf(b),
        BinaryOp::Mod => modulo(a, b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powi_is_the_run_time_powi_bit_for_bit_and_so_is_its_block() {
        let bases = [
            0.0,
            -0.0,
            1.5,
            -0.7,
            3.25,
            1e-160,
            -2e150,
            f64::NAN,
            f64::INFINITY,
        ];
        for n in [
            -9,
            -3,
            -2,
            -1,
            0,
            1,
            3,
            4,
            5,
            7,
            8,
            13,
            31,
            i32::MIN,
            i32::MAX,
        ] {
            let mut block = [0.0; 9];
            powi_block(&mut block, &bases, n);
            for (a, b) in bases.iter().zip(block) {
                // black_box: a constant exponent would let the compiler expand powi itself.
                let libm = a.powi(std::hint::black_box(n));
                let ours = powi(*a, n);
                assert!(ours.to_bits() == libm.to_bits() || ours.is_nan() && libm.is_nan());
                assert!(ours.to_bits() == b.to_bits() || ours.is_nan() && b.is_nan());
            }
        }
    }
}
