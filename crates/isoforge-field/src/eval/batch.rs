//! The batch evaluator: many points a call, structure of arrays.
//!
//! Points are worked through in blocks of [`BLOCK`]. Each register is a fixed-size array
//! of one block, and each instruction is one loop over the block calling the same scalar
//! function as the point evaluator; with the length known at compile time the compiler
//! turns the arithmetic, min/max and abs loops into SIMD code; sin, cos and atan2 too,
//! written in plain arithmetic (`trig.rs`), and powers step by step. The other
//! transcendental functions stay calls into libm.

use crate::eval::{scalar, trig};
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::Var;
use crate::tape::{Op, Tape};

/// Points per block.
pub const BLOCK: usize = 256;

type Reg = [f64; BLOCK];

/// Evaluates a tape at many points (any count; worked through in blocks sized for
/// vectorized loops). Reuse one per thread: it holds its buffers.
#[derive(Default)]
pub struct BatchEval {
    regs: Vec<Reg>,
}

/// The output register mutably and one operand register shared; `out != a` is guaranteed
/// by the register allocator.
fn split1(r: &mut [Reg], out: u32, a: u32) -> (&mut Reg, &Reg) {
    let (out, a) = (out as usize, a as usize);
    if a < out {
        let (lo, hi) = r.split_at_mut(out);
        (&mut hi[0], &lo[a])
    } else {
        let (lo, hi) = r.split_at_mut(a);
        (&mut lo[out], &hi[0])
    }
}

/// The output register mutably and two operand registers shared (they may be the same).
fn split2(r: &mut [Reg], out: u32, a: u32, b: u32) -> (&mut Reg, &Reg, &Reg) {
    let (out, a, b) = (out as usize, a as usize, b as usize);
    let (lo, hi) = r.split_at_mut(out);
    let (o, rest) = hi.split_first_mut().expect("register in range");
    let get = |i: usize| -> &Reg { if i < out { &lo[i] } else { &rest[i - out - 1] } };
    (o, get(a), get(b))
}

#[inline(always)]
fn map1(o: &mut Reg, a: &Reg, f: impl Fn(f64) -> f64) {
    for (o, a) in o.iter_mut().zip(a) {
        *o = f(*a);
    }
}

#[inline(always)]
fn map2(o: &mut Reg, a: &Reg, b: &Reg, f: impl Fn(f64, f64) -> f64) {
    for ((o, a), b) in o.iter_mut().zip(a).zip(b) {
        *o = f(*a, *b);
    }
}

/// A unary operation over a block, one monomorphized loop per operation so the simple
/// ones vectorize.
fn unary(op: UnaryOp, o: &mut Reg, a: &Reg) {
    match op {
        UnaryOp::Neg => map1(o, a, |x| -x),
        UnaryOp::Abs => map1(o, a, f64::abs),
        UnaryOp::Recip => map1(o, a, |x| 1.0 / x),
        UnaryOp::Sqrt => map1(o, a, f64::sqrt),
        UnaryOp::Square => map1(o, a, |x| x * x),
        UnaryOp::Floor => map1(o, a, f64::floor),
        UnaryOp::Ceil => map1(o, a, f64::ceil),
        UnaryOp::Sin => trig_block(o, a, trig::sin_in_range, f64::sin),
        UnaryOp::Cos => trig_block(o, a, trig::cos_in_range, f64::cos),
        UnaryOp::PowI(n) => scalar::powi_block(o, a, n),
        op => map1(o, a, |x| scalar::unary(op, x)),
    }
}

/// sin or cos over a block: the plain-arithmetic loop for every lane (it vectorizes), then
/// libm for the rare lanes beyond [`trig::LIMIT`], as [`scalar::unary`] does per point.
#[inline(always)]
fn trig_block(o: &mut Reg, a: &Reg, in_range: impl Fn(f64) -> f64, libm: impl Fn(f64) -> f64) {
    map1(o, a, in_range);
    for (o, &x) in o.iter_mut().zip(a) {
        if !trig::in_range(x) {
            *o = libm(x);
        }
    }
}

/// After the plain-arithmetic atan2 over every lane: libm for the lanes it does not
/// cover (a zero, an infinity or NaN), as [`trig::atan2`] does per point.
fn atan2_fixup(o: &mut Reg, y: &Reg, x: &Reg) {
    for ((o, &y), &x) in o.iter_mut().zip(y).zip(x) {
        if !trig::atan2_in_range(y, x) {
            *o = y.atan2(x);
        }
    }
}

/// A binary operation over a block; `imm` variants pass a constant as one side.
fn binary(op: BinaryOp, o: &mut Reg, a: &Reg, b: &Reg) {
    match op {
        BinaryOp::Add => map2(o, a, b, |x, y| x + y),
        BinaryOp::Sub => map2(o, a, b, |x, y| x - y),
        BinaryOp::Mul => map2(o, a, b, |x, y| x * y),
        BinaryOp::Div => map2(o, a, b, |x, y| x / y),
        BinaryOp::Min => map2(o, a, b, scalar::min),
        BinaryOp::Max => map2(o, a, b, scalar::max),
        BinaryOp::Atan2 => {
            map2(o, a, b, trig::atan2_reduced);
            atan2_fixup(o, a, b);
        }
        op => map2(o, a, b, |x, y| scalar::binary(op, x, y)),
    }
}

fn binary_ri(op: BinaryOp, o: &mut Reg, a: &Reg, c: f64) {
    match op {
        BinaryOp::Add => map1(o, a, |x| x + c),
        BinaryOp::Sub => map1(o, a, |x| x - c),
        BinaryOp::Mul => map1(o, a, |x| x * c),
        BinaryOp::Div => map1(o, a, |x| x / c),
        BinaryOp::Min => map1(o, a, |x| scalar::min(x, c)),
        BinaryOp::Max => map1(o, a, |x| scalar::max(x, c)),
        BinaryOp::Atan2 => {
            map1(o, a, |x| trig::atan2_reduced(x, c));
            atan2_fixup(o, a, &[c; BLOCK]);
        }
        op => map1(o, a, |x| scalar::binary(op, x, c)),
    }
}

fn binary_ir(op: BinaryOp, o: &mut Reg, c: f64, b: &Reg) {
    match op {
        BinaryOp::Add => map1(o, b, |y| c + y),
        BinaryOp::Sub => map1(o, b, |y| c - y),
        BinaryOp::Mul => map1(o, b, |y| c * y),
        BinaryOp::Div => map1(o, b, |y| c / y),
        BinaryOp::Min => map1(o, b, |y| scalar::min(c, y)),
        BinaryOp::Max => map1(o, b, |y| scalar::max(c, y)),
        BinaryOp::Atan2 => {
            map1(o, b, |y| trig::atan2_reduced(c, y));
            atan2_fixup(o, &[c; BLOCK], b);
        }
        op => map1(o, b, |y| scalar::binary(op, c, y)),
    }
}

impl BatchEval {
    /// A new evaluator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Writes `f(xs[i], ys[i], zs[i])` to `out[i]`. All four slices have the same length;
    /// if they differ, only the shortest length is evaluated.
    pub fn eval(&mut self, tape: &Tape, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let n = xs.len().min(ys.len()).min(zs.len()).min(out.len());
        if self.regs.len() < tape.register_count() {
            self.regs.resize(tape.register_count(), [0.0; BLOCK]);
        }
        let mut start = 0;
        while start < n {
            let len = (n - start).min(BLOCK);
            let p = [
                &xs[start..start + len],
                &ys[start..start + len],
                &zs[start..start + len],
            ];
            self.block(tape, p, len);
            out[start..start + len].copy_from_slice(&self.regs[tape.output()][..len]);
            start += len;
        }
    }

    /// Evaluates one block of `len <= BLOCK` points. Lanes past `len` hold zeros and are
    /// computed but never read (custom callbacks only see the real points).
    fn block(&mut self, tape: &Tape, p: [&[f64]; 3], len: usize) {
        let r = &mut self.regs[..];
        for op in tape.ops() {
            match *op {
                Op::Var { out, v } => {
                    let src = match v {
                        Var::X => p[0],
                        Var::Y => p[1],
                        Var::Z => p[2],
                    };
                    let o = &mut r[out as usize];
                    o[..len].copy_from_slice(src);
                    o[len..].fill(0.0);
                }
                Op::Const { out, c } => r[out as usize].fill(c),
                Op::Copy { out, a } => {
                    let (o, a) = split1(r, out, a);
                    o.copy_from_slice(a)
                }
                Op::Unary { op, out, a } => {
                    let (o, a) = split1(r, out, a);
                    unary(op, o, a)
                }
                Op::Binary { op, out, a, b } => {
                    let (o, a, b) = split2(r, out, a, b);
                    binary(op, o, a, b)
                }
                Op::BinaryRI { op, out, a, imm } => {
                    let (o, a) = split1(r, out, a);
                    binary_ri(op, o, a, imm)
                }
                Op::BinaryIR { op, out, imm, b } => {
                    let (o, b) = split1(r, out, b);
                    binary_ir(op, o, imm, b)
                }
                Op::Custom { k, out, args } => {
                    let f = &tape.customs()[k as usize];
                    // The node sees the whole block at once (see `CustomField::values`).
                    let mut values = [0.0; BLOCK];
                    let [a, b, c] = args.map(|a| &r[a as usize][..len]);
                    f.values(a, b, c, &mut values[..len]);
                    r[out as usize] = values;
                }
            }
        }
    }
}
