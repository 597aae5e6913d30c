//! One run of the mesher, into the output's temporary file: checked (closed, manifold) as it
//! is written and, when asked, measured against the model (`isoforge_mesh::DeviationSink`),
//! the points beyond the tolerance kept. Whether the file is then put in place is the
//! caller's choice (`finer.rs`): a mesh that misses the tolerance is dropped for one refined
//! where it misses.

use std::path::Path;
use std::sync::Arc;

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
    /// When measured, the sample points beyond the tolerance (at most [`KEEP_MISSES`],
    /// the farthest first) and their distances.
    pub misses: Vec<([f64; 3], f64)>,
    /// The written file, to commit or drop.
    pub file: OutputFile,
}

/// Points beyond the tolerance kept from a measured mesh: enough to name every block that
/// misses (a few thousand on the fixtures that miss at depth 8), few enough to hold.
pub(super) const KEEP_MISSES: usize = 200_000;

/// What stays the same from one mesh of the model to the next.
pub(super) struct Job<'a> {
    /// The model's file.
    pub model_path: &'a Path,
    /// The model, loaded.
    pub loaded: &'a LoadedModel,
    /// The output's format.
    pub format: MeshFormat,
    /// The output file.
    pub output: &'a Path,
}

/// Meshes the job's model with `settings` into a new temporary file for its output, and
/// measures it against the model when `measure` says so. `estimate` is the memory estimate
/// the caller checked.
pub(super) fn attempt(
    job: &Job,
    settings: MeshSettings,
    estimate: Estimate,
    global: &Global,
    measure: bool,
) -> Result<Attempt> {
    let Job {
        model_path,
        loaded,
        format,
        output,
    } = *job;
    // Before the work: a model given as its own output, a missing folder or a read-only
    // file is refused now, not after minutes of meshing.
    let out = OutputFile::prepare(output, Options::with_inputs(&[model_path]))?;
    let mut settings = settings;
    let notes = Arc::new(MeshNotes::default());
    settings.notes = Some(notes.clone());
    let what = match &settings.refine {
        Some(r) => format!("meshing {}", super::blocks_finer(r, settings.depth)),
        None => format!("meshing at depth {}", settings.depth),
    };
    let bar = progress_bar(global, 1000, &what);
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
        let measured = DeviationSink::new(writer, &field, settings.effective_tolerance())
            .keeping_misses(KEEP_MISSES);
        let mut sink = StreamCheck::new(measured, centre);
        run(loaded, &settings, &mut sink, output)?;
        let (report, measured) = sink.finish();
        let (deviation, misses, writer) = measured.finish_with_misses();
        (report, Some(deviation), misses, writer)
    } else {
        let mut sink = StreamCheck::new(writer, centre);
        run(loaded, &settings, &mut sink, output)?;
        let (report, writer) = sink.finish();
        (report, None, Vec::new(), writer)
    };
    bar.finish_and_clear();
    let (report, deviation, misses, writer) = written;
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
    Ok(Attempt {
        settings,
        estimate,
        notes,
        report,
        deviation,
        misses,
        file,
    })
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
