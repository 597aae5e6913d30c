//! The interval gradient evaluator: over a box, an enclosure of the field's values and of
//! each partial derivative, by forward-mode differentiation in interval arithmetic.
//!
//! What it encloses is what [`crate::GradEval`] returns at the box's points, rule for rule:
//! `abs` has slope +1 at 0, `floor`/`ceil`/`round` have slope 0, `min`/`max` take the
//! slope of the side that won (the left on a tie). Where a value may be NaN, or a slope
//! NaN or infinite (`sqrt` at 0, `1/x` across 0, `0 * inf`), that slope is `ENTIRE`.
//!
//! Its use: a bound on |∇f| over a box, which turns a field's interval into an interval of
//! its first-order distance `f / |∇f|` (how `offset` and `shell` stay rigorous on fields
//! that are not distances).

use inari::Interval;

use crate::eval::enclose;
use crate::eval::interval::{binary, choose, imm_interval, unary};
use crate::op::{BinaryOp, UnaryOp};
use crate::shape::Var;
use crate::tape::{Choice, Op, Tape};

/// Relative widening of |∇f| bounds (about 4.5 ulps), for the rounding of a point
/// evaluator's `sqrt(dx² + dy² + dz²)` and of the bound's own arithmetic.
const SLOPE_MARGIN_UP: f64 = 1.0 + 1e-15;
const SLOPE_MARGIN_DOWN: f64 = 1.0 - 1e-15;

/// A value's enclosure with its partial derivatives' enclosures.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct IntervalGrad {
    /// The values (`ENTIRE` where NaN is possible).
    pub v: Interval,
    /// The partial derivatives d/dx, d/dy, d/dz.
    pub d: [Interval; 3],
}

impl IntervalGrad {
    /// An upper bound of |∇f| over the box (`+inf` when a slope is unbounded).
    pub fn slope_bound(&self) -> f64 {
        let mags = self.d.map(|d| d.mag());
        let sq: f64 = mags.iter().map(|m| m * m).sum();
        if sq.is_finite() {
            // Widened by 4 ulps: the three squares and two sums a point evaluator rounds
            // (half an ulp each) and the square root (half an ulp) stay inside.
            sq.sqrt() * SLOPE_MARGIN_UP
        } else {
            f64::INFINITY
        }
    }

    /// A lower bound of |∇f| over the box (0 when some point may have no slope).
    pub fn slope_floor(&self) -> f64 {
        let migs = self.d.map(|d| if d.is_empty() { 0.0 } else { d.mig() });
        let sq: f64 = migs.iter().map(|m| m * m).sum();
        if sq.is_finite() {
            sq.sqrt() * SLOPE_MARGIN_DOWN
        } else {
            0.0
        }
    }
}

#[derive(Copy, Clone)]
struct Reg {
    v: Interval,
    nan: bool,
    d: [Interval; 3],
}

const ZERO: Interval = inari::const_interval!(0.0, 0.0);
const ONE: Interval = inari::const_interval!(1.0, 1.0);
const ENTIRE: Interval = Interval::ENTIRE;

impl Reg {
    fn constant(v: Interval, nan: bool) -> Reg {
        Reg {
            v,
            nan,
            d: [ZERO; 3],
        }
    }
}

/// `a op b` as a slope: `ENTIRE` wherever the operation could give NaN.
fn op(o: BinaryOp, a: Interval, b: Interval) -> Interval {
    match binary(o, a, b) {
        (_, true) => ENTIRE,
        (v, false) => v,
    }
}
fn mul(a: Interval, b: Interval) -> Interval {
    op(BinaryOp::Mul, a, b)
}
fn add(a: Interval, b: Interval) -> Interval {
    op(BinaryOp::Add, a, b)
}
fn sub(a: Interval, b: Interval) -> Interval {
    op(BinaryOp::Sub, a, b)
}
fn div(a: Interval, b: Interval) -> Interval {
    op(BinaryOp::Div, a, b)
}
/// The result of an enclosure function as a slope factor.
fn factor((v, nan): (Interval, bool)) -> Interval {
    if nan { ENTIRE } else { v }
}

/// The slope of a unary operation at `a`, as a factor on the argument's slope.
fn unary_slope(o: UnaryOp, a: Interval) -> Interval {
    match o {
        UnaryOp::Neg => -ONE,
        UnaryOp::Abs => {
            // GradEval: -1 below zero, +1 at and above (-0 included).
            if a.sup() < 0.0 {
                -ONE
            } else if a.inf() >= 0.0 {
                ONE
            } else {
                enclose::interval(-1.0, 1.0)
            }
        }
        UnaryOp::Recip => {
            if enclose::has_zero(a) {
                ENTIRE
            } else {
                -(a.recip().sqr())
            }
        }
        UnaryOp::Sqrt => {
            if a.inf() > 0.0 {
                div(enclose::interval(0.5, 0.5), a.sqrt())
            } else {
                ENTIRE
            }
        }
        UnaryOp::Square => mul(enclose::interval(2.0, 2.0), a),
        UnaryOp::Sin => factor(enclose::cos(a)),
        UnaryOp::Cos => -factor(enclose::sin(a)),
        UnaryOp::Tan => {
            let t = factor(enclose::tan(a));
            add(ONE, t.sqr())
        }
        UnaryOp::Asin | UnaryOp::Acos => {
            let k = if a.inf() > -1.0 && a.sup() < 1.0 {
                let inner = sub(ONE, a.sqr());
                if inner.inf() > 0.0 {
                    inner.sqrt().recip()
                } else {
                    ENTIRE
                }
            } else {
                ENTIRE
            };
            if o == UnaryOp::Asin { k } else { -k }
        }
        UnaryOp::Atan => add(ONE, a.sqr()).recip(),
        UnaryOp::Exp => factor(enclose::exp(a)),
        UnaryOp::Ln => {
            if a.inf() > 0.0 {
                a.recip()
            } else {
                ENTIRE
            }
        }
        UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round => ZERO,
        UnaryOp::PowI(n) => {
            let p = factor(enclose::powi(a, n - 1));
            mul(enclose::interval(n as f64, n as f64), p)
        }
    }
}

fn unary_reg(o: UnaryOp, a: Reg) -> Reg {
    let (v, nan) = unary(o, a.v);
    let nan = nan || a.nan;
    if matches!(o, UnaryOp::Floor | UnaryOp::Ceil | UnaryOp::Round) && !nan {
        // GradEval gives these slope 0 even where the argument's slope is infinite.
        return Reg::constant(v, false);
    }
    let k = unary_slope(o, a.v);
    Reg {
        v,
        nan,
        d: a.d.map(|d| mul(k, d)),
    }
}

fn binary_reg(o: BinaryOp, a: Reg, b: Reg) -> Reg {
    let (v, nan) = binary(o, a.v, b.v);
    let nan = nan || a.nan || b.nan;
    let zip = |f: &dyn Fn(Interval, Interval) -> Interval| [0, 1, 2].map(|i| f(a.d[i], b.d[i]));
    let d = match o {
        BinaryOp::Add => zip(&add),
        BinaryOp::Sub => zip(&sub),
        BinaryOp::Mul => zip(&|p, q| add(mul(p, b.v), mul(a.v, q))),
        BinaryOp::Div => {
            let den = b.v.sqr();
            zip(&|p, q| div(sub(mul(p, b.v), mul(a.v, q)), den))
        }
        BinaryOp::Min | BinaryOp::Max => match choose(o, a.v, a.nan, b.v, b.nan) {
            Choice::Left => a.d,
            Choice::Right => b.d,
            Choice::Both => zip(&|p, q| p.convex_hull(q)),
        },
        BinaryOp::Atan2 => {
            let r2 = add(a.v.sqr(), b.v.sqr());
            zip(&|dy, dx| div(sub(mul(b.v, dy), mul(a.v, dx)), r2))
        }
        BinaryOp::Pow => {
            let bm1 = sub(b.v, ONE);
            let ka = mul(b.v, factor(enclose::pow(a.v, bm1)));
            let kb = mul(factor(enclose::pow(a.v, b.v)), factor(enclose::ln(a.v)));
            zip(&|p, q| {
                if q == ZERO {
                    mul(ka, p)
                } else {
                    add(mul(ka, p), mul(kb, q))
                }
            })
        }
        BinaryOp::Mod => {
            let f = div(a.v, b.v).floor();
            zip(&|p, q| sub(p, mul(f, q)))
        }
    };
    Reg { v, nan, d }
}

/// Evaluates value and slope enclosures over a box. Reuse one per thread.
#[derive(Default)]
pub struct IntervalGradEval {
    regs: Vec<Reg>,
}

impl IntervalGradEval {
    /// A new evaluator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Enclosures of f and of its partial derivatives over the box `b`.
    pub fn eval(&mut self, tape: &Tape, b: [Interval; 3]) -> IntervalGrad {
        let n = tape.register_count();
        if self.regs.len() < n {
            self.regs.resize(n, Reg::constant(ENTIRE, true));
        }
        let r = &mut self.regs[..];
        for o in tape.ops() {
            let (out, reg) = match *o {
                Op::Var { out, v } => {
                    let (i, iv) = match v {
                        Var::X => (0, b[0]),
                        Var::Y => (1, b[1]),
                        Var::Z => (2, b[2]),
                    };
                    let mut d = [ZERO; 3];
                    d[i] = ONE;
                    (
                        out,
                        Reg {
                            v: iv,
                            nan: iv.is_empty(),
                            d,
                        },
                    )
                }
                Op::Const { out, c } => {
                    let (v, nan) = imm_interval(c);
                    (out, Reg::constant(v, nan))
                }
                Op::Copy { out, a } => (out, r[a as usize]),
                Op::Unary { op, out, a } => (out, unary_reg(op, r[a as usize])),
                Op::Binary { op, out, a, b } => (out, binary_reg(op, r[a as usize], r[b as usize])),
                Op::BinaryRI { op, out, a, imm } => {
                    let (c, nan) = imm_interval(imm);
                    (out, binary_reg(op, r[a as usize], Reg::constant(c, nan)))
                }
                Op::BinaryIR { op, out, imm, b } => {
                    let (c, nan) = imm_interval(imm);
                    (out, binary_reg(op, Reg::constant(c, nan), r[b as usize]))
                }
                Op::Custom { k, out, args } => {
                    let ins = args.map(|a| r[a as usize]);
                    let boxed = ins.map(|i| i.v);
                    let f = &tape.customs()[k as usize];
                    let v = f.interval(boxed);
                    // As in IntervalEval: an unbounded box may meet infinite points.
                    let nan = ins.iter().any(|i| i.nan || enclose::unbounded(i.v)) || v.is_empty();
                    let g = f.interval_gradient(boxed);
                    let d = [0, 1, 2].map(|j| {
                        let terms = [0, 1, 2].map(|k| mul(g[k], ins[k].d[j]));
                        add(add(terms[0], terms[1]), terms[2])
                    });
                    (out, Reg { v, nan, d })
                }
            };
            r[out as usize] = if reg.nan || reg.v.is_empty() {
                Reg {
                    v: ENTIRE,
                    nan: true,
                    d: [ENTIRE; 3],
                }
            } else {
                Reg {
                    d: reg.d.map(|d| if d.is_empty() { ENTIRE } else { d }),
                    ..reg
                }
            };
        }
        let o = r[tape.output()];
        IntervalGrad { v: o.v, d: o.d }
    }
}
