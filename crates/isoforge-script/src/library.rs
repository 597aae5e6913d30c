//! The classic library in scripts: every name of docs/language.md's classic section, bound to
//! `isoforge_shapes`. Numeric arguments accept numbers or Shapes (a radius may vary).

use isoforge_field::Shape;
use isoforge_shapes::classic;
use isoforge_shapes::curve;
use rhai::{Array, Dynamic, Engine, EvalAltResult, FnPtr, NativeCallContext};
use std::cell::RefCell;

use crate::args::{RhaiResult, count_arg, fail, number_arg, numbers_arg, shape_arg};

macro_rules! register_shapes {
    ($engine:expr, $name:literal, [$($arg:ident),+], $body:expr) => {{
        $engine.register_fn($name, |$($arg: Dynamic),+| -> RhaiResult<Shape> {
            let mut _index = 0;
            $(
                _index += 1;
                let $arg = shape_arg($name, _index, stringify!($arg), &$arg)?;
            )+
            Ok($body)
        });
    }};
}

/// Registers the primitives, transforms, combinations and curve followers.
pub fn register(engine: &mut Engine) {
    register_primitives(engine);
    register_transforms(engine);
    register_combinations(engine);
    register_curve_followers(engine);
}

fn register_primitives(engine: &mut Engine) {
    register_shapes!(engine, "Sphere", [a], classic::sphere(a));
    register_shapes!(engine, "Cube", [h], classic::cube(h));
    register_shapes!(engine, "Prism", [a, b, c], classic::prism(a, b, c));
    register_shapes!(engine, "Torus", [a, b], classic::torus(a, b));
    register_shapes!(engine, "Cyl", [a, b, c], classic::cyl(a, b, c));
    register_shapes!(engine, "Cyyl", [a, b, c], classic::cyl(a, b, c));
    register_shapes!(engine, "Cone", [a, b, c], classic::cone(a, b, c));
    register_shapes!(engine, "Ellip", [a, b, c], classic::ellip(a, b, c));
    register_shapes!(engine, "Para", [a, b, c], classic::para(a, b, c));
    register_shapes!(engine, "Close", [s, b], classic::close(s, b));
    register_shapes!(engine, "HSpace", [h], classic::hspace(h));
    register_shapes!(
        engine,
        "Tetrahedral",
        [a, b, c],
        classic::tetrahedral(a, b, c)
    );
    register_shapes!(engine, "Sinus", [r, h], classic::sinus(r, h));
    register_shapes!(engine, "Bug", [a, b, c], classic::bug(a, b, c));
    register_shapes!(engine, "Drope", [h], classic::drope(h));
    register_shapes!(
        engine,
        "Heart",
        [a, b, c, d, e],
        classic::heart(a, b, c, d, e)
    );
}

fn register_transforms(engine: &mut Engine) {
    register_shapes!(engine, "TransX", [s, t], classic::trans_x(&s, t));
    register_shapes!(engine, "TransY", [s, t], classic::trans_y(&s, t));
    register_shapes!(engine, "TransZ", [s, t], classic::trans_z(&s, t));
    register_shapes!(engine, "ScaleX", [s, k], classic::scale_x(&s, k));
    register_shapes!(engine, "ScaleY", [s, k], classic::scale_y(&s, k));
    register_shapes!(engine, "ScaleZ", [s, k], classic::scale_z(&s, k));
    register_shapes!(engine, "ScaleXYZ", [s, k], classic::scale_xyz(&s, k));
    register_shapes!(engine, "ReflectXY", [s], classic::reflect_xy(&s));
    register_shapes!(engine, "ReflectZX", [s], classic::reflect_zx(&s));
    register_shapes!(engine, "ReflectYZ", [s], classic::reflect_yz(&s));
    register_shapes!(engine, "RotateRX", [s, r], classic::rotate_rx(&s, r));
    register_shapes!(engine, "RotateRY", [s, r], classic::rotate_ry(&s, r));
    register_shapes!(engine, "RotateRZ", [s, r], classic::rotate_rz(&s, r));
    register_shapes!(
        engine,
        "RotateX",
        [s, degrees],
        classic::rotate_x(&s, degrees)
    );
    register_shapes!(
        engine,
        "RotateY",
        [s, degrees],
        classic::rotate_y(&s, degrees)
    );
    register_shapes!(
        engine,
        "RotateZ",
        [s, degrees],
        classic::rotate_z(&s, degrees)
    );
}

fn register_combinations(engine: &mut Engine) {
    register_shapes!(engine, "Union", [a, b], classic::union(&a, &b));
    register_shapes!(engine, "Intersect", [a, b], classic::intersect(&a, &b));
    register_shapes!(engine, "Subtract", [a, b], classic::subtract(&a, &b));
    register_shapes!(engine, "Morph", [a, b, t], classic::morph(&a, &b, t));
    register_shapes!(engine, "Blend", [a, b, l], classic::blend(&a, &b, l));
    register_shapes!(engine, "Combine", [a, b, k], classic::combine(&a, &b, k));
    register_shapes!(engine, "Max", [a, b], classic::max(&a, &b));
    register_shapes!(engine, "Min", [a, b], classic::min(&a, &b));
}

/// Calls the script's curve closure at `t`; it must give `[x, y, z]`.
fn call_curve(ctx: &NativeCallContext, func: &str, f: &FnPtr, t: f64) -> RhaiResult<[f64; 3]> {
    let value: Dynamic = f.call_within_context(ctx, (t,))?;
    let Some(point) = value.clone().try_cast::<Array>() else {
        return Err(fail(format!(
            "{func}: the curve must return [x, y, z], but at t = {t} it returned {}",
            crate::args::type_name(&value)
        )));
    };
    numbers_arg::<3>(func, 1, "f(t)", &point)
}

/// Runs a curve follower with the script's closure as the curve. The closure is called
/// only here, while the graph is built; the first error it raises stops the build.
fn follow(
    ctx: &NativeCallContext,
    func: &str,
    f: &FnPtr,
    build: impl FnOnce(&dyn Fn(f64) -> [f64; 3]) -> Result<Shape, curve::CurveError>,
) -> RhaiResult<Shape> {
    let first_error: RefCell<Option<Box<EvalAltResult>>> = RefCell::new(None);
    let curve = |t: f64| {
        if first_error.borrow().is_some() {
            return [f64::NAN; 3];
        }
        call_curve(ctx, func, f, t).unwrap_or_else(|e| {
            *first_error.borrow_mut() = Some(e);
            [f64::NAN; 3]
        })
    };
    let built = build(&curve);
    if let Some(e) = first_error.into_inner() {
        return Err(e);
    }
    built.map_err(|e| fail(format!("{func}: {e}")))
}

fn register_curve_followers(engine: &mut Engine) {
    engine.register_fn(
        "curve_fol_sphere",
        |ctx: NativeCallContext, f: FnPtr, n: Dynamic, range: Array, radius: Dynamic| {
            let name = "curve_fol_sphere";
            let n = count_arg(name, 2, "n", &n)?;
            let range = numbers_arg::<2>(name, 3, "[a, b]", &range)?;
            let radius = shape_arg(name, 4, "radius", &radius)?;
            follow(&ctx, name, &f, |curve| {
                curve::curve_fol_sphere(curve, n, range, radius)
            })
        },
    );
    for name in ["curve_fol_cyl", "curve_fol_cyyl"] {
        engine.register_fn(
            name,
            move |ctx: NativeCallContext, f: FnPtr, n: Dynamic, range: Array, cde: Array| {
                let n = count_arg(name, 2, "n", &n)?;
                let range = numbers_arg::<2>(name, 3, "[a, b]", &range)?;
                let cde = numbers_arg::<3>(name, 4, "[c, d, e]", &cde)?;
                follow(&ctx, name, &f, |curve| {
                    curve::curve_fol_cyl(curve, n, range, cde)
                })
            },
        );
    }
    engine.register_fn(
        "curve_fol_box",
        |ctx: NativeCallContext, f: FnPtr, n: Dynamic, range: Array, size: Dynamic| {
            let name = "curve_fol_box";
            let n = count_arg(name, 2, "n", &n)?;
            let range = numbers_arg::<2>(name, 3, "[a, b]", &range)?;
            let size = number_arg(name, 4, "size", &size)?;
            follow(&ctx, name, &f, |curve| {
                curve::curve_fol_box(curve, n, range, size)
            })
        },
    );
}
