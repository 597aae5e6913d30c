//! The places the mesher's splits left off the surface, measured: a plain run's word on
//! whether, and where, the mesh misses the tolerance, at the cost of a few thousand points
//! at most (measuring the whole mesh, as `--max-depth` does, costs about a second meshing).
//!
//! The splits onto the surface (`isoforge_mesh`'s refiner) leave an edge whole, its middle
//! off the surface, where every split would fold the mesh (a part or a groove narrower than
//! a cell or two, a sharp wedge): those middles are the places collected
//! ([`isoforge_mesh::MeshNotes::left_off`]). Each is a point of the mesh; measured the way
//! `check --against` measures the mesh's sample points, one farther than the tolerance is a
//! place where the mesh misses it. The places do not cover everything `check` samples, so
//! none beyond says nothing for sure: `check --against` is the measure.

use std::sync::atomic::Ordering;

use isoforge_field::ClippedField;
use isoforge_mesh::{MeshNotes, MeshSettings, distances_beyond};
use serde_json::{Value, json};

use crate::common::LoadedModel;

/// The measured places.
#[derive(Clone, Copy, Debug)]
pub(in crate::cmd) struct LeftOff {
    /// Places found, each once.
    pub places: u64,
    /// Of them, those kept and measured (all, unless there were more than the mesher
    /// keeps).
    pub measured: usize,
    /// Of those measured, how many are farther from the surface than the tolerance.
    pub beyond: usize,
    /// The farthest one's distance, and where it is.
    pub max: f64,
    pub at: [f64; 3],
}

impl LeftOff {
    /// Measures the places the mesher noted against the model.
    pub fn measure(loaded: &LoadedModel, settings: &MeshSettings, notes: &MeshNotes) -> LeftOff {
        let points = notes
            .left_off
            .lock()
            .map(|kept| kept.clone())
            .unwrap_or_default();
        let tolerance = settings.effective_tolerance();
        let field = ClippedField::new(&loaded.model.shape, settings.bounds);
        let distances = if points.is_empty() {
            Vec::new()
        } else {
            distances_beyond(&field, &points, tolerance)
        };
        let mut out = LeftOff {
            places: notes.left_off_found.load(Ordering::Relaxed),
            measured: points.len(),
            beyond: 0,
            max: 0.0,
            at: [0.0; 3],
        };
        for (p, &d) in points.iter().zip(&distances) {
            // Infinite: no surface found near a point the field says nothing useful at.
            if !d.is_finite() {
                continue;
            }
            if d > tolerance {
                out.beyond += 1;
            }
            if d > out.max {
                out.max = d;
                out.at = *p;
            }
        }
        out
    }

    /// For `--json`.
    pub fn to_json(self) -> Value {
        json!({
            "places": self.places,
            "measured": self.measured,
            "beyond_tolerance": self.beyond,
            "max_distance": self.max,
            "max_distance_at": self.at,
        })
    }

    /// The note for a mesh at `depth` with `tolerance`, when a place misses it.
    pub fn note(&self, tolerance: f64, depth: u8) -> Option<String> {
        (self.beyond > 0).then(|| {
            format!(
                "the mesh misses the tolerance ({tolerance:.3e} mm): it is {:.3e} mm from the \
                 surface at {}, the farthest of {} place{} beyond it that the splits onto the \
                 surface had to leave (a split there would fold the mesh: the surface bends or \
                 narrows within a cell or two); `isoforge check MESH --against MODEL` measures \
                 the whole mesh, and --max-depth {} or deeper meshes finer until the tolerance \
                 holds",
                self.max,
                super::point(self.at),
                self.beyond,
                if self.beyond == 1 { "" } else { "s" },
                (depth + 2).min(isoforge_mesh::MAX_DEPTH)
            )
        })
    }
}
