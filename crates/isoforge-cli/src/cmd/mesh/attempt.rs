//! One run of the mesher at one depth, into the output's temporary file: checked (closed,
//! manifold) as it is written and, when `--max-depth` asks, measured against the model
//! (`isoforge_mesh::DeviationSink`). Whether the file is then put in place is the
//! caller's choice (`mesh.rs`): a mesh that misses the tolerance is dropped for a finer one.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context as _, Result, bail};
use isoforge_field::ClippedField;
use isoforge_mesh::io::MeshWriter;
use isoforge_mesh::{
    Deviation, DeviationSink, Estimate, MeshError, MeshFormat, MeshNotes, MeshSettings,
    StreamCheck, StreamReport,
};
use isoforge_output::{Options, OutputFile};

use crate::common::{Global, LoadedModel, progress_bar};

/// A mesh written to its temporary file, not yet in place.
pub(super) struct Attempt {
    /// The settings it was made with.
    pub settings: MeshSettings,
    /// The memory estimate it was checked against.
    pub estimate: Estimate,
    /// What the stages noticed.
    pub notes: Arc<MeshNotes>,
    /// Counts, volume, closed and manifold.
    pub report: StreamReport,
    /// The distance from the model's surface, when measured.
    pub deviation: Option<Deviation>,
    /// The written file, to commit or drop.
    pub file: OutputFile,
}

/// How an attempt ended.
pub(super) enum Tried {
    /// The mesh is written (to commit or drop).
    Made(Box<Attempt>),
    /// A measured point missed the tolerance and the attempt was stopped there, as asked:
    /// the temporary file is gone.
    Stopped {
        /// The distance of what was measured before the stop (`max` is the miss).
        deviation: Deviation,
        /// Triangles written before the stop.
        triangles: u64,
    },
}

/// What stays the same from one depth to the next.
pub(super) struct Job<'a> {
    /// The model's file.
    pub model_path: &'a Path,
    /// The model, loaded.
    pub loaded: &'a LoadedModel,
    /// The output's format.
    pub format: MeshFormat,
    /// The output file.
    pub output: &'a Path,
    /// Whether each mesh is measured against the model.
    pub measure: bool,
}

/// Meshes the job's model with `settings` into a new temporary file for its output,
/// measured against the model when the job says so. `estimate` is the memory estimate the
/// caller checked. With `stop_on_miss` (and measuring), the mesher stops at the first
/// point measured beyond the tolerance: a caller that drops such a mesh for a finer one
/// saves the rest of the meshing and measuring.
pub(super) fn attempt(
    job: &Job,
    settings: MeshSettings,
    estimate: Estimate,
    global: &Global,
    stop_on_miss: bool,
) -> Result<Tried> {
    let Job {
        model_path,
        loaded,
        format,
        output,
        measure,
    } = *job;
    // Before the work: a model given as its own output, a missing folder or a read-only
    // file is refused now, not after minutes of meshing.
    let out = OutputFile::prepare(output, Options::with_inputs(&[model_path]))?;
    let mut settings = settings;
    let notes = Arc::new(MeshNotes::default());
    settings.notes = Some(notes.clone());
    let bar = progress_bar(
        global,
        1000,
        &format!("meshing at depth {}", settings.depth),
    );
    let bar_cb = bar.clone();
    settings.progress = Some(Arc::new(move |f: f64| {
        bar_cb.set_position((f.clamp(0.0, 1.0) * 1000.0) as u64)
    }));
    let bounds = settings.bounds;
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
    let written = if measure {
        let field = ClippedField::new(&loaded.model.shape, bounds);
        let mut measured = DeviationSink::new(writer, &field, settings.effective_tolerance());
        // The sink's miss is the mesher's cancel flag: both stop.
        let missed = Arc::new(AtomicBool::new(false));
        if stop_on_miss {
            settings.cancel = Some(missed.clone());
            measured = measured.stop_on_miss(missed.clone());
        }
        let mut sink = StreamCheck::new(measured, centre);
        let ran = run(loaded, &settings, &mut sink, output);
        if missed.load(Ordering::Relaxed) {
            bar.finish_and_clear();
            let (report, measured) = sink.finish();
            // (The writer goes with its temporary file.)
            let (deviation, _) = measured.finish();
            return Ok(Tried::Stopped {
                deviation,
                triangles: report.tally.triangles,
            });
        }
        ran?;
        let (report, measured) = sink.finish();
        let (deviation, writer) = measured.finish();
        (report, Some(deviation), writer)
    } else {
        let mut sink = StreamCheck::new(writer, centre);
        run(loaded, &settings, &mut sink, output)?;
        let (report, writer) = sink.finish();
        (report, None, writer)
    };
    bar.finish_and_clear();
    let (report, deviation, writer) = written;
    if report.tally.triangles == 0 {
        bail!(
            "{}: nothing is inside the region {:?} to {:?} at depth {} (the field is not \
             negative at any lattice corner; parts thinner than a cell need a finer --depth)",
            model_path.display(),
            bounds.min,
            bounds.max,
            settings.depth
        );
    }
    let file = writer
        .finish()
        .and_then(|buf| buf.into_inner().map_err(|e| e.into_error()))
        .with_context(|| format!("{}: cannot write the mesh", output.display()))?;
    Ok(Tried::Made(Box::new(Attempt {
        settings,
        estimate,
        notes,
        report,
        deviation,
        file,
    })))
}

/// The mesher into `sink`, its write errors named by the output file.
fn run(
    loaded: &LoadedModel,
    settings: &MeshSettings,
    sink: &mut (dyn isoforge_mesh::MeshSink + Send),
    output: &Path,
) -> Result<()> {
    match isoforge_mesh::mesh_shape_into(&loaded.model.shape, settings, sink) {
        Ok(()) => Ok(()),
        Err(MeshError::Write(e)) => {
            Err(e).with_context(|| format!("{}: cannot write the mesh", output.display()))
        }
        Err(e) => Err(e.into()),
    }
}
