//! The signs a block sampled finer takes on its faces where it meets a block that is not.
//!
//! A refined block (`refined.rs`) is sampled on a lattice `R = 2^levels` times finer than
//! its neighbours. Where it meets a coarse block, the fine lattice points on their shared
//! face (`R + 1` per side of every coarse cell face, `R − 1` inside every coarse edge) are
//! seen by both: by the fine cells, as the corners of their faces, and by the coarse cells,
//! whose face is crossed by the surface where its coarse edges say and joined as its
//! joined rule says (`cell.rs`). The mesh is closed and manifold across the seam when the
//! fine points give the coarse face the same surface: on each coarse edge exactly one fine
//! crossing where its ends differ and none where they agree; on each coarse face curves that
//! join the coarse crossings in the coarse pairing, and no loop of their own.
//!
//! So every fine point on a seam takes the sign its coarse edge or face gives it
//! ([`edge_signs`], [`face_signs`]): the field's own signs there (sampled by the caller)
//! where they already do that, which is nearly always; otherwise a sign made up to do it,
//! uniform inside the face, with the joined rule of the odd fine face at a coarse corner
//! chosen to match. Made-up signs put the fine surface a fraction of a coarse cell off
//! the field for the width of the seam, no more than the coarse mesh is there anyway.
//!
//! Coordinates on a face normal to axis `n` are `(u, v)` along `cell::other_axes(n)`;
//! point `(i, j)` is index `i + (R + 1) j`. The face's coarse edges are numbered
//! `0`: `v = 0`, `1`: `v = R` (along `u`), `2`: `u = 0`, `3`: `u = R` (along `v`), each
//! ordered from its lower end, as the coarse lattice orders them.

/// The signs of the `R + 1` fine points along a coarse edge, its ends first and last:
/// `interior` (the field's signs at the `R − 1` points between) where they cross once when
/// the ends differ and never when they agree; else the start's sign up to the first point
/// that differs from it and the end's sign from there (all the ends' sign when they agree).
pub fn edge_signs(ends: [bool; 2], interior: &[bool]) -> Vec<bool> {
    let mut out = Vec::with_capacity(interior.len() + 2);
    out.push(ends[0]);
    if ends[0] == ends[1] {
        out.extend(std::iter::repeat_n(ends[0], interior.len()));
    } else {
        let first = interior.iter().position(|&s| s != ends[0]);
        for k in 0..interior.len() {
            out.push(match first {
                Some(f) if k >= f => ends[1],
                _ => ends[0],
            });
        }
    }
    out.push(ends[1]);
    out
}

/// The fine signs of one coarse face on a seam, and what its fine crossings stand for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FaceSeam {
    /// Fine cells per side of the coarse face.
    pub r: usize,
    /// The sign (inside) of each of the `(R + 1)²` points.
    pub signs: Vec<bool>,
    /// Per fine face (`i + R j`), whether the solid runs across it between its inside
    /// corners; read only where the fine face is ambiguous.
    pub joined: Vec<bool>,
    /// Per fine edge (`edge_index` numbering), the coarse edge (0 to 3) at one end of the
    /// curve it lies on, or [`NO_SEGMENT`] where the edge is not crossed.
    pub segment: Vec<u8>,
    /// True where the field's own signs were kept; false where they were made up.
    pub sampled: bool,
}

/// Seam faces whose signs were made up, for the tests to see that it happens.
#[cfg(test)]
pub static MADE_UP: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// No curve crosses this fine edge.
pub const NO_SEGMENT: u8 = u8::MAX;

/// Fine edges of a face: `R (R + 1)` along `u`, then as many along `v`. The one along `u`
/// from point `(i, j)` is `i + R j`; the one along `v` from `(i, j)` is
/// `R (R + 1) + i + (R + 1) j`.
pub fn edge_index(r: usize, along_v: bool, i: usize, j: usize) -> usize {
    if along_v {
        r * (r + 1) + i + (r + 1) * j
    } else {
        i + r * j
    }
}

impl FaceSeam {
    /// The sign of point `(i, j)`.
    pub fn sign(&self, i: usize, j: usize) -> bool {
        self.signs[i + (self.r + 1) * j]
    }
}

/// Builds the fine signs of a seam face. `edges` are the signs along its four coarse edges
/// (from [`edge_signs`], numbered as in the module doc, so their ends are the face's
/// corners); `joined` the coarse face's joined rule; `interior` the field's signs at the
/// `(R − 1)²` inner points, row by row; `fine_joined(i, j)` the joined rule of fine face
/// `(i, j)` by the field (asked only of ambiguous ones).
pub fn face_signs(
    edges: [&[bool]; 4],
    joined: bool,
    interior: &[bool],
    mut fine_joined: impl FnMut(usize, usize) -> bool,
) -> FaceSeam {
    let r = edges[0].len() - 1;
    let n = r + 1;
    let mut signs = vec![false; n * n];
    for i in 0..n {
        signs[i] = edges[0][i];
        signs[i + n * r] = edges[1][i];
        signs[n * i] = edges[2][i];
        signs[r + n * i] = edges[3][i];
    }
    let mut boundary = signs.clone();
    for j in 1..r {
        for i in 1..r {
            signs[i + n * j] = interior[(i - 1) + (r - 1) * (j - 1)];
        }
    }
    let mut fine = vec![false; r * r];
    for j in 0..r {
        for i in 0..r {
            if ambiguous(&signs, n, i, j) {
                fine[i + r * j] = fine_joined(i, j);
            }
        }
    }
    if let Some(segment) = trace(r, &signs, &fine, joined) {
        return FaceSeam {
            r,
            signs,
            joined: fine,
            segment,
            sampled: true,
        };
    }
    // Made up: every inner point one sign, and an ambiguous fine face (only a corner's
    // can be one) joined so that its corners of that sign connect through it.
    #[cfg(test)]
    MADE_UP.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let crossed = (0..4).filter(|&e| edges[e][0] != edges[e][r]).count();
    let fill = if crossed == 4 {
        // The coarse face joins its inside corners (a uniform inside runs across it) or
        // keeps them apart (a uniform outside does).
        joined
    } else {
        let inside = boundary.iter().filter(|&&s| s).count();
        2 * inside > boundary.len()
    };
    for j in 1..r {
        for i in 1..r {
            boundary[i + n * j] = fill;
        }
    }
    let signs = boundary;
    let mut fine = vec![false; r * r];
    for j in 0..r {
        for i in 0..r {
            if ambiguous(&signs, n, i, j) {
                fine[i + r * j] = fill;
            }
        }
    }
    let segment = trace(r, &signs, &fine, joined).unwrap_or_else(|| vec![NO_SEGMENT; 2 * r * n]);
    FaceSeam {
        r,
        signs,
        joined: fine,
        segment,
        sampled: false,
    }
}

/// True when fine face `(i, j)` has its inside corners diagonal.
fn ambiguous(signs: &[bool], n: usize, i: usize, j: usize) -> bool {
    let c00 = signs[i + n * j];
    let c10 = signs[i + 1 + n * j];
    let c01 = signs[i + n * (j + 1)];
    let c11 = signs[i + 1 + n * (j + 1)];
    c00 == c11 && c10 == c01 && c00 != c10
}

/// The coarse pairing of a face's crossed coarse edges, as pairs of coarse edge numbers.
fn coarse_pairs(corners: [bool; 4], joined: bool) -> Vec<[u8; 2]> {
    // Corners (0,0), (R,0), (0,R), (R,R); coarse edge e joins these two.
    let ends = [[0, 1], [2, 3], [0, 2], [1, 3]];
    let crossed: Vec<u8> = (0..4u8)
        .filter(|&e| corners[ends[e as usize][0]] != corners[ends[e as usize][1]])
        .collect();
    match crossed.len() {
        2 => vec![[crossed[0], crossed[1]]],
        4 => {
            // The edges meeting at each corner; pairs go around the inside corners, or
            // around the outside ones when the face is joined.
            let at = [[0u8, 2], [0, 3], [1, 2], [1, 3]];
            (0..4)
                .filter(|&c| corners[c] != joined)
                .map(|c| at[c])
                .collect()
        }
        _ => Vec::new(),
    }
}

/// Traces the fine curves of a face: for each crossed fine edge the coarse edge at one end
/// of its curve, if every curve runs from one coarse crossing to its coarse partner (no
/// loop, no other pairing); `None` otherwise.
fn trace(r: usize, signs: &[bool], joined: &[bool], coarse_joined: bool) -> Option<Vec<u8>> {
    let n = r + 1;
    let total = 2 * r * n;
    let ends_of = |e: usize| -> (usize, usize) {
        if e < r * n {
            let (i, j) = (e % r, e / r);
            (i + n * j, i + 1 + n * j)
        } else {
            let k = e - r * n;
            let (i, j) = (k % n, k / n);
            (i + n * j, i + n * (j + 1))
        }
    };
    let crossed = |e: usize| {
        let (a, b) = ends_of(e);
        signs[a] != signs[b]
    };
    // Each crossed edge's partners through its (one or two) fine faces.
    let mut link = vec![[usize::MAX; 2]; total];
    let add = |a: usize, b: usize, link: &mut Vec<[usize; 2]>| {
        for (x, y) in [(a, b), (b, a)] {
            let slot = usize::from(link[x][0] != usize::MAX);
            link[x][slot] = y;
        }
    };
    for j in 0..r {
        for i in 0..r {
            let bottom = edge_index(r, false, i, j);
            let top = edge_index(r, false, i, j + 1);
            let left = edge_index(r, true, i, j);
            let right = edge_index(r, true, i + 1, j);
            let sides = [bottom, top, left, right];
            let cut: Vec<usize> = sides.iter().copied().filter(|&e| crossed(e)).collect();
            match cut.len() {
                0 => {}
                2 => add(cut[0], cut[1], &mut link),
                _ => {
                    // Ambiguous: pairs around the corners of the sign that does not run
                    // across (around the inside corners unless joined).
                    let c00 = signs[i + n * j];
                    let around_00_11 = c00 != joined[i + r * j];
                    if around_00_11 {
                        add(bottom, left, &mut link);
                        add(top, right, &mut link);
                    } else {
                        add(bottom, right, &mut link);
                        add(top, left, &mut link);
                    }
                }
            }
        }
    }
    // The coarse edge a boundary fine edge lies on.
    let coarse_edge = |e: usize| -> Option<u8> {
        if e < r * n {
            let j = e / r;
            (j == 0).then_some(0).or((j == r).then_some(1))
        } else {
            let i = (e - r * n) % n;
            (i == 0).then_some(2).or((i == r).then_some(3))
        }
    };
    let mut segment = vec![NO_SEGMENT; total];
    let mut found: Vec<[u8; 2]> = Vec::new();
    for start in 0..total {
        let Some(from) = coarse_edge(start) else {
            continue;
        };
        if !crossed(start) || segment[start] != NO_SEGMENT {
            continue;
        }
        let (mut prev, mut cur) = (usize::MAX, start);
        let mut path = Vec::new();
        loop {
            path.push(cur);
            let [a, b] = link[cur];
            let next = if a != prev { a } else { b };
            if next == usize::MAX {
                break;
            }
            prev = cur;
            cur = next;
            if path.len() > total {
                return None;
            }
        }
        let to = coarse_edge(cur)?;
        let label = from.min(to);
        for &e in &path {
            segment[e] = label;
        }
        found.push([from.min(to), from.max(to)]);
    }
    // A crossed edge no path reached lies on a loop of its own.
    if (0..total).any(|e| crossed(e) && segment[e] == NO_SEGMENT) {
        return None;
    }
    let corners = [signs[0], signs[r], signs[n * r], signs[r + n * r]];
    let mut want = coarse_pairs(corners, coarse_joined);
    for p in &mut want {
        p.sort_unstable();
    }
    want.sort_unstable();
    found.sort_unstable();
    (found == want).then_some(segment)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator for the sampled signs.
    struct Lcg(u64);
    impl Lcg {
        fn bit(&mut self) -> bool {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            self.0 >> 33 & 1 == 1
        }
    }

    #[test]
    fn an_edge_crosses_once_where_its_ends_differ_and_never_where_they_agree() {
        for r in [2usize, 4, 8] {
            for bits in 0..1u32 << (r - 1) {
                let interior: Vec<bool> = (0..r - 1).map(|k| bits >> k & 1 == 1).collect();
                for ends in [[false, false], [true, true], [false, true], [true, false]] {
                    let s = edge_signs(ends, &interior);
                    assert_eq!(s.len(), r + 1);
                    assert_eq!((s[0], s[r]), (ends[0], ends[1]));
                    let changes = s.windows(2).filter(|w| w[0] != w[1]).count();
                    assert_eq!(changes, usize::from(ends[0] != ends[1]));
                    // Sampled signs that already do so are kept.
                    let mut all = vec![ends[0]];
                    all.extend(&interior);
                    all.push(ends[1]);
                    if all.windows(2).filter(|w| w[0] != w[1]).count() == changes {
                        assert_eq!(s, all);
                    }
                }
            }
        }
    }

    /// Every corner pattern, every place of the coarse crossings, both joined rules, and
    /// sampled inner signs (all of them at R = 2, many at R = 4): the face always traces
    /// to the coarse pairing, keeps its boundary, and keeps sampled signs that trace.
    #[test]
    fn every_seam_face_traces_to_its_coarse_pairing() {
        for r in [2usize, 4] {
            let mut rng = Lcg(r as u64);
            let inner = (r - 1) * (r - 1);
            let samples: Vec<u32> = if inner <= 9 && r == 2 {
                (0..1u32 << inner).collect()
            } else {
                (0..64u32)
                    .map(|k| k.wrapping_mul(0x9e37_79b9) >> (32 - inner))
                    .collect()
            };
            for corners in 0..16u8 {
                let c = |k: u8| corners >> k & 1 == 1;
                let ends = [[c(0), c(1)], [c(2), c(3)], [c(0), c(2)], [c(1), c(3)]];
                for places in 0..(r as u32).pow(4) {
                    let mut edges: Vec<Vec<bool>> = Vec::new();
                    for (e, end) in ends.iter().enumerate() {
                        let at = (places / (r as u32).pow(e as u32)) as usize % r;
                        let interior: Vec<bool> = (1..r)
                            .map(|k| if k <= at { end[0] } else { end[1] })
                            .collect();
                        edges.push(edge_signs(*end, &interior));
                    }
                    for joined in [false, true] {
                        for &bits in &samples {
                            let interior: Vec<bool> =
                                (0..inner).map(|k| bits >> k & 1 == 1).collect();
                            let face = face_signs(
                                [&edges[0], &edges[1], &edges[2], &edges[3]],
                                joined,
                                &interior,
                                |_, _| rng.bit(),
                            );
                            let kept = (0..=r).all(|i| {
                                [
                                    face.sign(i, 0),
                                    face.sign(i, r),
                                    face.sign(0, i),
                                    face.sign(r, i),
                                ] == [edges[0][i], edges[1][i], edges[2][i], edges[3][i]]
                            });
                            assert!(kept, "r {r} corners {corners:04b}: boundary changed");
                            let traced = trace(r, &face.signs, &face.joined, joined);
                            assert_eq!(
                                traced.as_ref(),
                                Some(&face.segment),
                                "r {r} corners {corners:04b}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_face_whose_samples_trace_keeps_them() {
        // R = 4, corner (0,0) inside alone, crossings at the middle of edges 0 and 2, and
        // the sampled quarter disc of inside points around it.
        let e0 = edge_signs([true, false], &[true, false, false]);
        let e2 = edge_signs([true, false], &[true, false, false]);
        let e1 = edge_signs([false, false], &[false; 3]);
        let e3 = edge_signs([false, false], &[false; 3]);
        let mut interior = vec![false; 9];
        interior[0] = true; // (1, 1)
        let face = face_signs([&e0, &e1, &e2, &e3], false, &interior, |_, _| false);
        assert!(face.sampled);
        assert!(face.sign(1, 1));
        // An island of inside in the middle is not the coarse face's surface.
        let mut island = vec![false; 9];
        island[4] = true; // (2, 2)
        let face = face_signs([&e0, &e1, &e2, &e3], false, &island, |_, _| false);
        assert!(!face.sampled);
        assert!(!face.sign(2, 2));
    }
}
