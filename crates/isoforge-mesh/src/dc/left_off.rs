//! The places the splits onto the surface left off it (`refine.rs`): points of the mesh (a
//! chord's middle, a triangle's centre, a vertex) farther from the surface than an edge
//! splits for, kept so that the caller can measure them and tell the user where the mesh
//! misses the tolerance (`MeshNotes::left_off`).
//!
//! The refiner adds them; the flips (`flips.rs`) take away those a turned edge takes off the
//! mesh (its middle and its two triangles' centres), so every place left is a point of the
//! mesh written. Each place is kept once, by its single-precision bits ([`place_key`]): an
//! edge left whole is asked about from both sides, and a centre summed in another order
//! still matches.

use std::collections::HashMap;

/// Places kept at most (about 40 bytes each): on the fixtures at depth 8 there are a few
/// thousand at most (hull_mixed 4,339 before the flips, heart_shell 2,070).
const KEPT: usize = 1 << 16;

/// A point as a key that a sum taken in another order still matches (the single-precision
/// bits of its coordinates).
pub fn place_key(p: [f64; 3]) -> [u32; 3] {
    p.map(|c| (c as f32).to_bits())
}

/// The places left off the surface so far.
#[derive(Debug, Default)]
pub struct LeftOff {
    kept: HashMap<[u32; 3], [f64; 3]>,
    /// Places found in all, each once (more than those kept past [`KEPT`]), less those
    /// taken off the mesh.
    pub found: u64,
}

impl LeftOff {
    /// Adds a place of the mesh left off the surface.
    pub fn add(&mut self, p: [f64; 3]) {
        let key = place_key(p);
        if self.kept.contains_key(&key) {
            return;
        }
        self.found += 1;
        if self.kept.len() < KEPT {
            self.kept.insert(key, p);
        }
    }

    /// Forgets a place that is no longer on the mesh, if it was one.
    pub fn gone(&mut self, p: [f64; 3]) {
        if self.kept.remove(&place_key(p)).is_some() {
            self.found -= 1;
        }
    }

    /// The places kept, in a fixed order (by their coordinates' bits).
    pub fn into_points(self) -> Vec<[f64; 3]> {
        let mut points: Vec<[f64; 3]> = self.kept.into_values().collect();
        points.sort_unstable_by_key(|p| p.map(f64::to_bits));
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_place_counts_once_and_a_place_gone_is_forgotten() {
        let mut places = LeftOff::default();
        let (a, b) = ([0.1, 0.2, 0.3], [1.0, 2.0, 3.0]);
        places.add(a);
        places.add(b);
        // The same point summed otherwise: the same place.
        places.add([0.1 + 1e-17, 0.2, 0.3]);
        assert_eq!(places.found, 2);
        places.gone(a);
        // Not a place: nothing changes.
        places.gone([5.0, 5.0, 5.0]);
        assert_eq!(places.found, 1);
        assert_eq!(places.into_points(), vec![b]);
    }
}
