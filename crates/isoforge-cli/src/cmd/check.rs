//! `isoforge check`: read a mesh file and report whether it is printable (closed, manifold,
//! consistently oriented), with its figures; a G-code file is summed up instead
//! (`check_gcode.rs`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::Args;
use isoforge_field::ClippedField;
use isoforge_mesh::{Deviation, MAX_DEPTH, MeshReport, check, deviation_where_wide, read_mesh};
use serde_json::json;

use crate::common::{Global, ModelArgs, print_json};

/// Arguments of `isoforge check`.
#[derive(Args, Debug)]
#[command(
    after_help = "Exit status: 0 closed and manifold (and, with --tolerance, within it), \
                        1 not (the report says why), 2 the file cannot be read."
)]
pub struct CheckArgs {
    /// The mesh file: STL (binary or ASCII), 3MF, OBJ or PLY; or a G-code file (.gcode),
    /// any slicer's, summed up: layers, retractions, layer times, volume by feature.
    pub mesh: PathBuf,
    /// Also measure how far the mesh is from this model's surface (largest and mean
    /// distance, by the model's field).
    #[arg(long, value_name = "MODEL")]
    pub against: Option<PathBuf>,
    /// With --against: set a script parameter, NAME=VALUE (repeatable).
    #[arg(long = "param", value_name = "NAME=VALUE", requires = "against")]
    pub params: Vec<String>,
    /// With --against: the region X0,Y0,Z0,X1,Y1,Z1 the mesh was made in (default: the
    /// script's).
    #[arg(
        long,
        value_name = "X0,Y0,Z0,X1,Y1,Z1",
        allow_hyphen_values = true,
        requires = "against"
    )]
    pub bounds: Option<String>,
    /// With --against: the largest distance allowed (as `mesh --tolerance` takes it, in
    /// model units): the report says whether the mesh keeps within it and how much of its
    /// area does not, and the exit status is 1 if it does not.
    #[arg(long, value_name = "MM", requires = "against", value_parser = parse_tolerance)]
    pub tolerance: Option<f64>,
    /// With --tolerance: the depth the mesh was made at (as `mesh --depth` takes it, or as
    /// `mesh` reports it). Points beyond the tolerance where the model is narrower than
    /// two of that depth's cells (a solid or a gap no lattice of them can follow) are
    /// counted apart, and the report says whether the tolerance holds everywhere else.
    #[arg(long, value_name = "N", requires = "tolerance")]
    pub depth: Option<u8>,
}

/// Finest cells across which a solid or a gap counts as narrow (`--depth`): a feature
/// must span two lattice samples to be seen whole.
const NARROW_CELLS: f64 = 2.0;

/// A tolerance: a finite number, 0 or more.
fn parse_tolerance(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err(format!("'{s}' is not a distance (a number, 0 or more)")),
    }
}

/// Runs the command.
pub fn run(args: CheckArgs, global: &Global) -> Result<ExitCode> {
    let ext = args
        .mesh
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if super::check_gcode::GCODE_EXTENSIONS.contains(&ext.as_str()) {
        return super::check_gcode::run(&args.mesh, global);
    }
    let mesh = match read_mesh(&args.mesh) {
        Ok(m) => m,
        // The contract: 2 when the file cannot be read (1 is kept for "read, and broken").
        Err(e) => {
            return Err(crate::common::usage(e.to_string()));
        }
    };
    if let Some(d) = args.depth
        && d > MAX_DEPTH
    {
        return Err(crate::common::usage(format!(
            "--depth {d}: at most {MAX_DEPTH}"
        )));
    }
    // The model is loaded before the mesh is judged, so a bad model is an error, not a
    // report without its figures.
    let field = match &args.against {
        Some(model) => {
            let loaded = ModelArgs {
                model: model.clone(),
                params: args.params.clone(),
                bounds: args.bounds.clone(),
                script_timeout: isoforge_script::DEFAULT_MAX_SECONDS,
                script_memory: isoforge_script::DEFAULT_MAX_MEMORY_BYTES >> 20,
            }
            .load()?;
            Some((
                ClippedField::new(&loaded.model.shape, loaded.bounds),
                loaded.bounds.longest_side(),
            ))
        }
        None => None,
    };
    // The width under which the model counts as narrow: two cells of the mesh's depth.
    let narrow = match (&field, args.depth) {
        (Some((_, longest)), Some(d)) => NARROW_CELLS * longest / f64::from(1u32 << d),
        _ => 0.0,
    };
    let report = check(&mesh);
    let tolerance = args.tolerance;
    let dev = field
        .as_ref()
        .map(|(f, _)| deviation_where_wide(&mesh, f, tolerance.unwrap_or(f64::INFINITY), narrow));
    let held = match (dev, tolerance) {
        (Some(d), Some(t)) => d.holds(t),
        _ => true,
    };
    let name = args.mesh.display().to_string();
    if global.json {
        let mut j = report_json(&name, &report);
        if let (Some(d), Some(obj)) = (dev, j.as_object_mut()) {
            obj.insert("max_deviation".into(), json!(d.max));
            obj.insert("mean_deviation".into(), json!(d.mean));
            obj.insert("max_deviation_at".into(), json!(d.at));
            obj.insert("deviation_samples".into(), json!(d.samples));
            obj.insert("triangles_facing_against".into(), json!(d.facing_against));
            obj.insert("area_facing_against".into(), json!(d.area_facing_against));
            if let Some(t) = tolerance {
                obj.insert("tolerance".into(), json!(t));
                obj.insert("tolerance_held".into(), json!(held));
                obj.insert("area_beyond_tolerance".into(), json!(d.area_beyond));
                obj.insert("points_beyond_tolerance".into(), json!(d.points_beyond));
                if narrow > 0.0 {
                    obj.insert("narrow_width".into(), json!(narrow));
                    obj.insert(
                        "tolerance_held_where_wide".into(),
                        json!(d.holds_where_wide(t)),
                    );
                    obj.insert("max_deviation_where_wide".into(), json!(d.max_wide));
                    obj.insert("max_deviation_where_wide_at".into(), json!(d.max_wide_at));
                    obj.insert(
                        "area_beyond_where_narrow".into(),
                        json!(d.area_beyond_narrow),
                    );
                    obj.insert(
                        "points_beyond_where_narrow".into(),
                        json!(d.points_beyond_narrow),
                    );
                }
            }
        }
        print_json(&j);
    } else if !global.quiet {
        print!("{}", report_text(&name, &report));
        if let Some(d) = dev {
            print!("{}", deviation_text(&d));
            if let Some(t) = tolerance {
                print!("{}", tolerance_text(&d, t));
                if narrow > 0.0 && !d.holds(t) {
                    print!("{}", narrow_text(&d, t, narrow));
                }
            }
        }
    }
    Ok(if report.is_closed_manifold() && held {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The report as the JSON object `--json` prints.
pub fn report_json(file: &str, r: &MeshReport) -> serde_json::Value {
    json!({
        "file": file,
        "triangles": r.triangles,
        "vertices": r.vertices,
        "unused_vertices": r.unused_vertices,
        "components": r.components,
        "boundary_edges": r.boundary_edges,
        "non_manifold_edges": r.non_manifold_edges,
        "inconsistent_edges": r.inconsistent_edges,
        "degenerate_triangles": r.degenerate_triangles,
        "non_manifold_vertices": r.non_manifold_vertices,
        "bad_indices": r.bad_indices,
        "volume": r.volume,
        "area": r.area,
        "bounds": r.bounds,
        "watertight": r.watertight,
        "manifold": r.manifold,
        "closed_manifold": r.is_closed_manifold(),
        "problems": r.problems(),
    })
}

/// The readable report.
pub fn report_text(file: &str, r: &MeshReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let verdict = if r.is_closed_manifold() {
        "closed and manifold"
    } else {
        "NOT closed and manifold"
    };
    let _ = writeln!(s, "{file}: {verdict}");
    let mut row = |label: &str, value: String| {
        let _ = writeln!(s, "  {label:<24}{value}");
    };
    row("triangles", r.triangles.to_string());
    row("vertices", r.vertices.to_string());
    row("components", r.components.to_string());
    row("boundary edges", r.boundary_edges.to_string());
    row("non-manifold edges", r.non_manifold_edges.to_string());
    row("inconsistent edges", r.inconsistent_edges.to_string());
    row("non-manifold vertices", r.non_manifold_vertices.to_string());
    row("degenerate triangles", r.degenerate_triangles.to_string());
    row("volume", format!("{:.6} mm³", r.volume));
    row("area", format!("{:.6} mm²", r.area));
    match r.bounds {
        // Vertices are f32: print them as f32 so the numbers are the file's, not the
        // f64 widening's 17 digits.
        Some([lo, hi]) => {
            let (lo, hi) = (lo.map(|v| v as f32), hi.map(|v| v as f32));
            row(
                "bounds",
                format!(
                    "[{}, {}, {}] to [{}, {}, {}] ({} x {} x {} mm)",
                    lo[0],
                    lo[1],
                    lo[2],
                    hi[0],
                    hi[1],
                    hi[2],
                    hi[0] - lo[0],
                    hi[1] - lo[1],
                    hi[2] - lo[2]
                ),
            )
        }
        None => row("bounds", "none (no vertices)".into()),
    }
    row("watertight", yes_no(r.watertight));
    row("manifold", yes_no(r.manifold));
    for p in r.problems() {
        let _ = writeln!(s, "  problem: {p}");
    }
    s
}

/// The distance rows of the readable report, and the folds.
fn deviation_text(d: &Deviation) -> String {
    format!(
        "  {:<24}{:.6} mm (at [{}, {}, {}])\n  {:<24}{:.6} mm ({} points sampled)\n  {:<24}{} triangles ({:.4} % of the area)\n",
        "max deviation",
        d.max,
        d.at[0] as f32,
        d.at[1] as f32,
        d.at[2] as f32,
        "mean deviation",
        d.mean,
        d.samples,
        "facing against field",
        d.facing_against,
        100.0 * d.area_facing_against,
    )
}

/// The tolerance row: held, or how much is beyond it.
fn tolerance_text(d: &Deviation, t: f64) -> String {
    let verdict = if d.holds(t) {
        "held".to_string()
    } else {
        format!(
            "NOT held: {}{:.4} % of the area ({} of {} points) farther",
            if d.beyond_exact { "" } else { "at most " },
            100.0 * d.area_beyond,
            d.points_beyond,
            d.samples
        )
    };
    format!("  {:<24}{t:.6} mm: {verdict}\n", "tolerance")
}

/// The rows that split what is beyond the tolerance by the model's width there.
fn narrow_text(d: &Deviation, t: f64, narrow: f64) -> String {
    let wide = if d.holds_where_wide(t) {
        "held".to_string()
    } else {
        format!(
            "NOT held: {:.6} mm at [{}, {}, {}]",
            d.max_wide, d.max_wide_at[0] as f32, d.max_wide_at[1] as f32, d.max_wide_at[2] as f32
        )
    };
    format!(
        "  {:<24}{wide}\n  {:<24}{:.4} % of the area ({} points) beyond, where narrower\n",
        format!("where ≥ {narrow:.4} mm wide"),
        "",
        100.0 * d.area_beyond_narrow,
        d.points_beyond_narrow,
    )
}

fn yes_no(b: bool) -> String {
    if b { "yes" } else { "no" }.to_string()
}
