//! 2D profiles and sweeps in scripts (`docs/library-sweeps.md`): `circle`, `rect`,
//! `polygon` and their transforms; `linear_sweep`, `revolve` (alias `rotate_sweep`),
//! `spiral_sweep`, `path_sweep`, `skin`. Optional arguments come in an options map, read
//! with [`crate::options::Options`] (unknown keys are errors that name them).
//!
//! A profile is its own script type, `Profile`: a 2D shape that becomes a solid only when
//! swept. The transforms `move`, `rotate`, `scale`, `mirror_x`, `mirror_y` and `offset`
//! take a profile as their first argument too, with 2D arguments.

use std::cell::RefCell;

use glam::DVec3;
use isoforge_field::Shape;
use isoforge_shapes::profile::{self, Profile};
use isoforge_shapes::sweep::{
    self, LinearSweep, PathMethod, PathSweep, Sampling, SkinMethod, SkinOptions, SpiralSweep,
};
use rhai::{Array, Dynamic, Engine, EvalAltResult, FnPtr, Map, NativeCallContext};

use crate::args::{RhaiResult, as_number, fail, number_arg, type_name};
use crate::options::Options;

/// A profile argument, or an error saying what was given instead.
pub fn profile_arg(func: &str, index: usize, d: &Dynamic) -> RhaiResult<Profile> {
    d.clone().try_cast::<Profile>().ok_or_else(|| {
        let hint = if d.is::<Shape>() {
            " (a 3D shape cannot be swept: use circle, rect or polygon)"
        } else {
            ""
        };
        fail(format!(
            "{func}: argument {index} must be a 2D profile (circle, rect, polygon), not {}{hint}",
            type_name(d)
        ))
    })
}

/// `[x, y]` or `[x, y, z]` as a 3D point (z = 0 for a 2D point).
pub fn point_arg(func: &str, what: &str, d: &Dynamic) -> RhaiResult<[f64; 3]> {
    let wrong = || {
        fail(format!(
            "{func}: {what} must be [x, y] or [x, y, z], not {}",
            type_name(d)
        ))
    };
    let a = d.clone().try_cast::<Array>().ok_or_else(wrong)?;
    let nums: Option<Vec<f64>> = a.iter().map(as_number).collect();
    match nums.as_deref() {
        Some([x, y]) => Ok([*x, *y, 0.0]),
        Some([x, y, z]) => Ok([*x, *y, *z]),
        _ => Err(wrong()),
    }
}

/// A list of `[x, y]` points.
fn points2(func: &str, what: &str, a: &Array) -> RhaiResult<Vec<[f64; 2]>> {
    a.iter()
        .enumerate()
        .map(|(i, p)| {
            let bad = || {
                fail(format!(
                    "{func}: point {i} of {what} must be [x, y], not {}",
                    type_name(p)
                ))
            };
            let q = p.clone().try_cast::<Array>().ok_or_else(bad)?;
            match (
                q.len(),
                q.first().and_then(as_number),
                q.get(1).and_then(as_number),
            ) {
                (2, Some(x), Some(y)) => Ok([x, y]),
                _ => Err(bad()),
            }
        })
        .collect()
}

fn built<T, E: std::fmt::Display>(func: &str, r: Result<T, E>) -> RhaiResult<T> {
    r.map_err(|e| fail(format!("{func}: {e}")))
}

/// Registers profiles and sweeps.
pub fn register(engine: &mut Engine) {
    engine.register_type_with_name::<Profile>("Profile");
    engine.register_fn("to_string", |p: &mut Profile| describe(p));
    engine.register_fn("to_debug", |p: &mut Profile| describe(p));
    register_profiles(engine);
    register_profile_transforms(engine);
    register_sweeps(engine);
    register_path_and_skin(engine);
}

fn describe(p: &Profile) -> String {
    let b = p.bounds();
    format!(
        "Profile([{}, {}] to [{}, {}])",
        b.min.x, b.min.y, b.max.x, b.max.y
    )
}

fn circle(r: &Dynamic, opts: Map) -> RhaiResult<Profile> {
    let r = number_arg("circle", 1, "r", r)?;
    let mut o = Options::new("circle", opts);
    let segments = o.count("segments")?;
    o.finish()?;
    match segments {
        None => built("circle", profile::circle(r)),
        Some(n) if (3..=profile::MAX_POINTS as i64).contains(&n) => {
            built("circle", profile::regular_polygon(r, n as usize))
        }
        Some(n) => Err(fail(format!(
            "circle: option `segments` must be a whole number from 3 to {}, not {n}",
            profile::MAX_POINTS
        ))),
    }
}

fn rect(size: &Dynamic, opts: Map) -> RhaiResult<Profile> {
    let size = match as_number(size) {
        Some(k) => [k, k],
        None => {
            let a = size.clone().try_cast::<Array>();
            match a
                .as_deref()
                .map(|a| a.iter().map(as_number).collect::<Option<Vec<_>>>())
            {
                Some(Some(v)) if v.len() == 2 => [v[0], v[1]],
                _ => {
                    return Err(fail(format!(
                        "rect: argument 1 must be a size [w, h] or a number, not {}",
                        type_name(size)
                    )));
                }
            }
        }
    };
    let mut o = Options::new("rect", opts);
    let rounding = o.number("rounding")?.unwrap_or(0.0);
    o.finish()?;
    built("rect", profile::rect(size, rounding))
}

fn polygon(points: &Dynamic) -> RhaiResult<Profile> {
    let func = "polygon";
    let a = points.clone().try_cast::<Array>().ok_or_else(|| {
        fail(format!(
            "polygon: argument 1 must be an array of [x, y] points, or of rings of them, not {}",
            type_name(points)
        ))
    })?;
    // Rings when the first element is itself a list of points.
    let nested = a
        .first()
        .and_then(|f| f.clone().try_cast::<Array>())
        .and_then(|f| f.first().cloned())
        .is_some_and(|p| p.is_array());
    let rings = if nested {
        a.iter()
            .enumerate()
            .map(|(i, r)| {
                let r = r.clone().try_cast::<Array>().ok_or_else(|| {
                    fail(format!(
                        "polygon: ring {i} must be an array of [x, y] points"
                    ))
                })?;
                points2(func, &format!("ring {i}"), &r)
            })
            .collect::<RhaiResult<Vec<_>>>()?
    } else {
        vec![points2(func, "the polygon", &a)?]
    };
    built(func, profile::polygon(&rings))
}

fn register_profiles(engine: &mut Engine) {
    engine.register_fn("circle", |r: Dynamic| circle(&r, Map::new()));
    engine.register_fn("circle", |r: Dynamic, o: Map| circle(&r, o));
    engine.register_fn("rect", |s: Dynamic| rect(&s, Map::new()));
    engine.register_fn("rect", |s: Dynamic, o: Map| rect(&s, o));
    engine.register_fn("polygon", |p: Dynamic| polygon(&p));
}

/// A 2D vector argument: `[x, y]`.
fn vec2(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<[f64; 2]> {
    let wrong = || {
        fail(format!(
            "{func}: argument {index} (`{name}`) must be [x, y] for a profile, not {}",
            type_name(d)
        ))
    };
    let a = d.clone().try_cast::<Array>().ok_or_else(wrong)?;
    crate::args::numbers_arg::<2>(func, index, name, &a)
}

fn register_profile_transforms(engine: &mut Engine) {
    // Typed on Profile, so that these and the 3D transforms of the same names (which take
    // shapes) do not shadow each other.
    engine.register_fn("move", |p: Profile, v: Array| {
        let v = vec2("move", 2, "[x, y]", &Dynamic::from(v))?;
        built("move", p.translate(v))
    });
    let rotate = |p: Profile, deg: Dynamic| {
        let deg = number_arg("rotate", 2, "degrees", &deg)?;
        built("rotate", p.rotate(deg))
    };
    engine.register_fn("rotate", move |p: Profile, d: rhai::INT| {
        rotate(p, Dynamic::from(d))
    });
    engine.register_fn("rotate", move |p: Profile, d: rhai::FLOAT| {
        rotate(p, Dynamic::from(d))
    });
    let scale = |p: Profile, k: Dynamic| {
        let k = match as_number(&k) {
            Some(v) => [v, v],
            None => vec2("scale", 2, "k or [kx, ky]", &k)?,
        };
        built("scale", p.scale(k))
    };
    engine.register_fn("scale", move |p: Profile, k: rhai::INT| {
        scale(p, Dynamic::from(k))
    });
    engine.register_fn("scale", move |p: Profile, k: rhai::FLOAT| {
        scale(p, Dynamic::from(k))
    });
    engine.register_fn("scale", move |p: Profile, k: Array| {
        scale(p, Dynamic::from(k))
    });
    engine.register_fn("mirror_x", |p: Profile| {
        built("mirror_x", p.scale([-1.0, 1.0]))
    });
    engine.register_fn("mirror_y", |p: Profile| {
        built("mirror_y", p.scale([1.0, -1.0]))
    });
    let offset = |p: Profile, d: Dynamic| {
        let d = number_arg("offset", 2, "d", &d)?;
        built("offset", p.offset(d))
    };
    engine.register_fn("offset", move |p: Profile, d: rhai::INT| {
        offset(p, Dynamic::from(d))
    });
    engine.register_fn("offset", move |p: Profile, d: rhai::FLOAT| {
        offset(p, Dynamic::from(d))
    });
}

fn linear(p: &Dynamic, h: &Dynamic, opts: Map) -> RhaiResult<Shape> {
    let func = "linear_sweep";
    let profile = profile_arg(func, 1, p)?;
    let h = number_arg(func, 2, "h", h)?;
    let mut o = Options::new(func, opts);
    let sweep = linear_options(&mut o, h)?;
    o.finish()?;
    built(func, sweep::linear_sweep(&profile, &sweep))
}

/// The options a linear sweep takes (shared with the textured sweeps): twist, scale,
/// shift, center, and `slices`, accepted for BOSL2 scripts and without effect (the sweep
/// is exact, not sliced).
pub fn linear_options(o: &mut Options, h: f64) -> RhaiResult<LinearSweep> {
    let mut s = LinearSweep::new(h);
    s.twist = o.number("twist")?.unwrap_or(0.0);
    s.scale = o.number_or_vector::<2>("scale")?.unwrap_or([1.0, 1.0]);
    s.shift = o.vector::<2>("shift")?.unwrap_or([0.0, 0.0]);
    s.center = o.flag("center")?.unwrap_or(false);
    let _exact_without_slices = o.count("slices")?;
    Ok(s)
}

fn revolve(func: &'static str, p: &Dynamic, opts: Map) -> RhaiResult<Shape> {
    let profile = profile_arg(func, 1, p)?;
    let mut o = Options::new(func, opts);
    let angle = o.number("angle")?.unwrap_or(360.0);
    o.finish()?;
    built(func, sweep::revolve(&profile, angle))
}

fn spiral(args: [&Dynamic; 4], opts: Map) -> RhaiResult<Shape> {
    let func = "spiral_sweep";
    let profile = profile_arg(func, 1, args[0])?;
    let height = number_arg(func, 2, "h", args[1])?;
    let radius = number_arg(func, 3, "r", args[2])?;
    let turns = number_arg(func, 4, "turns", args[3])?;
    let mut o = Options::new(func, opts);
    let taper = o.number("taper")?.unwrap_or(0.0);
    let internal = o.flag("internal")?.unwrap_or(false);
    o.finish()?;
    let opts = SpiralSweep {
        height,
        radius,
        turns,
        taper,
        internal,
    };
    built(func, sweep::spiral_sweep(&profile, &opts))
}

fn register_sweeps(engine: &mut Engine) {
    engine.register_fn("linear_sweep", |p: Dynamic, h: Dynamic| {
        linear(&p, &h, Map::new())
    });
    engine.register_fn("linear_sweep", |p: Dynamic, h: Dynamic, o: Map| {
        linear(&p, &h, o)
    });
    for name in ["revolve", "rotate_sweep"] {
        engine.register_fn(name, move |p: Dynamic| revolve(name, &p, Map::new()));
        engine.register_fn(name, move |p: Dynamic, o: Map| revolve(name, &p, o));
    }
    engine.register_fn(
        "spiral_sweep",
        |p: Dynamic, h: Dynamic, r: Dynamic, t: Dynamic| spiral([&p, &h, &r, &t], Map::new()),
    );
    engine.register_fn(
        "spiral_sweep",
        |p: Dynamic, h: Dynamic, r: Dynamic, t: Dynamic, o: Map| spiral([&p, &h, &r, &t], o),
    );
}

/// Calls a script closure with one number; it must give a point `[x, y]` or `[x, y, z]`.
pub fn call_point(
    ctx: &NativeCallContext,
    func: &str,
    what: &str,
    f: &FnPtr,
    s: f64,
) -> RhaiResult<[f64; 3]> {
    let value: Dynamic = f.call_within_context(ctx, (s,))?;
    point_arg(func, &format!("{what} at {s}"), &value)
}

/// Runs `build` with a closure as a plain curve; the first error the closure raises
/// stops the build and is returned.
pub fn with_curve<T>(
    ctx: &NativeCallContext,
    func: &str,
    what: &str,
    f: &FnPtr,
    build: impl FnOnce(&dyn Fn(f64) -> [f64; 3]) -> T,
) -> RhaiResult<T> {
    let first_error: RefCell<Option<Box<EvalAltResult>>> = RefCell::new(None);
    let curve = |s: f64| {
        if first_error.borrow().is_some() {
            return [f64::NAN; 3];
        }
        call_point(ctx, func, what, f, s).unwrap_or_else(|e| {
            *first_error.borrow_mut() = Some(e);
            [f64::NAN; 3]
        })
    };
    let out = build(&curve);
    match first_error.into_inner() {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

fn path_sweep(
    ctx: &NativeCallContext,
    p: &Dynamic,
    path: &Dynamic,
    opts: Map,
) -> RhaiResult<Shape> {
    let func = "path_sweep";
    let profile = profile_arg(func, 1, p)?;
    let mut o = Options::new(func, opts);
    let method = match o.choice("method", &["incremental", "natural", "manual"])? {
        Some("natural") => PathMethod::Natural,
        Some("manual") => PathMethod::Manual,
        _ => PathMethod::Incremental,
    };
    let normal = o.vector::<3>("normal")?;
    let twist = o.number("twist")?.unwrap_or(0.0);
    let scale = o.number("scale")?.unwrap_or(1.0);
    let closed = o.flag("closed")?.unwrap_or(false);
    let symmetry = o.count("symmetry")?.unwrap_or(1);
    o.finish()?;
    if !(1..=10_000).contains(&symmetry) {
        return Err(fail(format!(
            "path_sweep: option `symmetry` must be a whole number from 1 to 10000, not {symmetry}"
        )));
    }
    let points: Vec<DVec3> = if let Some(f) = path.clone().try_cast::<FnPtr>() {
        let sampled = with_curve(ctx, func, "the path", &f, |curve| {
            sweep::path::sample_curve(curve, closed)
        })?;
        built(func, sampled)?
    } else if let Some(a) = path.clone().try_cast::<Array>() {
        a.iter()
            .enumerate()
            .map(|(i, q)| point_arg(func, &format!("path point {i}"), q).map(DVec3::from))
            .collect::<RhaiResult<_>>()?
    } else {
        return Err(fail(format!(
            "path_sweep: argument 2 must be an array of [x, y, z] points or a closure |s| [x, y, z], not {}",
            type_name(path)
        )));
    };
    let opts = PathSweep {
        method,
        normal,
        twist,
        scale,
        closed,
        symmetry: symmetry as u32,
    };
    built(func, sweep::path_sweep(&profile, &points, &opts))
}

fn skin(profiles: &Dynamic, heights: &Dynamic, opts: Map) -> RhaiResult<Shape> {
    let func = "skin";
    let list = profiles.clone().try_cast::<Array>().ok_or_else(|| {
        fail(format!(
            "skin: argument 1 must be an array of profiles, not {}",
            type_name(profiles)
        ))
    })?;
    let profiles = list
        .iter()
        .enumerate()
        .map(|(i, p)| profile_arg(&format!("skin (profile {i})"), 1, p))
        .collect::<RhaiResult<Vec<_>>>()?;
    let zs = heights.clone().try_cast::<Array>().ok_or_else(|| {
        fail(format!(
            "skin: argument 2 must be an array of heights, one per profile, not {}",
            type_name(heights)
        ))
    })?;
    let zs = zs
        .iter()
        .enumerate()
        .map(|(i, z)| number_arg(func, 2, &format!("height {i}"), z))
        .collect::<RhaiResult<Vec<_>>>()?;
    let mut o = Options::new(func, opts);
    let method = match o.choice(
        "method",
        &["direct", "reindex", "distance", "fast_distance", "tangent"],
    )? {
        Some("reindex") => SkinMethod::Reindex,
        Some("distance") => SkinMethod::Distance,
        Some("fast_distance") => SkinMethod::FastDistance,
        Some("tangent") => SkinMethod::Tangent,
        _ => SkinMethod::Direct,
    };
    let sampling = match o.choice("sampling", &["length", "segment"])? {
        Some("segment") => Sampling::Segment,
        _ => Sampling::Length,
    };
    let refine = o.count("refine")?.unwrap_or(1);
    let _exact_without_slices = o.count("slices")?;
    o.finish()?;
    if !(1..=1000).contains(&refine) {
        return Err(fail(format!(
            "skin: option `refine` must be a whole number from 1 to 1000, not {refine}"
        )));
    }
    let opts = SkinOptions {
        method,
        sampling,
        refine: refine as usize,
    };
    built(func, sweep::skin(&profiles, &zs, &opts))
}

fn register_path_and_skin(engine: &mut Engine) {
    engine.register_fn(
        "path_sweep",
        |ctx: NativeCallContext, p: Dynamic, path: Dynamic| path_sweep(&ctx, &p, &path, Map::new()),
    );
    engine.register_fn(
        "path_sweep",
        |ctx: NativeCallContext, p: Dynamic, path: Dynamic, o: Map| path_sweep(&ctx, &p, &path, o),
    );
    engine.register_fn("skin", |p: Dynamic, z: Dynamic| skin(&p, &z, Map::new()));
    engine.register_fn("skin", |p: Dynamic, z: Dynamic, o: Map| skin(&p, &z, o));
}
