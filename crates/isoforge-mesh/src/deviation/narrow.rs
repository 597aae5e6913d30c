//! How wide the model is where a mesh misses its tolerance.
//!
//! A point `p` of the mesh that is far from the surface lies in the solid or in the gap
//! outside it; the surface nearest it is at `s`, a distance `d` away in the direction `u`.
//! The model counts as narrow there when either is narrower than the width asked for:
//!
//! * **what `p` is in**: along the same line, from `s` back through `p` and on, to where
//!   the field changes sign again (`p` in a needle's tip, or bridging a narrow groove);
//! * **what is behind `s`**: at a point a little past `s`, along the field's gradient
//!   there, both ways to where the sign changes back (`p` just off a sheet or a fin
//!   thinner than that; a little past, so that at a fin's rounded edge the gradient is
//!   the fin's faces', not its edge's).
//!
//! A lattice of samples cannot follow a solid or a gap narrower than two of its cells (a
//! feature must span two samples to be seen whole), so that is where a mesh made on it
//! may miss. A chord across a convex crease lies in a solid that goes on, with open space
//! behind the face nearest it, and counts as wide.
//!
//! Only points beyond the tolerance are measured, in batches.

use glam::DVec3;
use isoforge_field::{ClippedField, GradEval};

use super::{Batch, Found};

/// Samples along each line, spread over the width: a solid or gap thinner than one step
/// may be stepped over, and is then counted wide (the verdict errs towards "our fault").
const STEPS: usize = 32;
/// How far past `s` the gradient is taken, in steps: a few depths, the model counting
/// narrow if it is at any.
const BEHIND: [usize; 3] = [1, 2, 4];

/// Per sample point: whether it is beyond `tolerance` and the model is narrower than
/// `width` there (see the module doc). Empty when `width` is 0 (none is).
pub(super) fn beyond_and_narrow(
    field: &ClippedField,
    points: &[[f64; 3]],
    found: &[Found],
    tolerance: f64,
    width: f64,
) -> Vec<bool> {
    if width <= 0.0 {
        return Vec::new();
    }
    let mut narrow = vec![false; points.len()];
    let measured: Vec<usize> = (0..points.len())
        .filter(|&i| {
            let f = found[i];
            f.d > tolerance && f.d.is_finite() && f.toward != DVec3::ZERO
        })
        .collect();
    let step = width / STEPS as f64;
    let (mut lines, mut batch) = (Vec::new(), Batch::default());
    let mut grad = GradEval::new();
    // A thousand points at a time: bounded memory, and batches the evaluator likes.
    for chunk in measured.chunks(1024) {
        lines.clear();
        for &i in chunk {
            let (p, f) = (DVec3::from(points[i]), found[i]);
            let s = p + f.toward * f.d;
            // The point itself (its side of the surface), then the line back through it.
            lines.push(p);
            push_line(&mut lines, s, -f.toward, step);
            for m in BEHIND {
                let q = s + f.toward * (step * m as f64);
                let g = DVec3::from(field.grad(&mut grad, q.to_array()).d).normalize_or_zero();
                lines.push(q);
                push_line(&mut lines, q, g, step);
                push_line(&mut lines, q, -g, step);
            }
        }
        let values = batch.eval(field, lines.iter().copied());
        let per_point = 1 + STEPS + BEHIND.len() * (1 + 2 * STEPS);
        for (j, &i) in chunk.iter().enumerate() {
            let v = &values[j * per_point..(j + 1) * per_point];
            let inside = v[0] < 0.0;
            let other_side = |x: f64| (x < 0.0) != inside;
            // What `p` is in: past `p`, the first sample on the other side ends it (one
            // before `p` would be a nearer surface than the search found; not counted).
            let line = &v[1..=STEPS];
            let in_p =
                (0..STEPS).any(|k| step * (k + 1) as f64 > found[i].d && other_side(line[k]));
            // What is behind `s`: the sign at `q`, and its run both ways.
            let behind = (0..BEHIND.len()).any(|b| {
                let at = 1 + STEPS + b * (1 + 2 * STEPS);
                let q_side = other_side(v[at]);
                let ends = |run: &[f64]| run.iter().position(|&x| other_side(x) != q_side);
                let (up, down) = (
                    &v[at + 1..at + 1 + STEPS],
                    &v[at + 1 + STEPS..at + 1 + 2 * STEPS],
                );
                q_side && matches!((ends(up), ends(down)), (Some(a), Some(b)) if a + b + 2 <= STEPS)
            });
            narrow[i] = in_p || behind;
        }
    }
    narrow
}

/// [`STEPS`] points from `from` along `dir`, `step` apart (the first a step away).
fn push_line(line: &mut Vec<DVec3>, from: DVec3, dir: DVec3, step: f64) {
    line.extend((1..=STEPS).map(|k| from + dir * (step * k as f64)));
}

#[cfg(test)]
mod tests {
    use super::super::deviation_where_wide;
    use crate::mesh::Mesh;
    use isoforge_field::{Bounds, ClippedField, Shape};

    /// A flat square at height `z`, two triangles facing up.
    fn square_at(z: f32) -> Mesh {
        Mesh {
            vertices: vec![
                [-0.5, -0.5, z],
                [0.5, -0.5, z],
                [0.5, 0.5, z],
                [-0.5, 0.5, z],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn a_miss_inside_a_thin_sheet_is_narrow_and_inside_a_slab_is_not() {
        let z = Shape::z();
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        // |z| − 0.05: a sheet 0.1 thick. The square at z = 0.01 is 0.04 from its faces.
        let sheet = z.abs() - 0.05;
        let field = ClippedField::new(&sheet, region);
        let mesh = square_at(0.01);
        let d = deviation_where_wide(&mesh, &field, 0.01, 0.2);
        assert!((d.max - 0.04).abs() < 1e-6, "{d:?}");
        assert_eq!(d.points_beyond, 14, "{d:?}");
        assert_eq!(d.points_beyond_narrow, 14, "{d:?}");
        assert!(
            (d.area_beyond_narrow - d.area_beyond).abs() < 1e-12,
            "{d:?}"
        );
        assert!(!d.holds(0.01) && d.holds_where_wide(0.01), "{d:?}");
        // Narrower than the sheet: the sheet counts as wide.
        let d = deviation_where_wide(&mesh, &field, 0.01, 0.05);
        assert_eq!(d.points_beyond_narrow, 0, "{d:?}");
        assert!(!d.holds_where_wide(0.01), "{d:?}");
        // A slab a unit thick: the same miss is the mesh's own.
        let slab = z.abs() - 0.5;
        let mesh = square_at(0.46);
        let d = deviation_where_wide(&mesh, &ClippedField::new(&slab, region), 0.01, 0.2);
        assert!((d.max - 0.04).abs() < 1e-6, "{d:?}");
        assert_eq!(d.points_beyond_narrow, 0, "{d:?}");
        assert!((d.max_wide - d.max).abs() < 1e-12, "{d:?}");
        assert!(!d.holds_where_wide(0.01), "{d:?}");
    }

    #[test]
    fn a_miss_across_a_narrow_gap_is_narrow() {
        let z = Shape::z();
        let region = Bounds::new([-2.0; 3], [2.0; 3]).expect("box");
        // 0.05 − |z|: solid above 0.05 and below −0.05, a gap 0.1 wide between; the
        // square at z = 0.01 is 0.04 from its top.
        let gap = -z.abs() + 0.05;
        let field = ClippedField::new(&gap, region);
        let d = deviation_where_wide(&square_at(0.01), &field, 0.01, 0.2);
        assert!((d.max - 0.04).abs() < 1e-6, "{d:?}");
        assert_eq!(d.points_beyond, 14, "{d:?}");
        assert_eq!(d.points_beyond_narrow, d.points_beyond, "{d:?}");
        assert_eq!(d.max_wide, 0.0, "{d:?}");
        // Without a width, nothing is counted narrow.
        let d = deviation_where_wide(&square_at(0.01), &field, 0.01, 0.0);
        assert_eq!(d.points_beyond_narrow, 0, "{d:?}");
        assert_eq!(d.max_wide, d.max, "{d:?}");
    }
}
