//! `isoforge slice`: a model script or a mesh file to G-code, an SL1 or SVX archive, or a
//! folder of layer PNGs.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Result, bail};
use clap::{ArgGroup, Args};
use isoforge_mesh::Mesh;
use isoforge_slice::{
    Control, GridSpec, Origin, Profile, ProfileError, ProfileErrorKind, SliceError, Source,
    Technology, check, preview, render_layers_from, sl1, slice_plate, svx,
};

use isoforge_output::{Options, OutputFile, OutputFolder};

use crate::common::{Global, ModelArgs, print_json, progress_bar, usage};

/// Arguments of `isoforge slice`.
#[derive(Args, Debug)]
#[command(group(ArgGroup::new("destination").required(true).args(["output", "sl1", "svx", "png_dir"])))]
pub struct SliceArgs {
    /// The models: scripts (.rhai, .vm) or meshes (.stl, .3mf, .obj, .ply). Several models
    /// (G-code only) are arranged on the bed side by side.
    #[arg(required = true, num_args = 1.., value_name = "MODEL")]
    pub models: Vec<PathBuf>,
    /// Set a script parameter: NAME=VALUE (repeatable; applies to every script).
    #[arg(long = "param", value_name = "NAME=VALUE")]
    pub params: Vec<String>,
    /// The region: X0,Y0,Z0,X1,Y1,Z1 (overrides each script's bounds).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Stop a script that runs longer than this (wall-clock seconds).
    #[arg(long, value_name = "SECONDS", default_value_t = isoforge_script::DEFAULT_MAX_SECONDS)]
    pub script_timeout: f64,
    /// Stop a script that makes isoforge grow by more than this (MiB; Linux).
    #[arg(long, value_name = "MIB", default_value_t = isoforge_script::DEFAULT_MAX_MEMORY_BYTES >> 20)]
    pub script_memory: u64,
    /// Printer profile (TOML); defaults to a generic 220 x 220 Marlin printer for G-code and
    /// an SL1 for images (fixtures/printers/ holds examples).
    #[arg(long, value_name = "FILE")]
    pub profile: Option<PathBuf>,
    /// Override one profile key, e.g. --set layer_height=0.1 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Write G-code for a filament printer.
    #[arg(short = 'o', long = "output", value_name = "OUT.gcode")]
    pub output: Option<PathBuf>,
    /// Write a resin-printer (SL1) archive.
    #[arg(long, value_name = "OUT.sl1")]
    pub sl1: Option<PathBuf>,
    /// Write a voxel (SVX) archive.
    #[arg(long, value_name = "OUT.svx")]
    pub svx: Option<PathBuf>,
    /// Write the layer PNGs alone, DIR/00000.png upward.
    #[arg(long, value_name = "DIR")]
    pub png_dir: Option<PathBuf>,
    /// With -o: also draw pictures of layers into DIR (layer-00042.png), every line
    /// coloured by its feature.
    #[arg(long, value_name = "DIR", requires = "output")]
    pub preview_layers: Option<PathBuf>,
    /// The layers to draw, e.g. 0,10,42 (default: the first, quarters, the last, and the
    /// first with a bridge, overhang or support).
    #[arg(
        long,
        value_name = "N,N,...",
        value_delimiter = ',',
        requires = "preview_layers"
    )]
    pub preview_at: Vec<usize>,
}

/// Pictures are this many pixels along their longer side.
const PREVIEW_SIZE: u32 = 1000;

const MESH_EXTENSIONS: &[&str] = &["stl", "3mf", "obj", "ply"];

/// The model, loaded: a field with its region or a mesh.
enum Loaded {
    Field(isoforge_field::Shape, isoforge_field::Bounds),
    Mesh(Mesh),
}

impl Loaded {
    fn source(&self) -> Source<'_> {
        match self {
            Loaded::Field(s, b) => Source::field(s, *b),
            Loaded::Mesh(m) => Source::mesh(m),
        }
    }
}

fn load(args: &SliceArgs, model: &Path) -> Result<Loaded> {
    let ext = model
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if MESH_EXTENSIONS.contains(&ext.as_str()) {
        if args.models.len() == 1 && (!args.params.is_empty() || args.bounds.is_some()) {
            bail!(
                "{}: --param and --bounds apply to model scripts, not meshes",
                model.display()
            );
        }
        let mesh = isoforge_mesh::read_mesh(model)?;
        return Ok(Loaded::Mesh(mesh));
    }
    let m = ModelArgs {
        model: model.to_path_buf(),
        params: args.params.clone(),
        bounds: args.bounds.clone(),
        script_timeout: args.script_timeout,
        script_memory: args.script_memory,
    }
    .load()?;
    Ok(Loaded::Field(m.model.shape, m.bounds))
}

fn profile(args: &SliceArgs, resin: bool) -> Result<Profile> {
    let mut p = match &args.profile {
        Some(path) => Profile::load(path).map_err(profile_error)?,
        None if resin => Profile::default_resin(),
        None => Profile::default_fdm(),
    };
    for s in &args.set {
        p.set(s).map_err(profile_error)?;
    }
    Ok(p)
}

/// A profile error in the command line's words: an override is named as the `--set` it was,
/// any refused `--set` is a usage error, and a missing key says how to give it.
fn profile_error(e: ProfileError) -> anyhow::Error {
    let from_set = matches!(e.origin, Some(Origin::Override { .. }));
    let text = match (&e.origin, &e.kind) {
        (Some(Origin::Override { assignment }), kind) => format!("--set {assignment}: {kind}"),
        (_, ProfileErrorKind::Missing { spec }) => {
            format!("{e}, or give it with --set {}=VALUE", spec.key)
        }
        (_, ProfileErrorKind::WrongTechnology { wanted, .. }) => format!(
            "{e}: give one with --profile, e.g. fixtures/printers/{}",
            match wanted {
                Technology::Fdm => "generic_marlin_220.toml",
                Technology::Resin => "prusa_sl1.toml",
            }
        ),
        _ => e.to_string(),
    };
    // A `--set` is a flag value like `--depth`: out of range or malformed, it is a usage
    // error (2), as `mesh --depth 40` is; the same value in a profile file is a bad input (1).
    if from_set {
        usage(text)
    } else {
        anyhow::anyhow!(text)
    }
}

/// A slicing error, with the flag named where one gives what is missing.
fn slice_error(e: SliceError) -> anyhow::Error {
    match e {
        SliceError::Profile(p) => profile_error(p),
        SliceError::EmptyRegion { .. } => anyhow::anyhow!("{e} (--bounds sets it)"),
        other => anyhow::Error::new(other),
    }
}

/// Where the slices go, checked and ready before the work (one destination is required).
enum Destination {
    Gcode(OutputFile, Option<OutputFolder>),
    Images(Images),
}

/// Where layer images go.
enum Images {
    Sl1(OutputFile),
    Svx(OutputFile),
    PngDir(OutputFolder),
}

impl Destination {
    /// Refuses an output that is the model or the profile, a missing folder, a read-only
    /// file, or a --png-dir that is not empty, before any slicing.
    fn prepare(args: &SliceArgs) -> Result<Destination> {
        let mut inputs: Vec<&Path> = args.models.iter().map(PathBuf::as_path).collect();
        inputs.extend(args.profile.as_deref());
        let options = Options::with_inputs(&inputs);
        let file = |p: &Path| OutputFile::prepare(p, options);
        if args.output.is_none() && args.models.len() > 1 {
            return Err(usage(
                "layer images (--sl1, --svx, --png-dir) take one model; several models are \
                 arranged on the bed for G-code (-o)",
            ));
        }
        Ok(match (&args.output, &args.sl1, &args.svx, &args.png_dir) {
            (Some(out), _, _, _) => {
                let pictures = match &args.preview_layers {
                    Some(dir) => Some(OutputFolder::prepare(dir, options)?),
                    None => None,
                };
                Destination::Gcode(file(out)?, pictures)
            }
            (_, Some(out), _, _) => Destination::Images(Images::Sl1(file(out)?)),
            (_, _, Some(out), _) => Destination::Images(Images::Svx(file(out)?)),
            (_, _, _, Some(dir)) => {
                Destination::Images(Images::PngDir(OutputFolder::prepare(dir, options)?))
            }
            _ => bail!(
                "no output given: use -o OUT.gcode, --sl1 OUT.sl1, --svx OUT.svx or --png-dir DIR"
            ),
        })
    }
}

/// Runs the command.
pub fn run(args: SliceArgs, global: &Global) -> Result<ExitCode> {
    let started = Instant::now();
    let resin = args.output.is_none();
    // Settings first: a bad profile is reported before any slow work.
    let p = profile(&args, resin)?;
    // The outputs first: a bad one is refused before any slow work.
    let destination = Destination::prepare(&args)?;
    let loaded = args
        .models
        .iter()
        .map(|m| load(&args, m))
        .collect::<Result<Vec<_>>>()?;
    let sources: Vec<Source> = loaded.iter().map(Loaded::source).collect();
    let source = sources[0];
    let bar = progress_bar(global, 0, "slicing");
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };

    let images_out = match destination {
        Destination::Images(images) => images,
        Destination::Gcode(file, pictures) => {
            let out = file.path().to_path_buf();
            let s = p.fdm().map_err(profile_error)?;
            // A signal ends the command (and removes the unfinished output) by itself.
            let control = Control::new(&progress);
            let job = slice_plate(&sources, &s, &control).map_err(slice_error)?;
            bar.finish_and_clear();
            file.write_with(|w| Ok::<_, anyhow::Error>(w.write_all(job.gcode.as_bytes())?))?;
            if let Some(folder) = pictures {
                write_pictures(folder, &job.gcode, &args.preview_at, s.filament_diameter)?;
            }
            let seconds = started.elapsed().as_secs_f64();
            let warnings: Vec<String> = job.warnings.iter().map(ToString::to_string).collect();
            if global.json {
                print_json(&serde_json::json!({
                    "layers": job.stats.layers,
                    "seconds": seconds,
                    "filament_mm": job.stats.filament_mm,
                    "filament_g": job.stats.filament_g,
                    "estimated_print_seconds": job.stats.seconds,
                    "retractions": job.stats.retractions,
                    "warnings": warnings,
                }));
            } else if !global.quiet {
                for w in &warnings {
                    eprintln!("warning: {w}");
                }
                eprintln!(
                    "{}: {} layers, {:.2} m of filament ({:.1} g), about {:.0} min to print; sliced in {:.2} s",
                    out.display(),
                    job.stats.layers,
                    job.stats.filament_mm / 1000.0,
                    job.stats.filament_g,
                    job.stats.seconds / 60.0,
                    seconds
                );
            }
            return Ok(ExitCode::SUCCESS);
        }
    };

    let r = p.resin().map_err(profile_error)?;
    // Voxels are cubes: an SVX's first layer is as thick as the others.
    let voxels = matches!(images_out, Images::Svx(_));
    let first = if voxels {
        r.layer_height
    } else {
        r.first_layer_height
    };
    let spec = if voxels {
        GridSpec::Fit {
            pixel: r.layer_height,
        }
    } else {
        GridSpec::Display {
            width: r.resolution[0],
            height: r.resolution[1],
            pixel: r.pixel_size,
            frame: r.frame(),
        }
    };
    let images =
        render_layers_from(&source, first, r.layer_height, spec, &progress).map_err(slice_error)?;
    bar.finish_and_clear();
    let height = images.layers.last().map_or(0.0, |l| l.top);
    if height > r.max_height {
        bail!(
            "the model is {height:.1} mm tall, more than the printer's {:.0} mm max_height: scale it down",
            r.max_height
        );
    }
    let written: PathBuf = match images_out {
        Images::Sl1(file) => {
            let out = file.path().to_path_buf();
            let job = job_name(&out);
            let thumb = sl1::thumbnail(
                &images.silhouette,
                images.silhouette_size.0,
                images.silhouette_size.1,
                sl1::THUMBNAIL,
            )?;
            file.write_with(|w| {
                let mut buf = std::io::Cursor::new(Vec::new());
                sl1::write_sl1(&mut buf, &images, &r, &job, &thumb)?;
                w.write_all(buf.get_ref())?;
                Ok::<_, anyhow::Error>(())
            })?;
            out
        }
        Images::Svx(file) => {
            let out = file.path().to_path_buf();
            let g = images.grid;
            let origin = [
                g.origin[0],
                g.origin[1],
                images
                    .layers
                    .first()
                    .map_or(0.0, |l| l.model_z - l.height * 0.5),
            ];
            file.write_with(|w| {
                let mut buf = std::io::Cursor::new(Vec::new());
                svx::write_svx(&mut buf, &images, r.layer_height, origin)?;
                w.write_all(buf.get_ref())?;
                Ok::<_, anyhow::Error>(())
            })?;
            out
        }
        Images::PngDir(mut folder) => {
            let dir = folder.path().to_path_buf();
            for (k, png) in images.pngs.iter().enumerate() {
                folder.write(&format!("{k:05}.png"), png)?;
            }
            folder.commit()?;
            dir
        }
    };
    let seconds = started.elapsed().as_secs_f64();
    if global.json {
        print_json(&serde_json::json!({"layers": images.layers.len(), "seconds": seconds}));
    } else if !global.quiet {
        eprintln!(
            "{}: {} layers of {} x {} pixels; sliced in {:.2} s",
            written.display(),
            images.layers.len(),
            images.image_size()[0],
            images.image_size()[1],
            seconds
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Draws the chosen layers of the G-code just written.
fn write_pictures(
    mut folder: OutputFolder,
    gcode: &str,
    at: &[usize],
    filament: f64,
) -> Result<()> {
    let report = check::parse(gcode)?;
    let layers = if at.is_empty() {
        preview::default_layers(&report)
    } else {
        at.to_vec()
    };
    let view = preview::View::fit(&report, PREVIEW_SIZE);
    for l in layers {
        if l >= report.layers.len() {
            return Err(usage(format!(
                "--preview-at {l}: the print has {} layers (0 to {})",
                report.layers.len(),
                report.layers.len().saturating_sub(1)
            )));
        }
        let png = preview::draw_layer(&report, l, &view, filament)?;
        folder.write(&format!("layer-{l:05}.png"), &png)?;
    }
    folder.commit()?;
    Ok(())
}

/// The job name SL1 uses for its folder and image names: the output's file stem, kept to
/// characters every printer firmware accepts.
fn job_name(out: &Path) -> String {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("job");
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if clean.is_empty() {
        "job".into()
    } else {
        clean
    }
}
