//! Turning script values into library arguments, with errors that say which argument of
//! which function was wrong.

use isoforge_field::Shape;
use rhai::{Array, Dynamic, EvalAltResult, INT, Position};

/// A script-level result.
pub type RhaiResult<T> = Result<T, Box<EvalAltResult>>;

/// A runtime error; rhai fills in the position of the call that raised it.
pub fn fail(message: impl Into<String>) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(message.into()),
        Position::NONE,
    ))
}

/// A runtime error with a typed cause, which the loader reports as that cause (see
/// `rhai_errors::describe`); rhai fills in the position as for [`fail`].
pub fn fail_with(cause: crate::RuntimeCause) -> Box<EvalAltResult> {
    Box::new(EvalAltResult::ErrorRuntime(
        Dynamic::from(cause),
        Position::NONE,
    ))
}

/// A script type's name as users see it.
pub fn type_name(d: &Dynamic) -> &'static str {
    if d.is::<Shape>() {
        "a shape"
    } else if d.is_int() || d.is_float() {
        "a number"
    } else if d.is_string() {
        "a string"
    } else if d.is_array() {
        "an array"
    } else if d.is_unit() {
        "nothing (`()`)"
    } else if d.is_bool() {
        "a boolean"
    } else if d.is_map() {
        "an object map"
    } else if d.is_fnptr() {
        "a function"
    } else if d.is::<isoforge_shapes::profile::Profile>() {
        "a 2D profile (sweep it into a solid: linear_sweep, revolve, ...)"
    } else if d.is::<isoforge_shapes::texture::Texture>() {
        "a texture"
    } else {
        "a value of another kind"
    }
}

/// A number, if `d` is one (INT or FLOAT).
pub fn as_number(d: &Dynamic) -> Option<f64> {
    if let Ok(i) = d.as_int() {
        Some(i as f64)
    } else {
        d.as_float().ok()
    }
}

/// A shape, or a number made into a constant field.
pub fn shape_arg(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<Shape> {
    if let Some(s) = d.clone().try_cast::<Shape>() {
        return Ok(s);
    }
    match as_number(d) {
        Some(v) => Ok(Shape::constant(v)),
        None => Err(fail(format!(
            "{func}: argument {index} (`{name}`) must be a number or a shape, not {}",
            type_name(d)
        ))),
    }
}

/// A number (INT or FLOAT).
pub fn number_arg(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<f64> {
    as_number(d).ok_or_else(|| {
        fail(format!(
            "{func}: argument {index} (`{name}`) must be a number, not {}",
            type_name(d)
        ))
    })
}

/// A whole number (an INT, or a FLOAT with no fraction).
pub fn count_arg(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<INT> {
    if let Ok(i) = d.as_int() {
        return Ok(i);
    }
    match d.as_float() {
        Ok(f) if f.fract() == 0.0 && f.abs() < 1e15 => Ok(f as INT),
        _ => Err(fail(format!(
            "{func}: argument {index} (`{name}`) must be a whole number, not {}",
            match as_number(d) {
                Some(v) => format!("{v}"),
                None => type_name(d).to_string(),
            }
        ))),
    }
}

/// An array of exactly `N` numbers.
pub fn numbers_arg<const N: usize>(
    func: &str,
    index: usize,
    name: &str,
    a: &Array,
) -> RhaiResult<[f64; N]> {
    let wrong = || {
        fail(format!(
            "{func}: argument {index} (`{name}`) must be an array of {N} numbers"
        ))
    };
    if a.len() != N {
        return Err(wrong());
    }
    let mut out = [0.0; N];
    for (o, d) in out.iter_mut().zip(a) {
        *o = as_number(d).ok_or_else(wrong)?;
    }
    Ok(out)
}

/// A number or a shape as a script value: a number stays a FLOAT.
pub fn number_or_shape(value: Result<f64, Shape>) -> Dynamic {
    match value {
        Ok(v) => Dynamic::from_float(v),
        Err(s) => Dynamic::from(s),
    }
}
