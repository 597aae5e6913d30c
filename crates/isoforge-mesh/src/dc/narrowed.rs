//! The field narrowed to the box around each point the late stages ask about.
//!
//! The edge collapses (`decimate.rs`) and the refiner (`refine.rs`) evaluate the field at
//! points of the mesh, one at a time. On the whole tape, a model of many parts pays for
//! every part at every point: the refiner's gradients cost spheres_chain at depth 9 three
//! times the mesher's own time, and the collapses on drilled_import evaluated both copies
//! of its imported mesh everywhere. So the region is cut into boxes of [`BOX_CELLS`]
//! finest cells, and each box gets the tape narrowed by intervals over it (plus a cell's
//! margin), kept while the stream is near. Inside its box the narrowed tape gives the same
//! values and gradients as the whole one: only choices the intervals settled are dropped.

use std::collections::HashMap;

use glam::DVec3;
use isoforge_field::Interval;

use super::sampler::Sampler;

/// The side of the boxes the field is narrowed on, in finest cells: a block's.
const BOX_CELLS: f64 = 16.0;

/// Narrowed fields kept at most (the stream goes slab by slab, so the last slab's boxes
/// are what is needed).
const BOXES_KEPT: usize = 4096;

/// The field over the whole region and its narrowings to the boxes asked about lately.
pub struct Narrowed<S: Sampler> {
    root: S::Local,
    /// The side of a box.
    size: f64,
    /// The margin each box is grown by before narrowing.
    margin: f64,
    boxes: HashMap<[i64; 3], S::Local>,
}

impl<S: Sampler> Narrowed<S> {
    /// Boxes of [`BOX_CELLS`] cells of side `cell`.
    pub fn new(sampler: &S, cell: f64) -> Self {
        Narrowed {
            root: sampler.root(),
            size: BOX_CELLS * cell,
            margin: cell,
            boxes: HashMap::new(),
        }
    }

    /// The field narrowed to the box around `p`; `None` off the lattice's numbers (a NaN or
    /// far-off point).
    pub fn around(&mut self, sampler: &S, ev: &mut S::Evals, p: DVec3) -> Option<&S::Local> {
        let key = (p / self.size).floor();
        if !key.is_finite() || key.abs().max_element() > 1e15 {
            return None;
        }
        let key = key.as_i64vec3().to_array();
        if !self.boxes.contains_key(&key) {
            let b = [0, 1, 2].map(|i| {
                let lo = key[i] as f64 * self.size - self.margin;
                Interval::try_from((lo, lo + self.size + 2.0 * self.margin))
                    .unwrap_or(Interval::ENTIRE)
            });
            let _ = sampler.interval(ev, &self.root, b);
            let local = sampler.narrow(ev, &self.root);
            if self.boxes.len() >= BOXES_KEPT {
                self.boxes.clear();
            }
            self.boxes.insert(key, local);
        }
        self.boxes.get(&key)
    }

    /// F and its gradient at `p` (`[F, dF/dx, dF/dy, dF/dz]`), on the box's narrowed tape,
    /// or the whole one where `p` has no box.
    pub fn grad(&mut self, sampler: &S, ev: &mut S::Evals, p: DVec3) -> [f64; 4] {
        let at = p.to_array();
        if let Some(local) = self.around(sampler, ev, p) {
            return sampler.grad(ev, local, at);
        }
        sampler.grad(ev, &self.root, at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dc::sampler::TapeSampler;
    use isoforge_field::{Bounds, ClippedField, Shape};

    /// Eight unit balls in a row, 3 apart: a box around one ball needs one ball's tape.
    fn row_of_balls() -> TapeSampler {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = |c: f64| ((&x - c).square() + y.square() + z.square()).sqrt() - 1.0;
        let row = (1..8).fold(ball(0.0), |s, k| s.min(&ball(3.0 * f64::from(k))));
        let region = Bounds::new([-1.5, -1.5, -1.5], [22.5, 1.5, 1.5]).unwrap();
        TapeSampler::new(ClippedField::new(&row, region))
    }

    #[test]
    fn a_box_gets_a_shorter_tape_with_the_same_values() {
        let sampler = row_of_balls();
        let mut ev = sampler.evals();
        let cell = 24.0 / 256.0;
        let mut field = Narrowed::new(&sampler, cell);
        let whole = sampler.root();
        let p = DVec3::new(9.3, 0.4, -0.7);
        let local = field.around(&sampler, &mut ev, p).unwrap().clone();
        // The fault would be a box that keeps every ball (no time saved) ...
        assert!(
            local.tape().len() * 3 < whole.tape().len(),
            "{} of {}",
            local.tape().len(),
            whole.tape().len()
        );
        // ... or one that dropped a ball that matters: values and gradients are the
        // whole tape's, to the bit, all over the box.
        let size = BOX_CELLS * cell;
        let corner = (p / size).floor() * size;
        for i in 0..=8 {
            for j in 0..=8 {
                for k in 0..=8 {
                    let q = corner + DVec3::new(i as f64, j as f64, k as f64) * (size / 8.0);
                    let q = q.min(corner + DVec3::splat(size * 0.999_999));
                    let narrowed = field.grad(&sampler, &mut ev, q);
                    let full = sampler.grad(&mut ev, &whole, q.to_array());
                    assert_eq!(narrowed.map(f64::to_bits), full.map(f64::to_bits), "at {q}");
                }
            }
        }
    }

    #[test]
    fn a_point_off_the_numbers_has_no_box_and_reads_the_whole_tape() {
        let sampler = row_of_balls();
        let mut ev = sampler.evals();
        let mut field = Narrowed::new(&sampler, 0.1);
        let nan = DVec3::new(f64::NAN, 0.0, 0.0);
        assert!(field.around(&sampler, &mut ev, nan).is_none());
        let g = field.grad(&sampler, &mut ev, nan);
        let full = sampler.grad(&mut ev, &sampler.root(), nan.to_array());
        assert_eq!(g.map(f64::to_bits), full.map(f64::to_bits));
    }
}
