//! The modern library's core in scripts: primitives, transforms (as functions and, by
//! Rhai's method-call syntax, as methods: `s.move([1, 0, 0])`), booleans, blends,
//! `offset`, `shell` and `hull`. Names and arguments as in `docs/library-modern.md`.
//!
//! Every result is noted in the run's [`Facts`]: which shapes are exact distances (their
//! offsets and shells are plain arithmetic) and which are convex bodies (their hulls are
//! exact).

use glam::{DMat3, DVec3};
use isoforge_field::Shape;
use isoforge_shapes::hull::{Body, Convex, HullPart, hull};
use isoforge_shapes::modern::{self as lib, ModernError};
use rhai::{Array, Dynamic, Engine};

use crate::args::{RhaiResult, fail, number_arg, type_name};
use crate::facts::{Fact, SharedFacts, lock};

/// A shape argument (numbers are refused: a set operation on a number is a mistake).
pub fn shape_only(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<Shape> {
    d.clone().try_cast::<Shape>().ok_or_else(|| {
        fail(format!(
            "{func}: argument {index} (`{name}`) must be a shape, not {}",
            type_name(d)
        ))
    })
}

/// An array of exactly three numbers.
pub fn vec3(func: &str, index: usize, name: &str, d: &Dynamic) -> RhaiResult<[f64; 3]> {
    let wrong = || {
        fail(format!(
            "{func}: argument {index} (`{name}`) must be [x, y, z], not {}",
            type_name(d)
        ))
    };
    let a = d.clone().try_cast::<Array>().ok_or_else(wrong)?;
    crate::args::numbers_arg::<3>(func, index, name, &a)
}

/// An array of shapes (at least one).
pub fn shape_list(func: &str, index: usize, d: &Dynamic) -> RhaiResult<Vec<Shape>> {
    let a = d.clone().try_cast::<Array>().ok_or_else(|| {
        fail(format!(
            "{func}: argument {index} must be a shape or an array of shapes, not {}",
            type_name(d)
        ))
    })?;
    if a.is_empty() {
        return Err(fail(format!("{func}: the array of shapes is empty")));
    }
    a.iter()
        .enumerate()
        .map(|(i, s)| {
            s.clone().try_cast::<Shape>().ok_or_else(|| {
                fail(format!(
                    "{func}: element {} of the array must be a shape, not {}",
                    i + 1,
                    type_name(s)
                ))
            })
        })
        .collect()
}

fn built(func: &str, r: Result<Shape, ModernError>) -> RhaiResult<Shape> {
    r.map_err(|e| fail(format!("{func}: {e}")))
}

/// Registers the modern core with the run's facts table.
pub fn register(engine: &mut Engine, facts: &SharedFacts) {
    register_primitives(engine, facts);
    register_transforms(engine, facts);
    register_booleans(engine, facts);
    register_offsets(engine, facts);
}

/// A primitive: its field, whether it is an exact distance, and its convex body.
fn primitive(
    facts: &SharedFacts,
    func: &str,
    r: Result<Shape, ModernError>,
    distance: bool,
    convex: Option<Convex>,
) -> RhaiResult<Shape> {
    let s = built(func, r)?;
    Ok(lock(facts).note(s, Fact { distance, convex }))
}

fn register_primitives(engine: &mut Engine, facts: &SharedFacts) {
    let f = facts.clone();
    engine.register_fn("sphere", move |r: Dynamic| {
        let r = number_arg("sphere", 1, "r", &r)?;
        primitive(
            &f,
            "sphere",
            lib::sphere(r),
            true,
            Some(Convex::ball(DVec3::ZERO, r)),
        )
    });
    let f = facts.clone();
    engine.register_fn("box", move |size: Dynamic| {
        let size = vec3("box", 1, "[sx, sy, sz]", &size)?;
        let half = DVec3::from(size) / 2.0;
        primitive(
            &f,
            "box",
            lib::box3(size),
            true,
            Some(Convex::new(Body::Box(half))),
        )
    });
    let f = facts.clone();
    engine.register_fn("cylinder", move |r: Dynamic, h: Dynamic| {
        let r = number_arg("cylinder", 1, "r", &r)?;
        let h = number_arg("cylinder", 2, "h", &h)?;
        let body = Convex::new(Body::Cylinder { r, half: h / 2.0 });
        primitive(&f, "cylinder", lib::cylinder(r, h), true, Some(body))
    });
    let f = facts.clone();
    engine.register_fn("cone", move |r: Dynamic, h: Dynamic| {
        let r = number_arg("cone", 1, "r", &r)?;
        let h = number_arg("cone", 2, "h", &h)?;
        let body = Convex::new(Body::Cone { r, h });
        primitive(&f, "cone", lib::cone(r, h), true, Some(body))
    });
    let f = facts.clone();
    engine.register_fn("torus", move |big: Dynamic, small: Dynamic| {
        let big = number_arg("torus", 1, "R", &big)?;
        let small = number_arg("torus", 2, "r", &small)?;
        primitive(&f, "torus", lib::torus(big, small), true, None)
    });
    let f = facts.clone();
    engine.register_fn("ellipsoid", move |abc: Dynamic| {
        let abc = vec3("ellipsoid", 1, "[a, b, c]", &abc)?;
        let body = Convex::new(Body::Ellipsoid(DVec3::from(abc)));
        primitive(&f, "ellipsoid", lib::ellipsoid(abc), false, Some(body))
    });
    let f = facts.clone();
    engine.register_fn("capsule", move |p0: Dynamic, p1: Dynamic, r: Dynamic| {
        let p0 = vec3("capsule", 1, "p0", &p0)?;
        let p1 = vec3("capsule", 2, "p1", &p1)?;
        let r = number_arg("capsule", 3, "r", &r)?;
        let body =
            Convex::new(Body::Segment(DVec3::from(p0), DVec3::from(p1))).inflated(r.max(0.0));
        primitive(&f, "capsule", lib::capsule(p0, p1, r), true, Some(body))
    });
    let f = facts.clone();
    engine.register_fn("half_space", move |n: Dynamic, offset: Dynamic| {
        let n = vec3("half_space", 1, "normal", &n)?;
        let offset = number_arg("half_space", 2, "offset", &offset)?;
        primitive(&f, "half_space", lib::half_space(n, offset), true, None)
    });
    engine.register_fn("gyroid", |period: Dynamic, thickness: Dynamic| {
        let period = number_arg("gyroid", 1, "period", &period)?;
        let thickness = number_arg("gyroid", 2, "thickness", &thickness)?;
        built("gyroid", lib::gyroid(period, thickness))
    });
}

/// A transform of `s` that keeps distances (`keeps`) and moves its convex body by `body`.
fn transformed(
    facts: &SharedFacts,
    func: &str,
    s: &Shape,
    r: Result<Shape, ModernError>,
    keeps: bool,
    body: impl FnOnce(Convex) -> Option<Convex>,
) -> RhaiResult<Shape> {
    let out = built(func, r)?;
    let mut table = lock(facts);
    let old = table.of(s);
    let fact = Fact {
        distance: keeps && old.distance,
        convex: old.convex.and_then(body),
    };
    Ok(table.note(out, fact))
}

fn register_transforms(engine: &mut Engine, facts: &SharedFacts) {
    let f = facts.clone();
    engine.register_fn("move", move |s: Dynamic, v: Dynamic| {
        let s = shape_only("move", 1, "s", &s)?;
        let v = vec3("move", 2, "[x, y, z]", &v)?;
        let moved = lib::move_by(&s, v);
        transformed(&f, "move", &s, moved, true, |c| {
            Some(c.moved(DVec3::from(v)))
        })
    });
    let f = facts.clone();
    engine.register_fn("scale", move |s: Dynamic, k: Dynamic| {
        let s = shape_only("scale", 1, "s", &s)?;
        let (k, uniform) = match crate::args::as_number(&k) {
            Some(k) => ([k; 3], true),
            None => (vec3("scale", 2, "k or [kx, ky, kz]", &k)?, false),
        };
        let uniform = uniform || (k[0] == k[1] && k[1] == k[2]);
        let scaled = lib::scale(&s, k);
        transformed(&f, "scale", &s, scaled, uniform, |c| {
            c.scaled(DVec3::from(k))
        })
    });
    for (name, matrix) in [
        (
            "rotate_x",
            lib::matrix_x as fn(f64) -> Result<DMat3, ModernError>,
        ),
        ("rotate_y", lib::matrix_y),
        ("rotate_z", lib::matrix_z),
    ] {
        let f = facts.clone();
        engine.register_fn(name, move |s: Dynamic, deg: Dynamic| {
            let s = shape_only(name, 1, "s", &s)?;
            let deg = number_arg(name, 2, "degrees", &deg)?;
            let m = matrix(deg).map_err(|e| fail(format!("{name}: {e}")))?;
            let turned = Ok(lib::turned(&s, m));
            transformed(&f, name, &s, turned, true, |c| Some(c.turned(m)))
        });
    }
    let f = facts.clone();
    engine.register_fn("rotate", move |s: Dynamic, axis: Dynamic, deg: Dynamic| {
        let s = shape_only("rotate", 1, "s", &s)?;
        let axis = vec3("rotate", 2, "axis", &axis)?;
        let deg = number_arg("rotate", 3, "degrees", &deg)?;
        let m = lib::matrix_axis(axis, deg).map_err(|e| fail(format!("rotate: {e}")))?;
        let turned = Ok(lib::turned(&s, m));
        transformed(&f, "rotate", &s, turned, true, |c| Some(c.turned(m)))
    });
    for (name, axis) in [("mirror_x", 0), ("mirror_y", 1), ("mirror_z", 2)] {
        let f = facts.clone();
        engine.register_fn(name, move |s: Dynamic| {
            let s = shape_only(name, 1, "s", &s)?;
            let mut d = DVec3::ONE;
            d[axis] = -1.0;
            let m = DMat3::from_diagonal(d);
            let mirrored = Ok(match axis {
                0 => lib::mirror_x(&s),
                1 => lib::mirror_y(&s),
                _ => lib::mirror_z(&s),
            });
            transformed(&f, name, &s, mirrored, true, |c| Some(c.turned(m)))
        });
    }
    engine.register_fn("twist", |s: Dynamic, rate: Dynamic| {
        let s = shape_only("twist", 1, "s", &s)?;
        let rate = number_arg("twist", 2, "deg_per_mm", &rate)?;
        built("twist", lib::twist(&s, rate))
    });
}

/// A boolean of shapes: a distance when all its inputs are.
fn combined(facts: &SharedFacts, inputs: &[Shape], out: Shape) -> Shape {
    let mut table = lock(facts);
    let distance = inputs.iter().all(|s| table.is_distance(s));
    table.note(
        out,
        Fact {
            distance,
            convex: None,
        },
    )
}

fn register_booleans(engine: &mut Engine, facts: &SharedFacts) {
    type Pair = fn(&Shape, &Shape) -> Shape;
    type Many = fn(&[Shape]) -> Option<Shape>;
    for (name, pair, many) in [
        ("union", lib::union as Pair, lib::union_all as Many),
        ("intersection", lib::intersection, lib::intersection_all),
        ("difference", lib::difference, lib::difference_all),
    ] {
        let f = facts.clone();
        engine.register_fn(name, move |a: Dynamic, b: Dynamic| {
            let a = shape_only(name, 1, "a", &a)?;
            let b = shape_only(name, 2, "b", &b)?;
            let out = pair(&a, &b);
            Ok::<_, Box<rhai::EvalAltResult>>(combined(&f, &[a, b], out))
        });
        let f = facts.clone();
        engine.register_fn(name, move |list: Dynamic| {
            let list = shape_list(name, 1, &list)?;
            let out = many(&list).ok_or_else(|| fail(format!("{name}: no shapes")))?;
            Ok::<_, Box<rhai::EvalAltResult>>(combined(&f, &list, out))
        });
    }
    type Smooth = fn(&Shape, &Shape, f64) -> Result<Shape, ModernError>;
    for (name, op) in [
        ("smooth_union", lib::smooth_union as Smooth),
        ("smooth_intersection", lib::smooth_intersection),
        ("smooth_difference", lib::smooth_difference),
    ] {
        engine.register_fn(name, move |a: Dynamic, b: Dynamic, k: Dynamic| {
            let a = shape_only(name, 1, "a", &a)?;
            let b = shape_only(name, 2, "b", &b)?;
            let k = number_arg(name, 3, "k", &k)?;
            built(name, op(&a, &b, k))
        });
    }
}

fn register_offsets(engine: &mut Engine, facts: &SharedFacts) {
    let f = facts.clone();
    engine.register_fn("offset", move |s: Dynamic, d: Dynamic| {
        let s = shape_only("offset", 1, "s", &s)?;
        let d = number_arg("offset", 2, "d", &d)?;
        let old = lock(&f).of(&s);
        let out = if old.distance {
            lib::offset_exact(&s, d)
        } else {
            lib::offset(&s, d)
        };
        let out = built("offset", out)?;
        // The first-order distance is treated as a distance from here on: an offset of
        // an offset subtracts again instead of estimating the estimate.
        let convex = old.convex.filter(|_| d >= 0.0).map(|c| c.inflated(d));
        Ok::<_, Box<rhai::EvalAltResult>>(lock(&f).note(
            out,
            Fact {
                distance: true,
                convex,
            },
        ))
    });
    let f = facts.clone();
    engine.register_fn("shell", move |s: Dynamic, t: Dynamic| {
        let s = shape_only("shell", 1, "s", &s)?;
        let t = number_arg("shell", 2, "t", &t)?;
        let out = if lock(&f).is_distance(&s) {
            lib::shell_exact(&s, t)
        } else {
            lib::shell(&s, t)
        };
        let out = built("shell", out)?;
        Ok::<_, Box<rhai::EvalAltResult>>(lock(&f).note(
            out,
            Fact {
                distance: true,
                convex: None,
            },
        ))
    });
    let f = facts.clone();
    engine.register_fn("hull", move |list: Dynamic| {
        let list = shape_list("hull", 1, &list)?;
        let parts = {
            let table = lock(&f);
            list.iter()
                .map(|s| match table.of(s).convex {
                    Some(c) => HullPart::Convex(c),
                    None => HullPart::Field(s.clone()),
                })
                .collect()
        };
        let (shape, body) = hull(parts).map_err(|e| fail(format!("hull: {e}")))?;
        Ok::<_, Box<rhai::EvalAltResult>>(lock(&f).note(
            shape,
            Fact {
                distance: true,
                convex: Some(body),
            },
        ))
    });
}
