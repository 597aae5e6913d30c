//! Textured sweeps in scripts: `textured_linear_sweep`, `textured_revolution`,
//! `textured_cylinder`, and `image("file.png")` (a grayscale image as a height texture,
//! read from the script's folder only).
//!
//! A texture argument is a name (`"ribs"`, ...), a 2D array of heights 0..1 (first row on
//! top), or an image. The texture options (BOSL2's names): `tex_size: [w, h]` (mm, fitted
//! to a whole number of tiles; default `[5, 5]`) or `counts: [n, m]`, `tex_depth` (mm,
//! default 1), `tex_inset` (mm, or `true` for the whole depth), `tex_rot` (a quarter turn).

use std::io::Cursor;
use std::sync::Arc;

use isoforge_field::Shape;
use isoforge_shapes::texture::{self, Texture, TextureOptions, Tile};
use rhai::{Array, Dynamic, Engine, Map};

use crate::args::{RhaiResult, as_number, fail, number_arg, type_name};
use crate::files::ScriptFolder;
use crate::options::Options;
use crate::sweeps::{linear_options, profile_arg};

fn built<T, E: std::fmt::Display>(func: &str, r: Result<T, E>) -> RhaiResult<T> {
    r.map_err(|e| fail(format!("{func}: {e}")))
}

/// A texture argument: a name, a 2D array of heights, or an `image(..)`.
fn texture_arg(func: &str, index: usize, d: &Dynamic) -> RhaiResult<Texture> {
    if let Some(t) = d.clone().try_cast::<Texture>() {
        return Ok(t);
    }
    if let Ok(name) = d.clone().into_immutable_string() {
        return built(func, texture::named(name.as_str()));
    }
    if let Some(rows) = d.clone().try_cast::<Array>() {
        let rows = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let bad = || {
                    fail(format!(
                        "{func}: row {i} of the height texture must be an array of numbers 0..1"
                    ))
                };
                let r = r.clone().try_cast::<Array>().ok_or_else(bad)?;
                r.iter()
                    .map(|v| as_number(v).ok_or_else(bad))
                    .collect::<RhaiResult<Vec<f64>>>()
            })
            .collect::<RhaiResult<Vec<_>>>()?;
        return built(func, texture::heights(rows));
    }
    Err(fail(format!(
        "{func}: argument {index} must be a texture name (such as \"ribs\"), a 2D array of heights 0..1, or image(\"file.png\"), not {}",
        type_name(d)
    )))
}

/// The texture options of a call.
fn texture_options(o: &mut Options) -> RhaiResult<TextureOptions> {
    let func = o.function();
    let size = o.number_or_vector::<2>("tex_size")?;
    let counts = o.number_or_vector::<2>("counts")?;
    let tile = match (size, counts) {
        (Some(_), Some(_)) => {
            return Err(fail(format!(
                "{func}: give `tex_size` or `counts`, not both"
            )));
        }
        (Some(s), None) => Tile::Size(s),
        (None, Some(c)) => {
            let whole = |v: f64| v.fract() == 0.0 && (1.0..=1e5).contains(&v);
            if !c.iter().all(|&v| whole(v)) {
                return Err(fail(format!(
                    "{func}: option `counts` must be whole numbers from 1 to 100000, not [{}, {}]",
                    c[0], c[1]
                )));
            }
            Tile::Counts([c[0] as u32, c[1] as u32])
        }
        (None, None) => Tile::Size([5.0, 5.0]),
    };
    let depth = o.number("tex_depth")?.unwrap_or(1.0);
    let inset = match o.take("tex_inset") {
        None => 0.0,
        Some(v) => {
            if let Ok(b) = v.as_bool() {
                if b { depth } else { 0.0 }
            } else if let Some(mm) = as_number(&v).filter(|x| x.is_finite()) {
                mm
            } else {
                return Err(o.wrong_type("tex_inset", "a number (mm) or true/false", &v));
            }
        }
    };
    let rotate = o.flag("tex_rot")?.unwrap_or(false);
    Ok(TextureOptions {
        tile,
        depth,
        inset,
        rotate,
    })
}

fn textured_linear(args: [&Dynamic; 3], opts: Map) -> RhaiResult<Shape> {
    let func = "textured_linear_sweep";
    let profile = profile_arg(func, 1, args[0])?;
    let tex = texture_arg(func, 2, args[1])?;
    let h = number_arg(func, 3, "h", args[2])?;
    let mut o = Options::new(func, opts);
    let sweep = linear_options(&mut o, h)?;
    let t = texture_options(&mut o)?;
    o.finish()?;
    built(
        func,
        texture::textured_linear_sweep(&profile, &tex, &sweep, &t),
    )
}

fn textured_revolution(args: [&Dynamic; 2], opts: Map) -> RhaiResult<Shape> {
    let func = "textured_revolution";
    let profile = profile_arg(func, 1, args[0])?;
    let tex = texture_arg(func, 2, args[1])?;
    let mut o = Options::new(func, opts);
    let angle = o.number("angle")?.unwrap_or(360.0);
    let t = texture_options(&mut o)?;
    o.finish()?;
    built(
        func,
        texture::textured_revolution(&profile, &tex, angle, &t),
    )
}

fn textured_cylinder(args: [&Dynamic; 3], opts: Map) -> RhaiResult<Shape> {
    let func = "textured_cylinder";
    let r = number_arg(func, 1, "r", args[0])?;
    let h = number_arg(func, 2, "h", args[1])?;
    let tex = texture_arg(func, 3, args[2])?;
    let mut o = Options::new(func, opts);
    // Centred like `cylinder(r, h)` unless told otherwise.
    let centred = o.take("center");
    let mut sweep = linear_options(&mut o, h)?;
    sweep.center = match centred {
        None => true,
        Some(v) => v
            .as_bool()
            .map_err(|_| o.wrong_type("center", "true or false", &v))?,
    };
    let t = texture_options(&mut o)?;
    o.finish()?;
    built(func, texture::textured_cylinder(r, &tex, &sweep, &t))
}

/// The largest side of an image texture.
const MAX_IMAGE_SIDE: u32 = 4096;

/// Decodes a PNG into rows of brightness 0..1 (colour is turned to luma, alpha ignored).
pub fn decode_png(name: &str, bytes: &[u8]) -> Result<Vec<Vec<f64>>, String> {
    let mut decoder = png::Decoder::new(Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder
        .read_info()
        .map_err(|e| format!("\"{name}\" is not a PNG image that can be read: {e}"))?;
    let (w, h) = (reader.info().width, reader.info().height);
    if w == 0 || h == 0 || w > MAX_IMAGE_SIDE || h > MAX_IMAGE_SIDE {
        return Err(format!(
            "\"{name}\" is {w} x {h} pixels; an image texture may be at most {MAX_IMAGE_SIDE} x {MAX_IMAGE_SIDE}"
        ));
    }
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| format!("\"{name}\" is too large to decode"))?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("\"{name}\": cannot decode the image: {e}"))?;
    let channels = info.color_type.samples();
    let mut rows = Vec::with_capacity(info.height as usize);
    for y in 0..info.height as usize {
        let line = &buf[y * info.line_size..(y + 1) * info.line_size];
        let row = (0..info.width as usize)
            .map(|x| {
                let px = &line[x * channels..(x + 1) * channels];
                let value = match channels {
                    // Gray, or gray with alpha.
                    1 | 2 => f64::from(px[0]),
                    // RGB(A): luma, ITU-R BT.601 weights.
                    _ => {
                        0.299 * f64::from(px[0])
                            + 0.587 * f64::from(px[1])
                            + 0.114 * f64::from(px[2])
                    }
                };
                value / 255.0
            })
            .collect();
        rows.push(row);
    }
    Ok(rows)
}

/// Registers the textured sweeps and `image`, reading images from `folder`.
pub fn register(engine: &mut Engine, folder: &ScriptFolder) {
    engine.register_type_with_name::<Texture>("Texture");
    engine.register_fn("to_string", |t: &mut Texture| format!("{t:?}"));
    engine.register_fn("to_debug", |t: &mut Texture| format!("{t:?}"));
    let folder = Arc::new(folder.clone());
    engine.register_fn("image", move |name: &str| -> RhaiResult<Texture> {
        let bytes = folder.read(name).map_err(|e| fail(format!("image: {e}")))?;
        let rows = decode_png(name, &bytes).map_err(|e| fail(format!("image: {e}")))?;
        built("image", texture::heights(rows))
    });
    engine.register_fn(
        "textured_linear_sweep",
        |p: Dynamic, t: Dynamic, h: Dynamic| textured_linear([&p, &t, &h], Map::new()),
    );
    engine.register_fn(
        "textured_linear_sweep",
        |p: Dynamic, t: Dynamic, h: Dynamic, o: Map| textured_linear([&p, &t, &h], o),
    );
    engine.register_fn("textured_revolution", |p: Dynamic, t: Dynamic| {
        textured_revolution([&p, &t], Map::new())
    });
    engine.register_fn("textured_revolution", |p: Dynamic, t: Dynamic, o: Map| {
        textured_revolution([&p, &t], o)
    });
    engine.register_fn("textured_cylinder", |r: Dynamic, h: Dynamic, t: Dynamic| {
        textured_cylinder([&r, &h, &t], Map::new())
    });
    engine.register_fn(
        "textured_cylinder",
        |r: Dynamic, h: Dynamic, t: Dynamic, o: Map| textured_cylinder([&r, &h, &t], o),
    );
}
