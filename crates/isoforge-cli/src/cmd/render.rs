//! `isoforge render`: a shaded PNG picture of a model, for looking before printing.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result};
use clap::{Args, ValueEnum};
use isoforge_render::{GifWriter, RenderSettings, View, render};
use serde_json::json;

use isoforge_output::{Options, OutputFile, OutputFolder};

use crate::common::{Global, ModelArgs, Sweep, print_json, usage};

/// The viewpoints, as named on the command line.
#[derive(Copy, Clone, Debug, Default, ValueEnum)]
pub enum ViewArg {
    /// From the front, right and above.
    #[default]
    Iso,
    /// From above.
    Top,
    /// From the front (-y).
    Front,
    /// From the right (+x).
    Right,
}

impl From<ViewArg> for View {
    fn from(v: ViewArg) -> View {
        match v {
            ViewArg::Iso => View::Iso,
            ViewArg::Top => View::Top,
            ViewArg::Front => View::Front,
            ViewArg::Right => View::Right,
        }
    }
}

/// Arguments of `isoforge render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// The PNG to write (default: the model's name with .png).
    #[arg(short, long, value_name = "OUT.png")]
    output: Option<PathBuf>,
    /// Picture size in pixels, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", default_value = "800x600", value_parser = parse_size)]
    size: (u32, u32),
    /// The viewpoint.
    #[arg(long, value_enum, default_value_t = ViewArg::Iso)]
    view: ViewArg,
    /// Depth resolution: the finest step along the view ray is the depth range / 2^N
    /// (default: about one pixel).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=24))]
    depth: Option<u8>,
    /// Frame the whole region, not just the model in it (always so for an animation, so
    /// that every frame has the same view).
    #[arg(long)]
    whole_region: bool,
    /// With a parameter range (--param t=0..1:30): write the frames as numbered PNGs
    /// (000.png upward) into this new or empty folder.
    #[arg(long, value_name = "DIR")]
    frames: Option<PathBuf>,
    /// With a parameter range: write the frames as an animated, looping GIF.
    #[arg(long, value_name = "FILE")]
    gif: Option<PathBuf>,
    /// Frames per second of the GIF.
    #[arg(long, value_name = "N", default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100))]
    fps: u32,
}

/// The largest side accepted: 16k pixels (a 16k x 16k RGB image is already 768 MiB).
const MAX_SIDE: u32 = 16384;

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{text:?}: expected WIDTHxHEIGHT, e.g. 800x600");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(format!(
            "{text:?}: each side must be 1 to {MAX_SIDE} pixels"
        ));
    }
    Ok((w, h))
}

/// Runs the command.
pub fn run(args: RenderArgs, global: &Global) -> Result<ExitCode> {
    if let Some(sweep) = args.model.sweep()? {
        return animate(args, sweep, global);
    }
    if args.frames.is_some() || args.gif.is_some() {
        return Err(usage(
            "--frames and --gif need a parameter range, e.g. --param t=0..1:30".to_string(),
        ));
    }
    let start = Instant::now();
    let loaded = args.model.load()?;
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| args.model.model.with_extension("png"));
    let output = OutputFile::prepare(&out, Options::with_inputs(&[&args.model.model]))?;
    let settings = settings(&args, !args.whole_region);
    let spinner = crate::common::progress_bar(global, 1, "render");
    let image = render(&loaded.model.shape, &loaded.bounds, &settings);
    spinner.finish_and_clear();
    output.write_with(|w| {
        image
            .write_png(w)
            .with_context(|| format!("{}: PNG encoding failed", out.display()))
    })?;
    let seconds = start.elapsed().as_secs_f64();
    if global.json {
        print_json(&json!({
            "output": out.display().to_string(),
            "width": image.width,
            "height": image.height,
            "view": format!("{:?}", args.view).to_lowercase(),
            "seconds": seconds,
        }));
    } else if !global.quiet {
        eprintln!(
            "wrote {} ({}x{}, {:.2} s)",
            out.display(),
            image.width,
            image.height,
            seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn settings(args: &RenderArgs, fit: bool) -> RenderSettings {
    RenderSettings {
        view: args.view.into(),
        width: args.size.0,
        height: args.size.1,
        depth: args.depth,
        fit,
    }
}

/// The file name of frame `i` of `n`: zero-padded to at least three digits.
pub fn frame_name(i: usize, n: usize, ext: &str) -> String {
    let digits = (n.saturating_sub(1)).to_string().len().max(3);
    format!("{i:0digits$}.{ext}")
}

/// Renders one frame per step of the parameter range into --frames and/or --gif. The
/// view is framed on the whole region, so it stands still while the model moves.
fn animate(args: RenderArgs, sweep: Sweep, global: &Global) -> Result<ExitCode> {
    let start = Instant::now();
    if args.frames.is_none() && args.gif.is_none() {
        return Err(usage(format!(
            "--param {}=..: a range renders an animation: give --frames DIR and/or --gif FILE",
            sweep.name
        )));
    }
    if args.output.is_some() {
        return Err(usage(
            "-o names one picture: with a parameter range use --frames DIR or --gif FILE"
                .to_string(),
        ));
    }
    let inputs = [args.model.model.as_path()];
    // Before the work: the folder and the file can be written.
    let mut folder = args
        .frames
        .as_deref()
        .map(|dir| OutputFolder::prepare(dir, Options::with_inputs(&inputs)))
        .transpose()?;
    let gif = args
        .gif
        .as_deref()
        .map(|file| OutputFile::prepare(file, Options::with_inputs(&inputs)))
        .transpose()?;
    let settings = settings(&args, false);
    let n = sweep.values.len();
    let bar = crate::common::progress_bar(global, n as u64, "frames");
    // Renders every frame into the folder and hands each to `each` (the GIF's encoder).
    let mut frames = |each: &mut dyn FnMut(&isoforge_render::Image) -> Result<()>| -> Result<()> {
        for (i, &value) in sweep.values.iter().enumerate() {
            let loaded = args
                .model
                .at_step(&sweep, value)
                .load()
                .with_context(|| format!("frame {i} ({}={value})", sweep.name))?;
            let image = render(&loaded.model.shape, &loaded.bounds, &settings);
            if let Some(folder) = folder.as_mut() {
                let mut png = Vec::new();
                image
                    .write_png(&mut png)
                    .with_context(|| format!("frame {i}: PNG encoding failed"))?;
                folder.write(&frame_name(i, n, "png"), &png)?;
            }
            each(&image)?;
            bar.inc(1);
        }
        Ok(())
    };
    match gif {
        Some(gif) => {
            let path = args.gif.clone().unwrap_or_default();
            let delay = 1000 / args.fps;
            gif.write_with(|w| -> Result<()> {
                let mut encoder = GifWriter::new(w, delay)
                    .with_context(|| format!("{}: GIF encoding failed", path.display()))?;
                frames(&mut |image| {
                    encoder
                        .push(image)
                        .with_context(|| format!("{}: GIF encoding failed", path.display()))
                })
            })?;
        }
        None => frames(&mut |_| Ok(()))?,
    }
    bar.finish_and_clear();
    if let Some(folder) = folder {
        folder.commit()?;
    }
    let seconds = start.elapsed().as_secs_f64();
    if global.json {
        print_json(&json!({
            "frames": n,
            "parameter": sweep.name,
            "values": sweep.values,
            "frames_dir": args.frames.as_ref().map(|p| p.display().to_string()),
            "gif": args.gif.as_ref().map(|p| p.display().to_string()),
            "width": args.size.0,
            "height": args.size.1,
            "seconds": seconds,
        }));
    } else if !global.quiet {
        let mut wrote = Vec::new();
        if let Some(d) = &args.frames {
            wrote.push(format!("{n} frames in {}", d.display()));
        }
        if let Some(g) = &args.gif {
            wrote.push(format!("{} ({n} frames at {} fps)", g.display(), args.fps));
        }
        eprintln!("wrote {} ({:.2} s)", wrote.join(" and "), seconds);
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes() {
        assert_eq!(parse_size("800x600"), Ok((800, 600)));
        assert_eq!(parse_size("64X32"), Ok((64, 32)));
        for bad in ["800", "0x10", "10x", "axb", "99999x2", "-1x5"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }
}
