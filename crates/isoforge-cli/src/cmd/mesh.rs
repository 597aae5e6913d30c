//! `isoforge mesh`: a model to a closed, manifold triangle mesh file.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::{Context as _, Result, bail};
use clap::Args;
use isoforge_mesh::io::MeshWriter;
use isoforge_mesh::{
    Estimate, MAX_DEPTH, MeshError, MeshFormat, MeshNotes, MeshSettings, StreamCheck,
};
use isoforge_output::{Options, OutputFile};
use serde_json::json;

use crate::common::{Global, ModelArgs, print_json, progress_bar};
use crate::machine::human_bytes;

/// The default finest level: the region's longest side in 256 cells.
const DEFAULT_DEPTH: u8 = 8;

mod steps;

/// Arguments of `isoforge mesh`.
#[derive(Args, Clone, Debug)]
pub struct MeshArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output file (default: the model's name with .stl, beside the model).
    #[arg(short, long, value_name = "OUT")]
    output: Option<PathBuf>,
    /// Finest cell size in mm (default: the region's longest side / 256).
    #[arg(long, value_name = "MM", conflicts_with = "depth")]
    resolution: Option<f64>,
    /// Finest level: 2^N cells along the region's longest side.
    #[arg(long, value_name = "N")]
    depth: Option<u8>,
    /// Largest distance in mm between the mesh and the true surface: flat parts get large
    /// triangles (default: a tenth of the finest cell; 0 keeps every cell at the finest
    /// size).
    #[arg(long, value_name = "MM")]
    tolerance: Option<f64>,
    /// stl (binary), stl-ascii, 3mf, obj or ply (default: from OUT's extension, else stl).
    #[arg(long, value_name = "F")]
    format: Option<String>,
    /// Worker threads (default: all cores; at most 256).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Mesh even when the estimated memory is more than the machine has available.
    #[arg(long)]
    no_memory_check: bool,
}

/// The most worker threads `--threads` takes: far more than any machine's cores, and few
/// enough that starting them is quick (each reserves a stack).
const MAX_THREADS: usize = 256;

/// The note on parts thinner than the lattice is printed when at least one triangle in
/// this many joins the two sides of one. A few such triangles are in many meshes at any
/// depth (where a gyroid's sheet meets a ball at a grazing angle, a sliver thinner than
/// any lattice: 0.5 % and 0.9 % of gyroid_sphere's at depths 8 and 9); a sheet thinner
/// than a cell everywhere puts 15 % of a mesh there.
const THIN_NOTE_SHARE: u64 = 50;

/// A usage error: message, exit status 2 (reported by `main`, with `--json` too).
fn usage(message: String) -> Result<ExitCode> {
    Err(crate::common::usage(message))
}

/// Refuses a mesh whose estimated peak memory is more than the machine has available.
fn check_fits(estimate: &Estimate, available: Option<u64>) -> Result<()> {
    let Some(available) = available else {
        return Ok(());
    };
    if estimate.bytes <= available as f64 {
        return Ok(());
    }
    Err(crate::common::usage(format!(
        "depth {}: about {:.1e} cells to sample in {:.1e} blocks near the surface would need \
         about {} of memory, and this machine has {} available; use a smaller --depth (each level less \
         needs about a quarter), a smaller region, or --no-memory-check to try anyway",
        estimate.depth,
        estimate.cells,
        estimate.blocks,
        human_bytes(estimate.bytes),
        human_bytes(available as f64),
    )))
}

/// The depth for a cell size: the first level whose cells are no larger.
fn depth_for(longest: f64, resolution: f64) -> Option<u8> {
    (0..=MAX_DEPTH).find(|&d| longest / f64::from(1u32 << d) <= resolution * (1.0 + 1e-9))
}

fn extension(format: MeshFormat) -> &'static str {
    match format {
        MeshFormat::Stl | MeshFormat::StlAscii => "stl",
        MeshFormat::ThreeMf => "3mf",
        MeshFormat::Obj => "obj",
        MeshFormat::Ply => "ply",
    }
}

fn default_output(model: &Path, format: MeshFormat) -> PathBuf {
    model.with_extension(extension(format))
}

/// Runs the command.
pub fn run(args: MeshArgs, global: &Global) -> Result<ExitCode> {
    let start = Instant::now();
    // Usage checks first, before any work.
    let format = match (&args.format, &args.output) {
        (Some(name), _) => match MeshFormat::from_name(name) {
            Some(f) => f,
            None => {
                return usage(format!(
                    "--format {name:?}: expected stl, stl-ascii, 3mf, obj or ply"
                ));
            }
        },
        (None, Some(out)) => MeshFormat::from_extension(out).unwrap_or(MeshFormat::Stl),
        (None, None) => MeshFormat::Stl,
    };
    if let Some(r) = args.resolution
        && !(r.is_finite() && r > 0.0)
    {
        return usage(format!("--resolution {r}: expected a positive size in mm"));
    }
    if let Some(d) = args.depth
        && d > MAX_DEPTH
    {
        return usage(format!("--depth {d}: at most {MAX_DEPTH}"));
    }
    if let Some(t) = args.tolerance
        && !(t.is_finite() && t >= 0.0)
    {
        return usage(format!(
            "--tolerance {t}: expected a distance in mm, 0 or more"
        ));
    }
    if let Some(n) = args.threads
        && !(1..=MAX_THREADS).contains(&n)
    {
        return usage(format!("--threads {n}: expected 1 to {MAX_THREADS}"));
    }
    let output = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.model.model, format));
    if let Some(sweep) = args.model.sweep()? {
        return steps::run(&args, &sweep, format, &output, global);
    }
    let (code, _) = mesh_one(args, format, output, global, start)?;
    Ok(code)
}

/// What one mesh run noticed, for a caller that reports it (`steps.rs`).
pub(super) struct Made {
    /// Triangles joining the two sides of parts thinner than the lattice resolves.
    pub thin_triangles: u64,
    /// Triangles written.
    pub triangles: u64,
    /// The finest cell's side.
    pub cell: f64,
}

impl Made {
    /// The note on parts thinner than the lattice, when they are enough of the mesh to
    /// tell ([`THIN_NOTE_SHARE`]).
    pub fn thin_note(&self) -> Option<String> {
        (self.triangles > 0 && self.thin_triangles * THIN_NOTE_SHARE >= self.triangles).then(|| {
            format!(
                "{} triangles ({:.1} % of the mesh) join the two sides of parts thinner than \
                 about two cells ({:.3} mm): sheets, needles or gaps the lattice does not \
                 resolve, where the mesh may be off by up to a cell; a finer --depth \
                 resolves them",
                self.thin_triangles,
                100.0 * self.thin_triangles as f64 / self.triangles as f64,
                2.0 * self.cell
            )
        })
    }
}

/// Meshes the model as `args` say (one parameter value) into `output`, and reports it.
pub(super) fn mesh_one(
    args: MeshArgs,
    format: MeshFormat,
    output: PathBuf,
    global: &Global,
    start: Instant,
) -> Result<(ExitCode, Made)> {
    let loaded = args.model.load()?;
    let bounds = loaded.bounds;
    let depth = match (args.depth, args.resolution) {
        (Some(d), _) => d,
        (None, Some(r)) => match depth_for(bounds.longest_side(), r) {
            Some(d) => d,
            None => {
                return Err(crate::common::usage(format!(
                    "--resolution {r}: too fine for a region {} mm long (at most 2^{MAX_DEPTH} cells)",
                    bounds.longest_side()
                )));
            }
        },
        (None, None) => DEFAULT_DEPTH,
    };
    // Before the work: a model given as its own output, a missing folder or a read-only
    // file is refused now, not after minutes of meshing.
    let out = OutputFile::prepare(&output, Options::with_inputs(&[&args.model.model]))?;

    let mut settings = MeshSettings::new(bounds, depth);
    settings.threads = args.threads.unwrap_or(0);
    settings.tolerance = args.tolerance;
    let notes = Arc::new(MeshNotes::default());
    settings.notes = Some(notes.clone());
    // The lattice's own bound first: when even a mesh of every block fits (depth 9 and
    // below, on any machine), the octree is not built twice just to count.
    let available = crate::machine::available_memory();
    let mut estimate = isoforge_mesh::estimate_bound(&settings);
    if available.is_some_and(|a| estimate.bytes > a as f64) {
        estimate = isoforge_mesh::estimate(&loaded.model.shape, &settings);
    }
    if !args.no_memory_check {
        check_fits(&estimate, available)?;
    }

    let bar = progress_bar(global, 1000, "meshing");
    let bar_cb = bar.clone();
    settings.progress = Some(Arc::new(move |f: f64| {
        bar_cb.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64)
    }));
    // The mesh goes to the file as it is made, through a checker: never held whole.
    let spill_folder = out
        .target()
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(std::env::temp_dir);
    let writer = MeshWriter::streaming(
        format,
        std::io::BufWriter::with_capacity(1 << 20, out),
        &spill_folder,
    )
    .with_context(|| format!("{}: cannot write the mesh", output.display()))?;
    let centre = [0, 1, 2].map(|a| (bounds.min[a] + bounds.max[a]) * 0.5);
    let mut sink = StreamCheck::new(writer, centre);
    match isoforge_mesh::mesh_shape_into(&loaded.model.shape, &settings, &mut sink) {
        Ok(()) => {}
        Err(MeshError::Write(e)) => {
            return Err(e).with_context(|| format!("{}: cannot write the mesh", output.display()));
        }
        Err(e) => return Err(e.into()),
    }
    bar.finish_and_clear();
    let (report, writer) = sink.finish();
    if report.tally.triangles == 0 {
        bail!(
            "{}: nothing is inside the region {:?} to {:?} at depth {depth} (the field is not \
             negative at any lattice corner; parts thinner than a cell need a finer --depth)",
            args.model.model.display(),
            bounds.min,
            bounds.max
        );
    }
    let file = writer
        .finish()
        .and_then(|buf| buf.into_inner().map_err(|e| e.into_error()))
        .with_context(|| format!("{}: cannot write the mesh", output.display()))?;
    file.commit()?;
    let seconds = start.elapsed().as_secs_f64();
    let thin_triangles = notes.thin_triangles.load(Ordering::Relaxed);
    if global.json {
        print_json(&json!({
            "triangles": report.tally.triangles,
            "vertices": report.tally.vertices,
            "volume": report.tally.volume(),
            "area": report.tally.area(),
            "bounds": report.tally.bounds.map(|b| b.map(|c| c.map(f64::from))),
            "watertight": report.watertight,
            "manifold": report.manifold,
            "depth": depth,
            "tolerance": settings.effective_tolerance(),
            "estimate": {
                "blocks": estimate.blocks,
                "cells": estimate.cells,
                "bytes": estimate.bytes,
            },
            "thin_triangles": thin_triangles,
            "parts_turned": notes.parts_turned.load(Ordering::Relaxed),
            "seconds": seconds,
        }));
    } else if !global.quiet {
        println!(
            "{}: {} triangles, {} vertices, volume {:.6}, depth {depth}, tolerance {:.3e} mm, {:.2} s",
            output.display(),
            report.tally.triangles,
            report.tally.vertices,
            report.tally.volume(),
            settings.effective_tolerance(),
            seconds
        );
    }
    let made = Made {
        thin_triangles,
        triangles: report.tally.triangles,
        cell: settings.cell(),
    };
    if let Some(note) = made.thin_note()
        && !global.quiet
    {
        eprintln!("note: {note}");
    }
    if !report.is_closed_manifold() {
        eprintln!(
            "error: the mesh is not closed and manifold ({} vertices on holes; watertight: {}, \
             manifold: {}); please report this as a bug with the model",
            report.open_vertices, report.watertight, report.manifold
        );
        return Ok((ExitCode::from(1), made));
    }
    Ok((ExitCode::SUCCESS, made))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_picks_the_first_fine_enough_depth() {
        assert_eq!(depth_for(3.0, 3.0 / 256.0), Some(8));
        assert_eq!(depth_for(3.0, 0.02), Some(8));
        assert_eq!(depth_for(3.0, 10.0), Some(0));
        assert_eq!(depth_for(3.0, 1e-9), None);
    }
}
