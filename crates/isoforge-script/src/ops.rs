//! Arithmetic and math for scripts: numbers and Shapes mix in `+ - * /`, unary `-` and `^`,
//! and the math functions take either (`sin(2.0)` is a number, `sin(x)` a Shape).
//!
//! Needs `Engine::set_fast_operators(false)`, or rhai would run its built-in integer `/`
//! (9/4 == 2) and `^` (exclusive or) without looking at what is registered here.

use isoforge_field::Shape;
use rhai::{Dynamic, Engine, FLOAT, INT};

use crate::args::{RhaiResult, as_number, fail, number_or_shape, type_name};

/// Registers operators and math functions.
pub fn register(engine: &mut Engine) {
    register_arithmetic(engine);
    register_power(engine);
    register_math(engine);
}

macro_rules! mixed_operator {
    ($engine:expr, $name:literal, $op:tt) => {
        $engine.register_fn($name, |a: Shape, b: Shape| &a $op &b);
        $engine.register_fn($name, |a: Shape, b: INT| &a $op (b as f64));
        $engine.register_fn($name, |a: INT, b: Shape| (a as f64) $op &b);
        $engine.register_fn($name, |a: Shape, b: FLOAT| &a $op b);
        $engine.register_fn($name, |a: FLOAT, b: Shape| a $op &b);
    };
}

fn register_arithmetic(engine: &mut Engine) {
    mixed_operator!(engine, "+", +);
    mixed_operator!(engine, "-", -);
    mixed_operator!(engine, "*", *);
    mixed_operator!(engine, "/", /);
    // `%` on Shapes is the floored modulo (the sign of the divisor); on numbers it stays
    // rhai's remainder, which is not overridden.
    engine.register_fn("%", |a: Shape, b: Shape| a.modulo(&b));
    engine.register_fn("%", |a: Shape, b: INT| a.modulo(&Shape::constant(b as f64)));
    engine.register_fn("%", |a: Shape, b: FLOAT| a.modulo(&Shape::constant(b)));
    engine.register_fn("%", |a: INT, b: Shape| Shape::constant(a as f64).modulo(&b));
    engine.register_fn("%", |a: FLOAT, b: Shape| Shape::constant(a).modulo(&b));
    engine.register_fn("-", |a: Shape| -a);
    engine.register_fn("+", |a: Shape| a);
    // Division of two integers is real division, as in the math the models come from.
    engine.register_fn("/", |a: INT, b: INT| a as FLOAT / b as FLOAT);
}

/// `a^b` on integers: an integer while it fits, else real.
fn int_pow(a: INT, b: INT) -> Dynamic {
    if let Ok(e) = u32::try_from(b)
        && let Some(v) = a.checked_pow(e)
    {
        return Dynamic::from_int(v);
    }
    Dynamic::from_float((a as FLOAT).powf(b as FLOAT))
}

/// Rhai's power operator, which scripts write as `^`.
const POW: &str = "**";

fn register_power(engine: &mut Engine) {
    // Scripts write `^`; the notation pass turns it into rhai's `**` (see notation.rs).
    engine.register_fn(POW, int_pow);
    engine.register_fn(POW, |a: FLOAT, b: FLOAT| a.powf(b));
    engine.register_fn(POW, |a: INT, b: FLOAT| (a as FLOAT).powf(b));
    engine.register_fn(POW, |a: FLOAT, b: INT| pow_f_i(a, b));
    engine.register_fn(POW, |a: Shape, b: Shape| a.pow(&b));
    engine.register_fn(POW, |a: Shape, b: INT| a.pow(&Shape::constant(b as f64)));
    engine.register_fn(POW, |a: Shape, b: FLOAT| a.pow(&Shape::constant(b)));
    engine.register_fn(POW, |a: INT, b: Shape| Shape::constant(a as f64).pow(&b));
    engine.register_fn(POW, |a: FLOAT, b: Shape| Shape::constant(a).pow(&b));
}

fn pow_f_i(a: FLOAT, b: INT) -> FLOAT {
    match i32::try_from(b) {
        Ok(n) => a.powi(n),
        Err(_) => a.powf(b as FLOAT),
    }
}

/// A number or a Shape, taken apart.
fn split(func: &str, d: &Dynamic) -> RhaiResult<Result<f64, Shape>> {
    if let Some(s) = d.clone().try_cast::<Shape>() {
        return Ok(Err(s));
    }
    as_number(d).map(Ok).ok_or_else(|| {
        fail(format!(
            "{func}: expected a number or a shape, not {}",
            type_name(d)
        ))
    })
}

fn unary(engine: &mut Engine, name: &'static str, num: fn(f64) -> f64, shape: fn(&Shape) -> Shape) {
    engine.register_fn(name, move |a: Dynamic| -> RhaiResult<Dynamic> {
        Ok(number_or_shape(
            split(name, &a)?.map(num).map_err(|s| shape(&s)),
        ))
    });
}

fn binary(
    engine: &mut Engine,
    name: &'static str,
    num: fn(f64, f64) -> f64,
    shape: fn(&Shape, &Shape) -> Shape,
) {
    engine.register_fn(name, move |a: Dynamic, b: Dynamic| -> RhaiResult<Dynamic> {
        Ok(match (split(name, &a)?, split(name, &b)?) {
            (Ok(a), Ok(b)) => Dynamic::from_float(num(a, b)),
            (a, b) => Dynamic::from(shape(&into_shape(a), &into_shape(b))),
        })
    });
}

fn into_shape(v: Result<f64, Shape>) -> Shape {
    match v {
        Ok(n) => Shape::constant(n),
        Err(s) => s,
    }
}

fn register_math(engine: &mut Engine) {
    unary(engine, "sin", f64::sin, Shape::sin);
    unary(engine, "cos", f64::cos, Shape::cos);
    unary(engine, "tan", f64::tan, Shape::tan);
    unary(engine, "asin", f64::asin, Shape::asin);
    unary(engine, "acos", f64::acos, Shape::acos);
    unary(engine, "atan", f64::atan, Shape::atan);
    unary(engine, "exp", f64::exp, Shape::exp);
    unary(engine, "ln", f64::ln, Shape::ln);
    unary(engine, "sqrt", f64::sqrt, Shape::sqrt);
    unary(engine, "abs", f64::abs, Shape::abs);
    unary(engine, "square", |a| a * a, Shape::square);
    unary(engine, "floor", f64::floor, Shape::floor);
    unary(engine, "ceil", f64::ceil, Shape::ceil);
    unary(engine, "round", f64::round, Shape::round);
    unary(engine, "DegToRad", f64::to_radians, |s| {
        isoforge_shapes::classic::deg_to_rad(s.clone())
    });
    binary(engine, "atan2", f64::atan2, Shape::atan2);
    binary(engine, "pow", f64::powf, Shape::pow);
    binary(engine, "min", f64::min, Shape::min);
    binary(engine, "max", f64::max, Shape::max);
}
