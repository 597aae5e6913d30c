//! `isoforge mesh --param t=0..1:N`: one mesh per step of a parameter range, `NAME-000.stl`
//! upward. Each step is an ordinary `isoforge mesh` run with the parameter fixed; its file is
//! then read back and checked, so the report is of what is on disk. A step whose mesh has
//! parts thinner than the lattice gets the same note a single run does; a step refined
//! where it missed its tolerance (`finer.rs`) reports how many levels finer.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context as _, Result};
use isoforge_mesh::{MeshFormat, check, read_mesh};
use isoforge_output::Options;
use serde_json::json;

use super::{MeshArgs, extension};
use crate::cmd::render::frame_name;
use crate::common::{Global, Sweep, print_json};

/// The file of step `i` of `n`: `NAME-000.ext` beside `output` (NAME its stem).
fn step_path(output: &Path, i: usize, n: usize, format: MeshFormat) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    let name = frame_name(i, n, extension(format));
    output.with_file_name(format!("{stem}-{name}"))
}

/// Meshes every step of `sweep` (the other arguments as given) into `NAME-000.ext` upward.
pub fn run(
    args: &MeshArgs,
    sweep: &Sweep,
    format: MeshFormat,
    output: &Path,
    global: &Global,
) -> Result<ExitCode> {
    let start = Instant::now();
    let n = sweep.values.len();
    let paths: Vec<PathBuf> = (0..n).map(|i| step_path(output, i, n, format)).collect();
    let inputs = [args.model.model.as_path()];
    // Before the work: every file can be written (a read-only one is refused now, not
    // after meshing half the steps).
    for p in &paths {
        isoforge_output::check_file(p, Options::with_inputs(&inputs))?;
    }
    let quiet = Global {
        quiet: true,
        json: false,
    };
    let mut steps = Vec::with_capacity(n);
    let mut failed = Vec::new();
    for (i, (&value, path)) in sweep.values.iter().zip(&paths).enumerate() {
        let step = || format!("step {i} ({}={value})", sweep.name);
        let mut step_args = args.clone();
        step_args.model = args.model.at_step(sweep, value);
        step_args.output = Some(path.clone());
        step_args.format = Some(format.name().to_string());
        // Exit 1 (a mesh not closed) is seen again in the check below.
        let (_, made) = super::mesh_one(step_args, format, path.clone(), &quiet, Instant::now())
            .with_context(step)?;
        let mesh = read_mesh(path).with_context(step)?;
        let report = check(&mesh);
        if !report.is_closed_manifold() {
            failed.push(format!(
                "{}: {}",
                path.display(),
                report.problems().join("; ")
            ));
        }
        if !global.quiet && !global.json {
            println!(
                "{}: {}={value}, {} triangles, {} vertices, volume {:.6}",
                path.display(),
                sweep.name,
                report.triangles,
                report.vertices,
                report.volume
            );
        }
        // Each step's own note: a sweep can thin a part below the lattice at some values.
        for note in made.notes() {
            if !global.quiet {
                eprintln!("note: {}: {note}", path.display());
            }
        }
        let mut j = crate::cmd::check::report_json(&path.display().to_string(), &report);
        j["value"] = json!(value);
        j["thin_triangles"] = json!(made.thin_triangles);
        j["depth"] = json!(made.depth);
        if made.refined_levels > 0 {
            j["refined_levels"] = json!(made.refined_levels);
        }
        if let Some(held) = made.tolerance_held {
            j["tolerance_held"] = json!(held);
        }
        if let Some(places) = &made.left_off {
            j["left_off"] = places.to_json();
        }
        steps.push(j);
    }
    if global.json {
        print_json(&json!({
            "parameter": sweep.name,
            "steps": steps,
            "seconds": start.elapsed().as_secs_f64(),
        }));
    }
    if !failed.is_empty() {
        eprintln!(
            "error: meshes not closed and manifold: {}",
            failed.join(" | ")
        );
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_files_are_numbered_beside_the_output() {
        let p = step_path(Path::new("out/lamp.stl"), 4, 30, MeshFormat::Stl);
        assert_eq!(p, Path::new("out/lamp-004.stl"));
        let p = step_path(Path::new("lamp.3mf"), 12, 1500, MeshFormat::ThreeMf);
        assert_eq!(p, Path::new("lamp-0012.3mf"));
    }
}
