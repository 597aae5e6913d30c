//! A texture from samples: a height array or a grayscale image, interpolated bilinearly
//! and repeating, as a custom node read at tile coordinates (u, v).
//!
//! Sample (row i, column j) sits at the centre of its texel: u = (j + ½)/cols,
//! v = 1 − (i + ½)/rows, so row 0 is at the top of the tile. Its interval callback takes
//! the smallest and largest sample among the texels a box of (u, v) covers: a bilinear
//! blend never leaves the range of its four samples.

use std::sync::Arc;

use isoforge_field::{CustomField, Interval, Shape};

use super::TextureError;
use crate::bound::{plane_box, widened};

/// The most samples a height field may have (a 4096 × 4096 image).
pub const MAX_SAMPLES: usize = 1 << 24;

/// Texels scanned for one interval before the whole field's range is used instead.
const SCAN_LIMIT: usize = 4096;

/// Heights in 0..1 on a grid.
#[derive(Debug)]
pub struct HeightField {
    cols: usize,
    rows: usize,
    values: Vec<f64>,
    lo: f64,
    hi: f64,
}

impl HeightField {
    /// A field from rows of heights (all rows the same length, each value in 0..1).
    pub fn new(rows: Vec<Vec<f64>>) -> Result<HeightField, TextureError> {
        let bad = |m: String| TextureError::BadHeights(m);
        let r = rows.len();
        let c = rows.first().map_or(0, Vec::len);
        if r == 0 || c == 0 {
            return Err(bad(
                "a height texture needs at least one row and one column".into(),
            ));
        }
        if r.saturating_mul(c) > MAX_SAMPLES {
            return Err(bad(format!(
                "a height texture may have at most {MAX_SAMPLES} samples, this one has {r} x {c}"
            )));
        }
        let mut values = Vec::with_capacity(r * c);
        for (i, row) in rows.iter().enumerate() {
            if row.len() != c {
                return Err(bad(format!(
                    "row {i} of the height texture has {} values, row 0 has {c}; every row needs the same length",
                    row.len()
                )));
            }
            for (j, &v) in row.iter().enumerate() {
                if !(0.0..=1.0).contains(&v) {
                    return Err(bad(format!(
                        "height [{i}][{j}] is {v}; heights must be between 0 and 1"
                    )));
                }
                values.push(v);
            }
        }
        let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Ok(HeightField {
            cols: c,
            rows: r,
            values,
            lo,
            hi,
        })
    }

    /// Columns.
    pub fn cols(&self) -> usize {
        self.cols
    }
    /// Rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    fn sample(&self, i: i64, j: i64) -> f64 {
        let i = i.rem_euclid(self.rows as i64) as usize;
        let j = j.rem_euclid(self.cols as i64) as usize;
        self.values[i * self.cols + j]
    }

    /// Grid coordinates (column, row) of tile coordinates (u, v).
    fn grid(&self, u: f64, v: f64) -> (f64, f64) {
        (
            u * self.cols as f64 - 0.5,
            (1.0 - v) * self.rows as f64 - 0.5,
        )
    }

    fn value_and_slope(&self, u: f64, v: f64) -> (f64, f64, f64) {
        if !u.is_finite() || !v.is_finite() {
            return (f64::NAN, 0.0, 0.0);
        }
        let (x, y) = self.grid(u.rem_euclid(1.0), v.rem_euclid(1.0));
        let (j, i) = (x.floor(), y.floor());
        let (fx, fy) = (x - j, y - i);
        let (i, j) = (i as i64, j as i64);
        let (a, b) = (self.sample(i, j), self.sample(i, j + 1));
        let (c, d) = (self.sample(i + 1, j), self.sample(i + 1, j + 1));
        let top = a + (b - a) * fx;
        let bottom = c + (d - c) * fx;
        let value = top + (bottom - top) * fy;
        let dx = (b - a) + ((d - c) - (b - a)) * fy;
        let dy = bottom - top;
        // x grows with u at `cols` per tile; y falls as v grows at `rows` per tile.
        (value, dx * self.cols as f64, -dy * self.rows as f64)
    }

    /// The texture read at (u, v).
    pub fn at(self: &Arc<Self>, u: &Shape, v: &Shape) -> Shape {
        Shape::custom(self.clone()).remap(u, v, &Shape::constant(0.0))
    }
}

impl CustomField for HeightField {
    fn name(&self) -> &str {
        "height_texture"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.value_and_slope(p[0], p[1]).0
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        let whole = widened(self.lo, self.hi);
        let Some((c, h)) = plane_box(b) else {
            return whole;
        };
        if 2.0 * h.x >= 1.0 || 2.0 * h.y >= 1.0 {
            return whole;
        }
        let (x0, y1) = self.grid(c.x - h.x, c.y - h.y);
        let (x1, y0) = self.grid(c.x + h.x, c.y + h.y);
        let (j0, j1) = (x0.floor() as i64, x1.floor() as i64 + 1);
        let (i0, i1) = (y0.floor() as i64, y1.floor() as i64 + 1);
        let count = ((j1 - j0 + 1) * (i1 - i0 + 1)) as usize;
        if count > SCAN_LIMIT {
            return whole;
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in i0..=i1 {
            for j in j0..=j1 {
                let s = self.sample(i, j);
                lo = lo.min(s);
                hi = hi.max(s);
            }
        }
        widened(lo, hi)
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let (v, du, dv) = self.value_and_slope(p[0], p[1]);
        [v, du, dv, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::at;

    fn iv(a: f64, b: f64) -> Interval {
        Interval::try_from((a, b)).unwrap()
    }

    #[test]
    fn samples_sit_at_texel_centres_row_zero_on_top() {
        let f = Arc::new(HeightField::new(vec![vec![1.0, 0.0], vec![0.0, 0.0]]).unwrap());
        let s = f.at(&Shape::x(), &Shape::y());
        // Row 0, column 0: u = 0.25, v = 0.75.
        assert!((at(&s, [0.25, 0.75, 0.0]) - 1.0).abs() < 1e-12);
        assert!(at(&s, [0.75, 0.25, 0.0]).abs() < 1e-12);
        // Halfway between two samples, and across the wrap.
        assert!((at(&s, [0.5, 0.75, 0.0]) - 0.5).abs() < 1e-12);
        assert!((at(&s, [0.0, 0.75, 0.0]) - 0.5).abs() < 1e-12);
        assert!((at(&s, [1.25, -0.25, 0.0]) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn intervals_enclose_and_prune() {
        let rows: Vec<Vec<f64>> = (0..16)
            .map(|i| {
                (0..16)
                    .map(|j| ((i * 7 + j * 3) % 11) as f64 / 10.0)
                    .collect()
            })
            .collect();
        let f = HeightField::new(rows).unwrap();
        for k in 0..200 {
            let (u, v) = (
                (k as f64 * 0.137) % 3.0 - 1.0,
                (k as f64 * 0.291) % 3.0 - 1.0,
            );
            let w = 0.01 + (k % 7) as f64 * 0.03;
            let e = f.interval([iv(u, u + w), iv(v, v + w), iv(0.0, 0.0)]);
            for a in 0..=5 {
                for b in 0..=5 {
                    let val = f.value([u + w * a as f64 / 5.0, v + w * b as f64 / 5.0, 0.0]);
                    assert!(e.inf() <= val && val <= e.sup());
                }
            }
        }
        let flat = HeightField::new(vec![vec![0.5; 4]; 4]).unwrap();
        let e = flat.interval([iv(0.1, 0.2), iv(0.1, 0.2), iv(0.0, 0.0)]);
        assert!(e.sup() - e.inf() < 1e-6);
    }

    #[test]
    fn bad_arrays_are_refused() {
        assert!(HeightField::new(vec![]).is_err());
        assert!(HeightField::new(vec![vec![0.0, 1.0], vec![0.5]]).is_err());
        assert!(HeightField::new(vec![vec![1.5]]).is_err());
    }
}
