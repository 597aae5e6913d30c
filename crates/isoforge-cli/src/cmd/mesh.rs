//! `isoforge mesh`: a model to a closed, manifold triangle mesh file.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use isoforge_mesh::{Estimate, MAX_DEPTH, MeshFormat, MeshSettings};

/// The most levels finer a block may be sampled (`isoforge_mesh::Refinement`).
const MAX_LEVELS: u8 = isoforge_mesh::MAX_REFINE_LEVELS;
use serde_json::json;

use crate::common::{Global, LoadedModel, ModelArgs, print_json};
use crate::machine::human_bytes;

/// The default finest level: the region's longest side in 256 cells.
const DEFAULT_DEPTH: u8 = 8;

mod attempt;
mod finer;
mod left_off;
mod steps;

/// Levels finer a run without `--depth` or `--resolution` may sample the blocks where the
/// mesh misses the tolerance: down to depth 11 from the default 8 (docs/meshing.md).
const AUTO_LEVELS: u8 = 3;

/// The most fine blocks a run without `--max-depth` may add, as a multiple of its blocks.
const AUTO_BUDGET: f64 = 3.0;

/// The longest a run without `--max-depth` may spend refining, as a multiple of its plain
/// mesh's time (at least 30 s): heart_shell, a slow field that needs three levels, takes
/// about 20 times its plain mesh's time to hold its tolerance.
const AUTO_SECONDS: f64 = 30.0;

/// The most fine blocks `--max-depth` may add, as a multiple of the blocks: about what
/// meshing the whole model two levels finer would cost.
const MAX_DEPTH_BUDGET: f64 = 15.0;

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
    /// Depth to go down to for the tolerance: each mesh is measured against the model by the
    /// field and, while it misses the tolerance (in mm, the first depth's), the blocks where
    /// it misses are sampled finer, down to depth N there (at most 4 levels finer than the
    /// first). Without --depth or --resolution, the mesh is refined where its own places say
    /// it misses, down to 3 levels finer, unless this says otherwise.
    #[arg(long, value_name = "N")]
    max_depth: Option<u8>,
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
pub(super) const THIN_NOTE_SHARE: u64 = 50;

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

/// The memory estimate for `settings`, refused when it is more than the machine has
/// available (unless `unchecked`). The lattice's own bound first: when even a mesh of every
/// block fits (depth 9 and below, on any machine), the octree is not built twice just to
/// count.
fn fitting_estimate(
    loaded: &LoadedModel,
    settings: &MeshSettings,
    available: Option<u64>,
    unchecked: bool,
) -> Result<Estimate> {
    let mut estimate = isoforge_mesh::estimate_bound(settings);
    if available.is_some_and(|a| estimate.bytes > a as f64) {
        estimate = isoforge_mesh::estimate(&loaded.model.shape, settings);
    }
    if !unchecked {
        check_fits(&estimate, available)?;
    }
    Ok(estimate)
}

/// A point for a note: `(x, y, z)` to a micrometre.
fn point(p: [f64; 3]) -> String {
    format!("({:.3}, {:.3}, {:.3})", p[0], p[1], p[2])
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
    if let Some(d) = args.max_depth
        && d > MAX_DEPTH
    {
        return usage(format!("--max-depth {d}: at most {MAX_DEPTH}"));
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
    // A mesh that misses the tolerance is dropped for a finer one, which a pipe or a
    // device cannot take back.
    if args.max_depth.is_some() && std::fs::metadata(&output).is_ok_and(|m| !m.is_file()) {
        return usage(format!(
            "--max-depth: {} is not a regular file, and a mesh written there could not be \
             dropped for a finer one",
            output.display()
        ));
    }
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
    /// The depth of the lattice the mesh was made on.
    pub depth: u8,
    /// The levels finer the blocks where it missed were sampled (0 if none were).
    pub refined_levels: u8,
    /// When measured whole: whether the mesh holds the tolerance.
    pub tolerance_held: Option<bool>,
    /// Without it: the places the splits left off the surface, measured.
    pub left_off: Option<left_off::LeftOff>,
}

impl Made {
    /// The notes for the user: parts thinner than the lattice, places left off the
    /// surface.
    pub fn notes(&self) -> impl Iterator<Item = String> {
        let left_off = self.left_off.as_ref().and_then(|l| l.note(self.depth));
        self.thin_note().into_iter().chain(left_off)
    }

    /// The note on parts thinner than the lattice, when they are enough of the mesh to
    /// tell ([`THIN_NOTE_SHARE`]).
    fn thin_note(&self) -> Option<String> {
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
    let mut settings = MeshSettings::new(bounds, depth);
    settings.threads = args.threads.unwrap_or(0);
    settings.tolerance = args.tolerance;
    // Refining keeps the tolerance the first lattice's in millimetres everywhere.
    let tolerance = settings.effective_tolerance();
    let uniform = tolerance.is_nan() || tolerance <= 0.0;
    let lattice_given = args.depth.is_some() || args.resolution.is_some();
    let mut plan = match args.max_depth {
        Some(m) if m < depth => {
            return Err(crate::common::usage(format!(
                "--max-depth {m}: below the depth meshed first ({depth})"
            )));
        }
        Some(_) if uniform => {
            return Err(crate::common::usage(
                "--max-depth needs a tolerance above 0 (--tolerance 0 asks for uniform cells, \
                 with no distance to hold)"
                    .to_string(),
            ));
        }
        Some(m) => {
            if m - depth > MAX_LEVELS && !global.quiet {
                eprintln!(
                    "note: --max-depth {m}: blocks are sampled at most {MAX_LEVELS} levels \
                     finer than depth {depth}, down to depth {}",
                    depth + MAX_LEVELS
                );
            }
            finer::Plan {
                levels: (m - depth).min(MAX_LEVELS),
                measure: true,
                budget: MAX_DEPTH_BUDGET,
                seconds: None,
            }
        }
        None => finer::Plan {
            levels: if lattice_given || uniform {
                0
            } else {
                AUTO_LEVELS.min(MAX_DEPTH - depth)
            },
            measure: false,
            budget: AUTO_BUDGET,
            seconds: Some(AUTO_SECONDS),
        },
    };
    // Refining writes a mesh and may drop it for a finer one, which a pipe or a device
    // cannot take back (`--max-depth` refuses them before any work, in `run`).
    let regular = !std::fs::metadata(&output).is_ok_and(|m| !m.is_file());
    if !regular {
        plan.levels = 0;
    }
    if plan.levels > 0 {
        settings.tolerance = Some(tolerance);
    }
    let job = attempt::Job {
        model_path: &args.model.model,
        loaded: &loaded,
        format,
        output: &output,
    };
    let available = crate::machine::available_memory();
    let fit = |s: &MeshSettings| fitting_estimate(&loaded, s, available, args.no_memory_check);
    let finer::Rounds {
        kept,
        rounds,
        places,
        refined,
    } = finer::run(&job, settings, plan, global, &fit)?;
    let attempt::Attempt {
        settings,
        estimate,
        notes,
        report,
        deviation,
        file,
        ..
    } = kept;
    let depth = settings.depth;
    file.commit()?;
    let thin_triangles = notes.thin_triangles.load(Ordering::Relaxed);
    let held = deviation.map(|d| d.holds(tolerance));
    // Measured whole, the mesh needs no hint.
    let left_off = if deviation.is_none() { places } else { None };
    let refinement = settings.refine.clone();
    let seconds = start.elapsed().as_secs_f64();
    if global.json {
        let mut j = json!({
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
        });
        if let Some(places) = &left_off {
            j["left_off"] = places.to_json();
        }
        if let Some(r) = &refinement {
            j["refined"] = json!({
                "levels": r.levels,
                "blocks": r.blocks.len(),
                "of_blocks": notes.blocks.load(Ordering::Relaxed),
                "finest_depth": depth + r.levels,
                "tight_merges": r.tight_merges,
            });
        }
        if let Some(m) = args.max_depth {
            j["max_depth"] = json!(m);
        }
        if let Some(d) = deviation {
            j["max_deviation"] = json!(d.max);
            j["max_deviation_at"] = json!(d.at);
            j["mean_deviation"] = json!(d.mean);
            j["tolerance_held"] = json!(held);
        }
        if args.max_depth.is_some() || refined {
            j["rounds"] = json!(rounds);
        }
        print_json(&j);
    } else if !global.quiet {
        let measured = deviation
            .map(|d| format!(", up to {:.3e} mm off", d.max))
            .unwrap_or_default();
        let finer = refinement
            .as_ref()
            .map(|r| format!(" ({})", blocks_finer(r, depth)))
            .unwrap_or_default();
        println!(
            "{}: {} triangles, {} vertices, volume {:.6}, depth {depth}{finer}, tolerance {:.3e} mm{measured}, {:.2} s",
            output.display(),
            report.tally.triangles,
            report.tally.vertices,
            report.tally.volume(),
            settings.effective_tolerance(),
            seconds
        );
    }
    if let (Some(false), Some(d)) = (held, deviation)
        && !global.quiet
    {
        let deeper = if plan.levels < MAX_LEVELS {
            "; a larger --max-depth may hold it"
        } else {
            ""
        };
        let levels = refinement.as_ref().map_or(0, |r| r.levels);
        eprintln!(
            "note: the mesh misses the tolerance ({tolerance:.3e} mm) by up to {:.3e} mm, at \
             {}, even sampled {levels} level{} finer where it missed{deeper}",
            d.max - tolerance,
            point(d.at),
            if levels == 1 { "" } else { "s" }
        );
    }
    let made = Made {
        thin_triangles,
        triangles: report.tally.triangles,
        cell: settings.cell(),
        depth,
        refined_levels: refinement.as_ref().map_or(0, |r| r.levels),
        tolerance_held: held,
        left_off,
    };
    for note in made.notes() {
        if !global.quiet {
            eprintln!("note: {note}");
        }
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

/// "30 blocks 2 levels finer": what a refinement of a mesh at `depth` is, for the summary
/// line and the progress bar.
fn blocks_finer(r: &isoforge_mesh::Refinement, depth: u8) -> String {
    let s = if r.levels == 1 { "" } else { "s" };
    let tight = if r.tight_merges {
        format!(", their cells merged as at depth {}", depth + r.levels)
    } else {
        String::new()
    };
    format!(
        "{} blocks {} level{s} finer{tight}",
        r.blocks.len(),
        r.levels
    )
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
