//! `param(..)` and `bounds(..)`: what a script declares about itself, collected while it
//! runs and checked against the command line's overrides.

use std::sync::{Arc, Mutex};

use isoforge_field::Bounds;
use rhai::{Array, Dynamic, Engine, FLOAT, INT, ImmutableString};

use crate::args::{RhaiResult, fail, fail_with, number_arg, numbers_arg};
use crate::{Param, RuntimeCause};

/// What the script declared, and the overrides it is run with.
#[derive(Default, Debug)]
pub struct Declared {
    /// Parameter values the loader was given, by name.
    pub overrides: Vec<(String, f64)>,
    /// Parameters in the order the script declared them.
    pub params: Vec<Param>,
    /// The last `bounds(..)`.
    pub bounds: Option<Bounds>,
}

/// Shared between the engine's callbacks and the loader.
pub type Shared = Arc<Mutex<Declared>>;

fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, Declared> {
    // A poisoned lock only means an earlier callback panicked; the data is still sound.
    shared.lock().unwrap_or_else(|e| e.into_inner())
}

/// Registers `param` and `bounds`.
pub fn register(engine: &mut Engine, shared: &Shared) {
    let s = shared.clone();
    engine.register_fn(
        "param",
        move |name: ImmutableString, default: Dynamic| -> RhaiResult<Dynamic> {
            declare(&s, &name, &default, None)
        },
    );
    let s = shared.clone();
    engine.register_fn(
        "param",
        move |name: ImmutableString,
              default: Dynamic,
              min: Dynamic,
              max: Dynamic|
              -> RhaiResult<Dynamic> {
            let min = number_arg("param", 3, "min", &min)?;
            let max = number_arg("param", 4, "max", &max)?;
            if min.is_nan() || max.is_nan() || min > max {
                return Err(fail(format!(
                    "param \"{name}\": the range [{min}, {max}] is empty (min must not exceed max)"
                )));
            }
            declare(&s, &name, &default, Some((min, max)))
        },
    );
    let s = shared.clone();
    engine.register_fn("bounds", move |lo: Array, hi: Array| -> RhaiResult<()> {
        let lo = numbers_arg::<3>("bounds", 1, "[x0, y0, z0]", &lo)?;
        let hi = numbers_arg::<3>("bounds", 2, "[x1, y1, z1]", &hi)?;
        let b = Bounds::new(lo, hi).ok_or_else(|| {
            fail(format!(
                "bounds({lo:?}, {hi:?}): every minimum must be finite and below its maximum"
            ))
        })?;
        lock(&s).bounds = Some(b);
        Ok(())
    });
}

fn declare(
    shared: &Shared,
    name: &str,
    default: &Dynamic,
    range: Option<(f64, f64)>,
) -> RhaiResult<Dynamic> {
    let d = number_arg("param", 2, "default", default)?;
    if name.is_empty() {
        return Err(fail("param: the name must not be empty"));
    }
    let mut declared = lock(shared);
    let value = declared
        .overrides
        .iter()
        .rev()
        .find(|(n, _)| n == name)
        .map_or(d, |(_, v)| *v);
    if let Some((lo, hi)) = range {
        if !(lo..=hi).contains(&d) {
            return Err(fail(format!(
                "param \"{name}\": the default {d} is outside its range [{lo}, {hi}]"
            )));
        }
        if !(lo..=hi).contains(&value) {
            return Err(fail_with(RuntimeCause::ParamOutOfRange {
                name: name.to_string(),
                value,
                min: lo,
                max: hi,
            }));
        }
    }
    match declared.params.iter_mut().find(|p| p.name == name) {
        Some(p) if p.default != d || p.range != range => {
            return Err(fail(format!(
                "param \"{name}\" is declared twice with different defaults or ranges"
            )));
        }
        Some(_) => {}
        None => declared.params.push(Param {
            name: name.to_string(),
            default: d,
            value,
            range,
        }),
    }
    // An integer default stays an integer when the value is whole, so a parameter can be a
    // count (`curve_fol_sphere(f, param("n", 7), ..)`) or an array index.
    Ok(
        if default.is_int() && value.fract() == 0.0 && value.abs() < 9e15 {
            Dynamic::from_int(value as INT)
        } else {
            Dynamic::from_float(value as FLOAT)
        },
    )
}

/// The override names the script never declared: probably typos.
pub fn undeclared(declared: &Declared) -> Vec<String> {
    declared
        .overrides
        .iter()
        .filter(|(n, _)| !declared.params.iter().any(|p| &p.name == n))
        .map(|(n, _)| n.clone())
        .collect()
}
