//! Layer outlines straight from the field.
//!
//! The field is the model clipped to its region ([`ClippedField`]: outside the box and
//! NaN count as outside, as when meshing), so a model cut by its region is capped.
//!
//! At a layer's height a quadtree over the plane is pruned by interval evaluation: a cell
//! whose interval is all positive is empty, all negative is full, and only cells that may
//! hold the surface are split, down to the finest cell size. Each split evaluates its
//! children with the tape simplified for the parent (and the layer with the tape
//! simplified for its whole slab), so deep min/max trees shrink to the few terms that
//! matter. Marching squares runs on the finest cells; every crossing is refined on the
//! field by bisection (not interpolated), so the outline lies on the true surface to a
//! thousandth of a cell. Segments are chained through the shared grid edges into closed,
//! oriented polygons and simplified (Douglas-Peucker).

use std::collections::HashMap;

use isoforge_field::{Bounds, ClippedField, GradEval, Interval, IntervalEval, PointEval, Shape};

use crate::geom::{Contour, Point, simplify_closed};
use crate::outline::march::{EdgeKey, cell_segments, chain, edge_corners};

/// Bisection steps for an edge crossing: 2^-12 of a cell (about 0.01 µm at 0.05 mm cells).
const BISECTION_STEPS: usize = 12;

/// Slices a field into layer outlines.
#[derive(Clone)]
pub struct FieldSlicer {
    field: ClippedField,
    /// The finest quadtree cell, mm.
    cell: f64,
    /// Douglas-Peucker tolerance, mm.
    tolerance: f64,
    origin: Point,
    /// Cells along each side of the root (a power of two).
    cells: i32,
}

/// A finest cell that may hold surface, with the field simplified for it.
struct Leaf {
    i: i32,
    j: i32,
    field: ClippedField,
}

impl FieldSlicer {
    /// A slicer for `shape` over `bounds` (outside the bounds counts as outside, so a
    /// model cut by its bounds is capped), with finest cells of `cell` mm and outlines
    /// simplified within `tolerance` mm.
    pub fn new(shape: &Shape, bounds: Bounds, cell: f64, tolerance: f64) -> FieldSlicer {
        let cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            bounds.longest_side() / 512.0
        };
        let size = bounds.size();
        // One spare cell on each side keeps the grid's rim outside the bounds, so every
        // chain closes.
        let need = ((size[0].max(size[1]) / cell).ceil() as i64 + 2).clamp(1, 1 << 24);
        let cells = (need as u64).next_power_of_two() as i32;
        FieldSlicer {
            field: ClippedField::new(shape, bounds),
            cell,
            tolerance: tolerance.max(0.0),
            origin: [bounds.min[0] - cell, bounds.min[1] - cell],
            cells,
        }
    }

    /// The model clipped to its region.
    pub fn field(&self) -> &ClippedField {
        &self.field
    }

    /// The region the field is sliced over.
    pub fn bounds(&self) -> Bounds {
        *self.field.bounds()
    }

    fn corner(&self, i: i32, j: i32) -> Point {
        [
            self.origin[0] + i as f64 * self.cell,
            self.origin[1] + j as f64 * self.cell,
        ]
    }

    /// Inside: in the region and the model strictly negative; NaN counts as outside.
    fn inside(&self, ev: &mut PointEval, field: &ClippedField, p: Point, z: f64) -> bool {
        field.is_inside(ev, [p[0], p[1], z])
    }

    /// An enclosure of the clipped field over cells (i0, j0) .. (i0 + n, j0 + n) at `z`:
    /// `inf() >= 0` means nothing there is inside, `sup() < 0` that all of it is.
    fn square_interval(
        &self,
        ev: &mut IntervalEval,
        field: &ClippedField,
        (i0, j0, n): (i32, i32, i32),
        z: Interval,
    ) -> Interval {
        let lo = self.corner(i0, j0);
        let hi = self.corner(i0 + n, j0 + n);
        let span = |a: f64, b: f64| Interval::try_from((a, b)).unwrap_or(Interval::ENTIRE);
        field.interval(ev, [span(lo[0], hi[0]), span(lo[1], hi[1]), z])
    }

    /// The field simplified for the slab `z0..z1` over the whole region; `None` when the
    /// slab is provably empty.
    fn slab_field(&self, ev: &mut IntervalEval, z0: f64, z1: f64) -> Option<ClippedField> {
        let (lo, hi) = (z0.min(z1), z0.max(z1));
        let zi = Interval::try_from((lo, hi)).unwrap_or(Interval::ENTIRE);
        let r = self.square_interval(ev, &self.field, (0, 0, self.cells), zi);
        if r.inf() >= 0.0 {
            return None;
        }
        Some(self.field.narrow(ev))
    }

    fn collect_leaves(
        &self,
        ev: &mut IntervalEval,
        field: &ClippedField,
        (i0, j0, n): (i32, i32, i32),
        z: Interval,
        out: &mut Vec<Leaf>,
    ) {
        let r = self.square_interval(ev, field, (i0, j0, n), z);
        if r.inf() >= 0.0 || r.sup() < 0.0 {
            return;
        }
        if n == 1 {
            out.push(Leaf {
                i: i0,
                j: j0,
                field: field.clone(),
            });
            return;
        }
        let child = field.narrow(ev);
        let h = n / 2;
        for (di, dj) in [(0, 0), (h, 0), (0, h), (h, h)] {
            self.collect_leaves(ev, &child, (i0 + di, j0 + dj, h), z, out);
        }
    }

    /// The outline at height `z`, for a layer spanning `slab` (used to simplify the tape
    /// once for the whole layer). Outer contours are counter-clockwise, holes clockwise.
    pub fn outline(&self, z: f64, slab: (f64, f64)) -> Vec<Contour> {
        let mut iev = IntervalEval::new();
        let mut pev = PointEval::new();
        let Some(field) = self.slab_field(&mut iev, slab.0.min(z), slab.1.max(z)) else {
            return Vec::new();
        };
        let zi = Interval::try_from((z, z)).unwrap_or(Interval::ENTIRE);
        let mut leaves = Vec::new();
        self.collect_leaves(&mut iev, &field, (0, 0, self.cells), zi, &mut leaves);

        let mut corners: HashMap<(i32, i32), bool> = HashMap::with_capacity(leaves.len() * 2);
        let mut segments: Vec<(EdgeKey, EdgeKey)> = Vec::with_capacity(leaves.len());
        // The tape that produced each edge's segment, for refining its crossing.
        let mut edge_tape: HashMap<EdgeKey, usize> = HashMap::with_capacity(leaves.len() * 2);
        for (k, leaf) in leaves.iter().enumerate() {
            let cs = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(di, dj)| {
                let key = (leaf.i + di, leaf.j + dj);
                *corners.entry(key).or_insert_with(|| {
                    self.inside(&mut pev, &leaf.field, self.corner(key.0, key.1), z)
                })
            });
            let before = segments.len();
            let center = {
                let c = self.corner(leaf.i, leaf.j);
                [c[0] + 0.5 * self.cell, c[1] + 0.5 * self.cell]
            };
            let pev_ref = &mut pev;
            cell_segments(
                leaf.i,
                leaf.j,
                cs,
                || self.inside(pev_ref, &leaf.field, center, z),
                &mut segments,
            );
            for s in &segments[before..] {
                edge_tape.entry(s.0).or_insert(k);
                edge_tape.entry(s.1).or_insert(k);
            }
        }

        let mut points: HashMap<EdgeKey, Point> = HashMap::with_capacity(edge_tape.len());
        for (&e, &k) in &edge_tape {
            points.insert(e, self.refine(&mut pev, &leaves[k].field, e, &corners, z));
        }
        let mut out = Vec::new();
        for ch in chain(&segments) {
            if !ch.closed || ch.edges.len() < 3 {
                continue;
            }
            let c: Contour = ch
                .edges
                .iter()
                .filter_map(|e| points.get(e).copied())
                .collect();
            let c = simplify_closed(&c, self.tolerance);
            if c.len() >= 3 {
                out.push(c);
            }
        }
        out
    }

    /// How far the surface faces down at each point of `contours` (at height `z`): −n_z of
    /// the field's unit gradient there, the exact normal of the model.
    pub fn tilts(&self, contours: &[Contour], z: f64) -> Vec<Vec<f32>> {
        let mut ev = GradEval::new();
        contours
            .iter()
            .map(|c| {
                c.iter()
                    .map(|p| {
                        let g = self.field.grad(&mut ev, [p[0], p[1], z]);
                        let len = (g.d[0] * g.d[0] + g.d[1] * g.d[1] + g.d[2] * g.d[2]).sqrt();
                        if len.is_finite() && len > 0.0 {
                            (-g.d[2] / len) as f32
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// The crossing on an edge, by bisection on the field between its inside and outside
    /// corners.
    fn refine(
        &self,
        ev: &mut PointEval,
        field: &ClippedField,
        e: EdgeKey,
        corners: &HashMap<(i32, i32), bool>,
        z: f64,
    ) -> Point {
        let [a, b] = edge_corners(e);
        let (pa, pb) = (self.corner(a.0, a.1), self.corner(b.0, b.1));
        let a_in = corners.get(&a).copied().unwrap_or(false);
        let (mut lo, mut hi) = if a_in { (pa, pb) } else { (pb, pa) };
        for _ in 0..BISECTION_STEPS {
            let mid = [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5];
            if self.inside(ev, field, mid, z) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5]
    }

    /// True when some finest-grid point of the plane at `z` is inside.
    pub fn any_inside(&self, z: f64) -> bool {
        let mut iev = IntervalEval::new();
        let mut pev = PointEval::new();
        let zi = Interval::try_from((z, z)).unwrap_or(Interval::ENTIRE);
        self.search(&mut iev, &mut pev, &self.field, (0, 0, self.cells), z, zi)
    }

    fn search(
        &self,
        iev: &mut IntervalEval,
        pev: &mut PointEval,
        field: &ClippedField,
        (i0, j0, n): (i32, i32, i32),
        z: f64,
        zi: Interval,
    ) -> bool {
        let r = self.square_interval(iev, field, (i0, j0, n), zi);
        if r.inf() >= 0.0 {
            return false;
        }
        if r.sup() < 0.0 {
            return true;
        }
        if n == 1 {
            let c = self.corner(i0, j0);
            let pts = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5]];
            return pts.iter().any(|d| {
                let p = [c[0] + d[0] * self.cell, c[1] + d[1] * self.cell];
                self.inside(pev, field, p, z)
            });
        }
        let child = field.narrow(iev);
        let h = n / 2;
        [(0, 0), (h, 0), (0, h), (h, h)]
            .into_iter()
            .any(|(di, dj)| self.search(iev, pev, &child, (i0 + di, j0 + dj, h), z, zi))
    }

    /// The model's height range within the bounds: the lowest and highest z with material,
    /// found by scanning in steps of `step` mm and bisecting the first hit from each end.
    /// `None` for an empty model.
    pub fn z_extent(&self, step: f64) -> Option<(f64, f64)> {
        let b = self.bounds();
        let (z0, z1) = (b.min[2], b.max[2]);
        let step = if step > 0.0 { step } else { (z1 - z0) / 1000.0 };
        let n = ((z1 - z0) / step).ceil().max(1.0) as usize;
        let at = |k: usize| (z0 + k as f64 * step).min(z1);
        let bottom = (0..=n).find(|&k| self.any_inside(at(k)))?;
        let top = (0..=n).rev().find(|&k| self.any_inside(at(k)))?;
        let lo = if bottom == 0 {
            z0
        } else {
            self.bisect(at(bottom - 1), at(bottom))
        };
        let hi = if top == n {
            z1
        } else {
            self.bisect(at(top + 1), at(top))
        };
        Some((lo, hi))
    }

    /// Bisects between an empty height and one with material.
    fn bisect(&self, mut empty: f64, mut full: f64) -> f64 {
        for _ in 0..24 {
            let mid = 0.5 * (empty + full);
            if self.any_inside(mid) {
                full = mid;
            } else {
                empty = mid;
            }
        }
        0.5 * (empty + full)
    }
}
