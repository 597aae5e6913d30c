//! The places the mesher's splits left off the surface, measured: a plain run's word on
//! whether, and where, the mesh misses the tolerance, at the cost of a few thousand points
//! at most (measuring the whole mesh, as `--max-depth` does, costs about a second meshing).
//!
//! The splits onto the surface (`isoforge_mesh`'s refiner) leave an edge whole, its middle
//! off the surface, where every split would fold the mesh (a part or a groove narrower than
//! a cell or two, a sharp wedge): those middles are the places collected
//! ([`isoforge_mesh::MeshNotes::left_off`]). Each is a point of the mesh; measured the way
//! `check --against` measures the mesh's sample points, one farther than the tolerance is a
//! place where the mesh misses it by that measure (whose distances are those of a point of
//! the surface found, searched around for a nearer one: a surface smaller than the search's
//! steps can go unseen). The places do not cover everything `check` samples, so none beyond
//! says nothing for sure: `check --against` measures the whole mesh.

use std::sync::atomic::Ordering;

use isoforge_field::ClippedField;
use isoforge_mesh::{MeshNotes, MeshSettings, farthest};
use serde_json::{Value, json};

use crate::common::LoadedModel;

/// The measured places.
#[derive(Clone, Debug)]
pub(in crate::cmd) struct LeftOff {
    /// Places found, each once.
    pub places: u64,
    /// Of them, those kept and measured (all, unless there were more than the mesher
    /// keeps).
    pub measured: usize,
    /// The farthest one's distance from the surface (0 with none), where it is, and the
    /// tolerance.
    pub max: f64,
    pub at: [f64; 3],
    pub tolerance: f64,
    /// The places themselves, for a finer round to start from (`finer.rs`).
    pub points: Vec<[f64; 3]>,
}

impl LeftOff {
    /// Measures the places the mesher noted against the model (taking them from the
    /// notes). Only the farthest is
    /// searched around to be sure of its distance (a mesh with tens of thousands of places
    /// beyond the tolerance, a shell thinner than the lattice, would otherwise take longer
    /// to measure than to mesh).
    pub fn measure(loaded: &LoadedModel, settings: &MeshSettings, notes: &MeshNotes) -> LeftOff {
        let points = notes
            .left_off
            .lock()
            .map(|mut kept| std::mem::take(&mut *kept))
            .unwrap_or_default();
        let field = ClippedField::new(&loaded.model.shape, settings.bounds);
        let (max, at) = farthest(&field, &points).unwrap_or((0.0, [0.0; 3]));
        LeftOff {
            places: notes.left_off_found.load(Ordering::Relaxed),
            measured: points.len(),
            max,
            at,
            tolerance: settings.effective_tolerance(),
            points,
        }
    }

    /// Whether a place is farther from the surface than the tolerance: the mesh misses it.
    pub fn missed(&self) -> bool {
        self.max > self.tolerance
    }

    /// For `--json`.
    pub fn to_json(&self) -> Value {
        json!({
            "places": self.places,
            "measured": self.measured,
            "max_distance": self.max,
            "max_distance_at": self.at,
            "tolerance_missed": self.missed(),
        })
    }

    /// The note for a mesh at `depth`, when a place misses the tolerance.
    pub fn note(&self, depth: u8) -> Option<String> {
        self.missed().then(|| {
            format!(
                "the mesh misses the tolerance ({:.3e} mm): by `check --against`'s measure it \
                 is {:.3e} mm from the surface at {}, the farthest of {} place{} where the \
                 splits onto the surface had to stop (a split there would fold the mesh: the \
                 surface bends or narrows within a cell or two); `isoforge check MESH \
                 --against MODEL` measures the whole mesh, and --max-depth {} or deeper \
                 samples it finer where it misses until the tolerance holds (as a run given \
                 no --depth or --resolution does)",
                self.tolerance,
                self.max,
                super::point(self.at),
                self.places,
                if self.places == 1 { "" } else { "s" },
                (depth + 2).min(isoforge_mesh::MAX_DEPTH)
            )
        })
    }
}
