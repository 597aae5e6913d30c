//! The operations a field is built from.

/// An operation with one argument.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum UnaryOp {
    /// `-a`
    Neg,
    /// `|a|`
    Abs,
    /// `1 / a`
    Recip,
    /// `sqrt(a)`; NaN below zero
    Sqrt,
    /// `a * a`
    Square,
    /// `sin(a)`
    Sin,
    /// `cos(a)`
    Cos,
    /// `tan(a)`
    Tan,
    /// `asin(a)`; NaN outside [-1, 1]
    Asin,
    /// `acos(a)`; NaN outside [-1, 1]
    Acos,
    /// `atan(a)`
    Atan,
    /// `e^a`
    Exp,
    /// natural logarithm; NaN below zero, -inf at zero
    Ln,
    /// round towards -inf
    Floor,
    /// round towards +inf
    Ceil,
    /// round to nearest, half away from zero
    Round,
    /// `a^n` for a whole number n (negative allowed)
    PowI(i32),
}

/// An operation with two arguments.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum BinaryOp {
    /// `a + b`
    Add,
    /// `a - b`
    Sub,
    /// `a * b`
    Mul,
    /// `a / b`
    Div,
    /// the smaller of a and b (a choice point for tape simplification)
    Min,
    /// the larger of a and b (a choice point for tape simplification)
    Max,
    /// `atan2(a, b)`: the angle of the point (b, a)
    Atan2,
    /// `a^b` for real b; NaN for a negative base
    Pow,
    /// `a - b * floor(a / b)`: Euclidean-style modulo, the sign of b
    Mod,
}
