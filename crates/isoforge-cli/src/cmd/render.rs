//! `isoforge render`: a shaded PNG picture of a model, for looking before printing.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result};
use clap::{Args, ValueEnum};
use isoforge_render::{RenderSettings, View, render};
use serde_json::json;

use isoforge_output::{Options, OutputFile};

use crate::common::{Global, ModelArgs, print_json};

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
    /// Frame the whole region, not just the model in it.
    #[arg(long)]
    whole_region: bool,
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
    let start = Instant::now();
    let loaded = args.model.load()?;
    let out = args
        .output
        .clone()
        .unwrap_or_else(|| args.model.model.with_extension("png"));
    let output = OutputFile::prepare(&out, Options::with_inputs(&[&args.model.model]))?;
    let settings = RenderSettings {
        view: args.view.into(),
        width: args.size.0,
        height: args.size.1,
        depth: args.depth,
        fit: !args.whole_region,
    };
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
