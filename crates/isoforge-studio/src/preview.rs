//! Glue to `isoforge-mesh`: a model to a mesh at a depth, its facts, and the compact binary
//! the page's WebGL view takes without parsing (positions and indices as they lie in
//! memory). Also the rule that keeps the preview current: the newest edit wins, older jobs
//! are dropped where they stand.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use isoforge_mesh::{Mesh, MeshNotes, MeshSettings, check};
use serde::Serialize;

use crate::model::Loaded;

/// The deepest preview the page may ask for: 2^10 cells a side is already finer than a
/// browser shows, and an export goes through the same limit.
pub const MAX_PREVIEW_DEPTH: u8 = 10;

/// What the page shows beside the view.
#[derive(Debug, Clone, Serialize)]
pub struct Facts {
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// Enclosed volume, mm³.
    pub volume: f64,
    /// Surface area, mm².
    pub area: f64,
    /// The mesh's box.
    pub bounds: Option<[[f64; 3]; 2]>,
    /// Every edge has two triangles.
    pub watertight: bool,
    /// Every edge and vertex is manifold.
    pub manifold: bool,
    /// The depth meshed at.
    pub depth: u8,
    /// Triangles joining the two sides of a part thinner than about two cells at this
    /// depth (as `isoforge mesh --json` counts them): the page says a finer depth is
    /// needed when they are many.
    pub thin_triangles: u64,
    /// Seconds spent meshing.
    pub seconds: f64,
}

/// Meshes a loaded model at `depth` (2^depth cells along the region's longest side).
pub fn mesh(model: &Loaded, depth: u8) -> Result<(Mesh, Facts), isoforge_mesh::MeshError> {
    let started = Instant::now();
    let mut settings = MeshSettings::new(model.bounds, depth);
    let notes = Arc::new(MeshNotes::default());
    settings.notes = Some(notes.clone());
    let mesh = isoforge_mesh::try_mesh_shape(&model.shape, &settings)?;
    let seconds = started.elapsed().as_secs_f64();
    let report = check(&mesh);
    let facts = Facts {
        triangles: report.triangles,
        vertices: report.vertices,
        volume: report.volume,
        area: report.area,
        bounds: report.bounds,
        watertight: report.watertight,
        manifold: report.manifold,
        depth,
        thin_triangles: notes.thin_triangles.load(Ordering::Relaxed),
        seconds,
    };
    Ok((mesh, facts))
}

/// The preview as the page reads it: `ISOP`, the header's length (u32), the JSON header
/// padded with spaces to a multiple of 4, the vertex count and triangle count (u32 each),
/// then positions (f32 × 3 per vertex) and indices (u32 × 3 per triangle), little-endian,
/// so the page hands both arrays to WebGL as they are.
pub fn encode(mesh: &Mesh, header: &serde_json::Value) -> Vec<u8> {
    let mut json = header.to_string().into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out =
        Vec::with_capacity(16 + json.len() + mesh.vertices.len() * 12 + mesh.triangles.len() * 12);
    out.extend_from_slice(b"ISOP");
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(&(mesh.vertices.len() as u32).to_le_bytes());
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    for v in &mesh.vertices {
        for c in v {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// Numbers the page's preview requests; a request older than the newest one seen is stale
/// and is dropped at the next check instead of using the cores the newest one needs.
#[derive(Debug, Default)]
pub struct Jobs {
    newest: AtomicU64,
}

impl Jobs {
    /// Notes a request's number.
    pub fn arrive(&self, job: u64) {
        self.newest.fetch_max(job, Ordering::SeqCst);
    }

    /// True when a newer request has arrived since `job`.
    pub fn is_stale(&self, job: u64) -> bool {
        self.newest.load(Ordering::SeqCst) > job
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn encodes_counts_and_arrays_in_place() {
        let text = "bounds([-2,-2,-2],[2,2,2]);\nSphere(1)";
        let model = crate::model::load(Path::new("s.rhai"), text, &[]).unwrap();
        let (mesh, facts) = mesh(&model, 4).unwrap();
        assert!(facts.watertight && facts.manifold && facts.triangles > 0);
        let bytes = encode(&mesh, &serde_json::json!({"a": 1}));
        assert_eq!(&bytes[..4], b"ISOP");
        let n = u32::from_le_bytes(bytes[4..8].try_into().unwrap()) as usize;
        assert_eq!(n % 4, 0);
        let at = 8 + n;
        let nv = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        let nt = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()) as usize;
        assert_eq!((nv, nt), (mesh.vertices.len(), mesh.triangles.len()));
        assert_eq!(bytes.len(), at + 8 + nv * 12 + nt * 12);
    }

    #[test]
    fn thin_parts_are_counted_for_the_page() {
        // A gyroid sheet a third of a cell thick at depth 5, resolved at depth 7.
        let text = "bounds([-10, -10, -10], [10, 10, 10]);\n\
                    intersection(gyroid(8, 0.22), sphere(3))";
        let model = crate::model::load(Path::new("thin.rhai"), text, &[]).unwrap();
        let (_, coarse) = mesh(&model, 5).unwrap();
        assert!(
            50 * coarse.thin_triangles >= coarse.triangles as u64,
            "{coarse:?}"
        );
        let (_, fine) = mesh(&model, 7).unwrap();
        assert_eq!(fine.thin_triangles, 0, "{fine:?}");
    }

    #[test]
    fn newer_jobs_make_older_ones_stale() {
        let jobs = Jobs::default();
        jobs.arrive(3);
        assert!(!jobs.is_stale(3));
        jobs.arrive(2);
        assert!(jobs.is_stale(2));
        jobs.arrive(5);
        assert!(jobs.is_stale(3));
    }
}
