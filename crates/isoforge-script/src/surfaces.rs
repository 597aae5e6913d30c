//! Free-form surfaces in scripts, thickened into solids: `bezier_surface`,
//! `bspline_surface`, `coons_patch`, each with `#{edges: "round" | "flat"}` (round by
//! default: the exact offset of the surface).

use isoforge_field::Shape;
use isoforge_shapes::surface::{self, CoonsCurves, Edges, Surface};
use rhai::{Array, Dynamic, Engine, FnPtr, Map, NativeCallContext};

use crate::args::{RhaiResult, count_arg, fail, number_arg, type_name};
use crate::options::Options;
use crate::sweeps::with_curve;

fn built<T, E: std::fmt::Display>(func: &str, r: Result<T, E>) -> RhaiResult<T> {
    r.map_err(|e| fail(format!("{func}: {e}")))
}

/// A net: rows of `[x, y, z]` points.
fn net_arg(func: &str, d: &Dynamic) -> RhaiResult<Vec<Vec<[f64; 3]>>> {
    let bad = |what: String| fail(format!("{func}: {what}"));
    let rows = d.clone().try_cast::<Array>().ok_or_else(|| {
        bad(format!(
            "argument 1 must be a net: rows of [x, y, z] points, not {}",
            type_name(d)
        ))
    })?;
    rows.iter()
        .enumerate()
        .map(|(i, row)| {
            let row = row.clone().try_cast::<Array>().ok_or_else(|| {
                bad(format!(
                    "row {i} of the net must be an array of [x, y, z] points"
                ))
            })?;
            row.iter()
                .enumerate()
                .map(|(j, p)| {
                    let wrong = || {
                        bad(format!(
                            "point [{i}][{j}] of the net must be [x, y, z], not {}",
                            type_name(p)
                        ))
                    };
                    let a = p.clone().try_cast::<Array>().ok_or_else(wrong)?;
                    crate::args::numbers_arg::<3>(func, 1, &format!("net[{i}][{j}]"), &a)
                        .map_err(|_| wrong())
                })
                .collect::<RhaiResult<Vec<_>>>()
        })
        .collect()
}

/// Reads `edges` and finishes the options.
fn edges(mut o: Options) -> RhaiResult<Edges> {
    let e = match o.choice("edges", &["round", "flat"])? {
        Some("flat") => Edges::Flat,
        _ => Edges::Round,
    };
    o.finish()?;
    Ok(e)
}

fn thicken(
    func: &str,
    index: usize,
    s: &Surface,
    thickness: &Dynamic,
    e: Edges,
) -> RhaiResult<Shape> {
    let t = number_arg(func, index, "thickness", thickness)?;
    built(func, s.thicken(t, e))
}

fn bezier(net: &Dynamic, thickness: &Dynamic, opts: Map) -> RhaiResult<Shape> {
    let func = "bezier_surface";
    let net = net_arg(func, net)?;
    let e = edges(Options::new(func, opts))?;
    let s = built(func, surface::bezier(&net))?;
    thicken(func, 2, &s, thickness, e)
}

fn bspline(args: [&Dynamic; 3], opts: Map) -> RhaiResult<Shape> {
    let func = "bspline_surface";
    let net = net_arg(func, args[0])?;
    let degree = count_arg(func, 2, "degree", args[1])?;
    let mut o = Options::new(func, opts);
    let clamped = o.flag("clamped")?.unwrap_or(false);
    let e = edges(o)?;
    let s = built(func, surface::bspline(&net, degree, clamped))?;
    thicken(func, 3, &s, args[2], e)
}

fn coons(
    ctx: &NativeCallContext,
    curves: [&Dynamic; 4],
    thickness: &Dynamic,
    opts: Map,
) -> RhaiResult<Shape> {
    let func = "coons_patch";
    let names = ["c0", "c1", "d0", "d1"];
    let mut fns = Vec::with_capacity(4);
    for (i, c) in curves.iter().enumerate() {
        fns.push((*c).clone().try_cast::<FnPtr>().ok_or_else(|| {
            fail(format!(
                "coons_patch: argument {} (`{}`) must be a closure |s| [x, y, z], not {}",
                i + 1,
                names[i],
                type_name(c)
            ))
        })?);
    }
    let e = edges(Options::new(func, opts))?;
    // Each closure is sampled once, here; the surface never calls back into the script.
    let s = with_curve(ctx, func, "c0", &fns[0], |c0| {
        with_curve(ctx, func, "c1", &fns[1], |c1| {
            with_curve(ctx, func, "d0", &fns[2], |d0| {
                with_curve(ctx, func, "d1", &fns[3], |d1| {
                    surface::coons(&CoonsCurves { c0, c1, d0, d1 })
                })
            })
        })
    })????;
    let s = built(func, s)?;
    thicken(func, 5, &s, thickness, e)
}

/// Registers the surfaces.
pub fn register(engine: &mut Engine) {
    engine.register_fn("bezier_surface", |n: Dynamic, t: Dynamic| {
        bezier(&n, &t, Map::new())
    });
    engine.register_fn("bezier_surface", |n: Dynamic, t: Dynamic, o: Map| {
        bezier(&n, &t, o)
    });
    engine.register_fn("bspline_surface", |n: Dynamic, d: Dynamic, t: Dynamic| {
        bspline([&n, &d, &t], Map::new())
    });
    engine.register_fn(
        "bspline_surface",
        |n: Dynamic, d: Dynamic, t: Dynamic, o: Map| bspline([&n, &d, &t], o),
    );
    engine.register_fn(
        "coons_patch",
        |ctx: NativeCallContext, a: Dynamic, b: Dynamic, c: Dynamic, d: Dynamic, t: Dynamic| {
            coons(&ctx, [&a, &b, &c, &d], &t, Map::new())
        },
    );
    engine.register_fn(
        "coons_patch",
        |ctx: NativeCallContext,
         a: Dynamic,
         b: Dynamic,
         c: Dynamic,
         d: Dynamic,
         t: Dynamic,
         o: Map| coons(&ctx, [&a, &b, &c, &d], &t, o),
    );
}
