//! Axis-aligned boxes: a model's region.

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
}
