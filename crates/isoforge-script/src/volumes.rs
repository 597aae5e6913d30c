//! Metaballs and the function volumes (Functy's three classes) in scripts.
//!
//! The function volumes take script closures of ordinary math and call them once with
//! fields in place of numbers (`|x, y| sin(x) * cos(y)` is called with the coordinates
//! x and y as shapes), so what they return is a field expression: it runs at kernel
//! speed, never back through the script per point.

use isoforge_field::Shape;
use isoforge_shapes::functions::{cartesian, spherical, spherical_angles};
use isoforge_shapes::metaballs::{DEFAULT_REACH, Falloff, metaballs};
use isoforge_shapes::tube::curve_tube;
use rhai::{Array, Dynamic, Engine, EvalAltResult, FnPtr, FuncArgs, Map, NativeCallContext};

use crate::args::{RhaiResult, as_number, fail, number_arg, type_name};
use crate::facts::{Fact, SharedFacts, lock};
use crate::modern::vec3;
use crate::options::Options;

/// Registers `metaballs`, `cartesian`, `spherical` and `curve_tube`.
pub fn register(engine: &mut Engine, facts: &SharedFacts) {
    register_functions(engine, facts);
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

/// Calls a script closure once with fields for its arguments. An operation it uses that
/// has no meaning on fields (a comparison, `if` on an argument) gets an error that says so.
fn call_with_fields(
    ctx: &NativeCallContext,
    func: &str,
    what: &str,
    f: &FnPtr,
    args: impl FuncArgs,
) -> RhaiResult<Dynamic> {
    f.call_within_context::<Dynamic>(ctx, args).map_err(|e| {
        let mut inner: &EvalAltResult = &e;
        while let EvalAltResult::ErrorInFunctionCall(_, _, next, _) = inner {
            inner = next;
        }
        match inner {
            EvalAltResult::ErrorFunctionNotFound(sig, _) if sig.contains("Shape") => fail(format!(
                "{func}: the {what} must be ordinary math on its arguments: it is run once with \
                 fields in place of numbers, so it becomes a field expression, and `{sig}` has \
                 no meaning on fields (a comparison or an `if` on an argument cannot become a \
                 field)"
            )),
            _ => e,
        }
    })
}

/// A closure's result as a field: a shape, or a number (a constant field).
fn as_field(func: &str, what: &str, d: &Dynamic) -> RhaiResult<Shape> {
    if let Some(s) = d.clone().try_cast::<Shape>() {
        return Ok(s);
    }
    match as_number(d) {
        Some(v) => Ok(Shape::constant(v)),
        None => Err(fail(format!(
            "{func}: the {what} must return a number, not {}",
            type_name(d)
        ))),
    }
}

fn register_functions(engine: &mut Engine, facts: &SharedFacts) {
    engine.register_fn(
        "cartesian",
        |ctx: NativeCallContext, f: FnPtr, thickness: Dynamic| -> RhaiResult<Shape> {
            let thickness = number_arg("cartesian", 2, "thickness", &thickness)?;
            let h = call_with_fields(
                &ctx,
                "cartesian",
                "height function |x, y|",
                &f,
                (Shape::x(), Shape::y()),
            )?;
            let h = as_field("cartesian", "height function", &h)?;
            cartesian(&h, thickness).map_err(|e| fail(format!("cartesian: {e}")))
        },
    );
    fn spherical_call(
        ctx: &NativeCallContext,
        f: &FnPtr,
        centre: [f64; 3],
        mut o: Options,
    ) -> RhaiResult<Shape> {
        let thickness = o.number("thickness")?.unwrap_or(0.0);
        o.finish()?;
        let (theta, phi) = spherical_angles(centre).map_err(|e| fail(format!("spherical: {e}")))?;
        let r = call_with_fields(
            ctx,
            "spherical",
            "radius function |theta, phi|",
            f,
            (theta, phi),
        )?;
        let r = as_field("spherical", "radius function", &r)?;
        spherical(&r, centre, thickness).map_err(|e| fail(format!("spherical: {e}")))
    }
    engine.register_fn("spherical", |ctx: NativeCallContext, f: FnPtr| {
        spherical_call(&ctx, &f, [0.0; 3], Options::none("spherical"))
    });
    engine.register_fn(
        "spherical",
        |ctx: NativeCallContext, f: FnPtr, centre: Dynamic| -> RhaiResult<Shape> {
            let centre = vec3("spherical", 2, "centre", &centre)?;
            spherical_call(&ctx, &f, centre, Options::none("spherical"))
        },
    );
    engine.register_fn(
        "spherical",
        |ctx: NativeCallContext, f: FnPtr, centre: Dynamic, options: Map| -> RhaiResult<Shape> {
            let centre = vec3("spherical", 2, "centre", &centre)?;
            spherical_call(&ctx, &f, centre, Options::new("spherical", options))
        },
    );
    let facts = facts.clone();
    engine.register_fn(
        "curve_tube",
        move |ctx: NativeCallContext,
              curve: FnPtr,
              radius: Dynamic,
              s0: Dynamic,
              s1: Dynamic|
              -> RhaiResult<Shape> {
            let name = "curve_tube";
            let s0 = number_arg(name, 3, "s0", &s0)?;
            let s1 = number_arg(name, 4, "s1", &s1)?;
            let point = call_with_fields(&ctx, name, "curve |s|", &curve, (Shape::x(),))?;
            let coords = point
                .clone()
                .try_cast::<Array>()
                .filter(|a| a.len() == 3)
                .ok_or_else(|| {
                    fail(format!(
                        "{name}: the curve must return [x, y, z], not {}",
                        type_name(&point)
                    ))
                })?;
            let coords = [0, 1, 2].map(|i| as_field(name, "curve's coordinate", &coords[i]));
            let [cx, cy, cz] = coords;
            let curve = [cx?, cy?, cz?];
            let radius = match radius.clone().try_cast::<FnPtr>() {
                Some(f) => {
                    let r = call_with_fields(
                        &ctx,
                        name,
                        "radius |s, theta|",
                        &f,
                        (Shape::x(), Shape::y()),
                    )?;
                    as_field(name, "radius", &r)?
                }
                None => Shape::constant(number_arg(name, 2, "radius", &radius)?),
            };
            let (shape, exact) =
                curve_tube(curve, &radius, s0, s1).map_err(|e| fail(format!("{name}: {e}")))?;
            Ok(lock(&facts).note(
                shape,
                Fact {
                    distance: exact,
                    convex: None,
                },
            ))
        },
    );
}
