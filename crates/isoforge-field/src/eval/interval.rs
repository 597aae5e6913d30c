//! The interval evaluator: rigorous enclosures over a box, and the min/max choices that
//! drive tape simplification.
//!
//! Every register carries an interval and a "may be NaN" bit. An operation that can give
//! NaN somewhere on its input box (sqrt below 0, 0 * inf, inf - inf, 0 / 0, ...) sets the
//! bit and makes its register `ENTIRE`; the bit flows to everything computed from it, and
//! a set bit at the output makes the result `ENTIRE`. A min or max with a NaN-possible
//! side records `Both`, so simplification never drops a branch that could make the point
//! value NaN.

use inari::Interval;

use crate::eval::enclose::{self, has_zero, unbounded};
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::Var;
use crate::tape::{Choice, Op, Tape};

/// Evaluates a tape over a box. Reuse one per thread.
#[derive(Default)]
pub struct IntervalEval {
    regs: Vec<Interval>,
    nan: Vec<bool>,
    choices: Vec<Choice>,
    /// The input box of each custom node the last pass met with bounded, NaN-free
    /// inputs, by the node's index in the tape (for [`Tape::narrow`]).
    custom_boxes: Vec<(u32, [Interval; 3])>,
}

/// An operation on one interval; the common cases inline.
#[inline(always)]
fn unary_fast(op: UnaryOp, a: Interval) -> (Interval, bool) {
    match op {
        UnaryOp::Neg => (-a, false),
        UnaryOp::Abs => (a.abs(), false),
        UnaryOp::Square => (a.sqr(), false),
        UnaryOp::Sqrt if a.inf() >= 0.0 => (a.sqrt(), false),
        _ => unary(op, a),
    }
}

/// An operation on one interval: `(enclosure, may be NaN)`.
#[inline(never)]
pub(crate) fn unary(op: UnaryOp, a: Interval) -> (Interval, bool) {
    if a.is_empty() {
        return (Interval::ENTIRE, true);
    }
    match op {
        UnaryOp::Neg => (-a, false),
        UnaryOp::Abs => (a.abs(), false),
        UnaryOp::Recip => {
            // 1 / ±0 is ±inf; inari's [0, x] reciprocal excludes -inf, which -0 gives.
            if has_zero(a) {
                (Interval::ENTIRE, false)
            } else {
                (a.recip(), false)
            }
        }
        UnaryOp::Sqrt => {
            if a.inf() < 0.0 {
                (Interval::ENTIRE, true)
            } else {
                (a.sqrt(), false)
            }
        }
        UnaryOp::Square => (a.sqr(), false),
        UnaryOp::Sin => enclose::sin(a),
        UnaryOp::Cos => enclose::cos(a),
        UnaryOp::Tan => enclose::tan(a),
        UnaryOp::Asin => enclose::asin(a),
        UnaryOp::Acos => enclose::acos(a),
        UnaryOp::Atan => enclose::atan(a),
        UnaryOp::Exp => enclose::exp(a),
        UnaryOp::Ln => enclose::ln(a),
        UnaryOp::Floor => (a.floor(), false),
        UnaryOp::Ceil => (a.ceil(), false),
        UnaryOp::Round => (a.round(), false),
        UnaryOp::PowI(n) => enclose::powi(a, n),
    }
}

/// An operation on two intervals: `(enclosure, may be NaN)`; the common cases inline.
#[inline(always)]
fn binary_fast(op: BinaryOp, a: Interval, b: Interval) -> (Interval, bool) {
    match op {
        // Registers never hold EMPTY, and min/max cannot create NaN themselves.
        BinaryOp::Min => (a.min(b), false),
        BinaryOp::Max => (a.max(b), false),
        // Bounded operands cannot make + - * give NaN (no infinity meets a zero or an
        // opposite infinity).
        BinaryOp::Add if a.is_common_interval() && b.is_common_interval() => (a + b, false),
        BinaryOp::Sub if a.is_common_interval() && b.is_common_interval() => (a - b, false),
        BinaryOp::Mul if a.is_common_interval() && b.is_common_interval() => (a * b, false),
        _ => binary(op, a, b),
    }
}

/// An operation on two intervals: `(enclosure, may be NaN)`.
#[inline(never)]
pub(crate) fn binary(op: BinaryOp, a: Interval, b: Interval) -> (Interval, bool) {
    if a.is_empty() || b.is_empty() {
        return (Interval::ENTIRE, true);
    }
    let inf = f64::INFINITY;
    let r = match op {
        BinaryOp::Add => {
            let nan = (a.sup() == inf && b.inf() == -inf) || (a.inf() == -inf && b.sup() == inf);
            (a + b, nan)
        }
        BinaryOp::Sub => {
            let nan = (a.sup() == inf && b.sup() == inf) || (a.inf() == -inf && b.inf() == -inf);
            (a - b, nan)
        }
        BinaryOp::Mul => {
            let nan = (has_zero(a) && unbounded(b)) || (has_zero(b) && unbounded(a));
            (a * b, nan)
        }
        BinaryOp::Div => {
            let nan = (has_zero(a) && has_zero(b)) || (unbounded(a) && unbounded(b));
            if has_zero(b) {
                // Division by ±0 gives either infinity (sign from the zero's sign).
                (Interval::ENTIRE, nan)
            } else {
                (a / b, nan)
            }
        }
        BinaryOp::Min => (a.min(b), false),
        BinaryOp::Max => (a.max(b), false),
        BinaryOp::Atan2 => enclose::atan2(a, b),
        BinaryOp::Pow => enclose::pow(a, b),
        BinaryOp::Mod => enclose::modulo(a, b),
    };
    if r.0.is_empty() {
        (Interval::ENTIRE, true)
    } else {
        r
    }
}

/// The choice of a min or max given its operands' intervals and NaN bits.
#[inline(always)]
pub(crate) fn choose(op: BinaryOp, a: Interval, an: bool, b: Interval, bn: bool) -> Choice {
    if an || bn {
        return Choice::Both;
    }
    // `p.strict_precedes(q)`: every value of p is below every value of q (registers are
    // never empty, where inari would answer true).
    let (lower, upper) = if op == BinaryOp::Min { (a, b) } else { (b, a) };
    if lower.strict_precedes(upper) {
        Choice::Left
    } else if upper.strict_precedes(lower) {
        Choice::Right
    } else {
        Choice::Both
    }
}

impl IntervalEval {
    /// A new evaluator.
    pub fn new() -> Self {
        Self::default()
    }

    /// An interval that encloses f over the box. Where f may be undefined (NaN) somewhere
    /// in the box the result is `Interval::ENTIRE`, never a false all-negative or
    /// all-positive answer.
    pub fn eval(&mut self, tape: &Tape, b: [Interval; 3]) -> Interval {
        let (v, nan) = self.eval_nan(tape, b);
        if nan { Interval::ENTIRE } else { v }
    }

    /// Like [`IntervalEval::eval`], but returns the enclosure of the non-NaN values and
    /// separately whether some point of the box may give NaN.
    pub fn eval_nan(&mut self, tape: &Tape, b: [Interval; 3]) -> (Interval, bool) {
        let n = tape.register_count();
        if self.regs.len() < n {
            self.regs.resize(n, Interval::ENTIRE);
            self.nan.resize(n, false);
        }
        self.choices.clear();
        self.custom_boxes.clear();
        let (r, nr) = (&mut self.regs[..], &mut self.nan[..]);
        for op in tape.ops() {
            let (out, v, nan) = match *op {
                Op::Var { out, v } => {
                    let i = match v {
                        Var::X => b[0],
                        Var::Y => b[1],
                        Var::Z => b[2],
                    };
                    (out, i, i.is_empty())
                }
                Op::Copy { out, a } => (out, r[a as usize], nr[a as usize]),
                Op::Const { out, c } => {
                    if c.is_nan() {
                        (out, Interval::ENTIRE, true)
                    } else {
                        (out, enclose::interval(c, c), false)
                    }
                }
                Op::Unary { op, out, a } => {
                    let (v, nan) = unary_fast(op, r[a as usize]);
                    (out, v, nan || nr[a as usize])
                }
                Op::Binary { op, out, a, b } => {
                    let (ia, ib) = (r[a as usize], r[b as usize]);
                    let (na, nb) = (nr[a as usize], nr[b as usize]);
                    if matches!(op, BinaryOp::Min | BinaryOp::Max) {
                        self.choices.push(choose(op, ia, na, ib, nb));
                    }
                    let (v, nan) = binary_fast(op, ia, ib);
                    (out, v, nan || na || nb)
                }
                Op::BinaryRI { op, out, a, imm } => {
                    let (ia, na) = (r[a as usize], nr[a as usize]);
                    let (ib, nb) = imm_interval(imm);
                    if matches!(op, BinaryOp::Min | BinaryOp::Max) {
                        self.choices.push(choose(op, ia, na, ib, nb));
                    }
                    let (v, nan) = binary_fast(op, ia, ib);
                    (out, v, nan || na || nb)
                }
                Op::BinaryIR { op, out, imm, b } => {
                    let (ib, nb) = (r[b as usize], nr[b as usize]);
                    let (ia, na) = imm_interval(imm);
                    if matches!(op, BinaryOp::Min | BinaryOp::Max) {
                        self.choices.push(choose(op, ia, na, ib, nb));
                    }
                    let (v, nan) = binary_fast(op, ia, ib);
                    (out, v, nan || na || nb)
                }
                Op::Custom { k, out, args } => {
                    let ins = args.map(|a| r[a as usize]);
                    // A callback handed an unbounded box may meet infinite points, where
                    // its own arithmetic can give NaN (inf - inf): count that as possible.
                    let nan =
                        args.iter().any(|&a| nr[a as usize]) || ins.iter().any(|&i| unbounded(i));
                    if !nan {
                        self.custom_boxes.push((k, ins));
                    }
                    let v = tape.customs()[k as usize].interval(ins);
                    if v.is_empty() {
                        (out, Interval::ENTIRE, true)
                    } else {
                        (out, v, nan)
                    }
                }
            };
            let nan = nan || v.is_empty();
            r[out as usize] = if nan { Interval::ENTIRE } else { v };
            nr[out as usize] = nan;
        }
        let o = tape.output();
        (r[o], nr[o])
    }

    /// The choices of the last `eval`, one per min/max of its tape, in tape order.
    pub fn choices(&self) -> &[Choice] {
        &self.choices
    }

    /// Forgets the last choices, for a pass that decided without evaluating the tape:
    /// simplifying by no choices keeps the tape whole, which is right anywhere.
    pub(crate) fn forget_choices(&mut self) {
        self.choices.clear();
        self.custom_boxes.clear();
    }

    /// The input boxes of the custom nodes of the last `eval` (see [`Tape::narrow`]).
    pub(crate) fn custom_boxes(&self) -> &[(u32, [Interval; 3])] {
        &self.custom_boxes
    }
}

/// An immediate operand as an interval (NaN immediates are NaN everywhere; infinite ones
/// become the unbounded sliver next to them, as [`enclose::interval`] does).
#[inline(always)]
pub(crate) fn imm_interval(c: f64) -> (Interval, bool) {
    if c.is_finite() {
        // A finite point interval is always valid.
        (
            Interval::try_from((c, c)).unwrap_or(Interval::ENTIRE),
            false,
        )
    } else if c.is_nan() {
        (Interval::ENTIRE, true)
    } else {
        (enclose::interval(c, c), false)
    }
}
