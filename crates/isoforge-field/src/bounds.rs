//! Axis-aligned boxes: a model's region, and the box's own distance-like field (what
//! [`crate::ClippedField`] combines with a model so that outside the box is outside).

/// An axis-aligned box, `min` to `max` in millimetres.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Bounds {
    /// The lowest corner.
    pub min: [f64; 3],
    /// The highest corner.
    pub max: [f64; 3],
}

impl Bounds {
    /// A box from two corners; `None` unless every `min < max` and all are finite.
    pub fn new(min: [f64; 3], max: [f64; 3]) -> Option<Self> {
        let ok = (0..3).all(|i| min[i].is_finite() && max[i].is_finite() && min[i] < max[i]);
        ok.then_some(Bounds { min, max })
    }
    /// The side lengths.
    pub fn size(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| self.max[i] - self.min[i])
    }
    /// The longest side.
    pub fn longest_side(&self) -> f64 {
        let s = self.size();
        s[0].max(s[1]).max(s[2])
    }
    /// The box as three intervals.
    pub fn intervals(&self) -> [inari::Interval; 3] {
        [0, 1, 2].map(|i| {
            inari::Interval::try_from((self.min[i], self.max[i])).unwrap_or(inari::Interval::ENTIRE)
        })
    }

    /// The box as a field: `max` over the axes of `(min - p, p - max)`. Negative inside,
    /// zero on the faces, positive outside; its gradient is the normal of the nearest face
    /// ([`Bounds::face_normal`]).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        let mut d = f64::NEG_INFINITY;
        for (i, &c) in p.iter().enumerate() {
            d = d.max(self.min[i] - c).max(c - self.max[i]);
        }
        d
    }

    /// The lowest and highest [`Bounds::distance`] over a box of intervals.
    pub fn distance_range(&self, b: [inari::Interval; 3]) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for (i, iv) in b.iter().enumerate() {
            // min - p over [inf, sup] is [min - sup, min - inf]; p - max likewise.
            lo = lo.max(self.min[i] - iv.sup()).max(iv.inf() - self.max[i]);
            hi = hi.max(self.min[i] - iv.inf()).max(iv.sup() - self.max[i]);
        }
        (lo, hi)
    }

    /// The outward unit normal of the face [`Bounds::distance`] measures to at `p` (the
    /// first axis wins a tie, so an edge or corner still gets one face's normal).
    pub fn face_normal(&self, p: [f64; 3]) -> [f64; 3] {
        let mut best = (f64::NEG_INFINITY, 0, 0.0);
        for (i, &c) in p.iter().enumerate() {
            let lo = self.min[i] - c;
            let hi = c - self.max[i];
            if lo > best.0 {
                best = (lo, i, -1.0);
            }
            if hi > best.0 {
                best = (hi, i, 1.0);
            }
        }
        let mut n = [0.0; 3];
        n[best.1] = best.2;
        n
    }
}
