//! Metaballs and the function volumes (Functy's three classes) in scripts.
//!
//! The function volumes take script closures of ordinary math and call them once with
//! fields in place of numbers (`|x, y| sin(x) * cos(y)` is called with the coordinates
//! x and y as shapes), so what they return is a field expression: it runs at kernel
//! speed, never back through the script per point.

use isoforge_field::Shape;
use isoforge_shapes::metaballs::{DEFAULT_REACH, Falloff, metaballs};
use rhai::{Array, Dynamic, Engine, Map};

use crate::args::{RhaiResult, as_number, fail, number_arg, type_name};
use crate::options::Options;

/// Registers `metaballs`, `cartesian`, `spherical` and `curve_tube`.
pub fn register(engine: &mut Engine) {
    engine.register_fn("metaballs", |balls: Dynamic, threshold: Dynamic| {
        metaballs_call(&balls, &threshold, Options::none("metaballs"))
    });
    engine.register_fn(
        "metaballs",
        |balls: Dynamic, threshold: Dynamic, options: Map| {
            metaballs_call(&balls, &threshold, Options::new("metaballs", options))
        },
    );
}

/// `[[x, y, z, r], ..]` as numbers, the error naming the ball that is wrong.
fn ball_list(d: &Dynamic) -> RhaiResult<Vec<[f64; 4]>> {
    let list = d.clone().try_cast::<Array>().ok_or_else(|| {
        fail(format!(
            "metaballs: argument 1 (`balls`) must be an array of [x, y, z, r], not {}",
            type_name(d)
        ))
    })?;
    list.iter()
        .enumerate()
        .map(|(i, b)| {
            let wrong = || {
                fail(format!(
                    "metaballs: ball {} must be [x, y, z, r] (four numbers), not {}",
                    i + 1,
                    type_name(b)
                ))
            };
            let a = b.clone().try_cast::<Array>().ok_or_else(wrong)?;
            if a.len() != 4 {
                return Err(wrong());
            }
            let mut out = [0.0; 4];
            for (o, v) in out.iter_mut().zip(&a) {
                *o = as_number(v).ok_or_else(wrong)?;
            }
            Ok(out)
        })
        .collect()
}

fn metaballs_call(balls: &Dynamic, threshold: &Dynamic, mut o: Options) -> RhaiResult<Shape> {
    let balls = ball_list(balls)?;
    let threshold = number_arg("metaballs", 2, "threshold", threshold)?;
    let falloff = o
        .choice("falloff", &["blinn", "wyvill"])?
        .unwrap_or("blinn");
    let reach = o.number("reach")?;
    o.finish()?;
    let falloff = match (falloff, reach) {
        ("wyvill", reach) => Falloff::Wyvill {
            reach: reach.unwrap_or(DEFAULT_REACH),
        },
        (_, Some(_)) => {
            return Err(fail(
                "metaballs: option `reach` belongs to the compact falloff: add falloff: \"wyvill\"",
            ));
        }
        _ => Falloff::Blinn,
    };
    metaballs(&balls, threshold, falloff).map_err(|e| fail(format!("metaballs: {e}")))
}
