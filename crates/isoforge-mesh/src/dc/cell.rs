//! Cell tables: corner, edge and face numbering, and the patches of every corner sign
//! pattern (one vertex per patch, as in Nielson 2004, "Dual marching cubes").
//!
//! Numbering (all tables below follow it):
//! - corner `c` has offsets `(c & 1, c >> 1 & 1, c >> 2 & 1)` along x, y, z;
//! - edge `4a + ub + 2uc` runs along axis `a` from the corner with offsets `ub` along
//!   `b = (a+1) % 3` and `uc` along `c = (a+2) % 3` (and 0 along `a`) to its neighbour
//!   along `a`;
//! - the lower face of axis `n` holds the corners with offset 0 along `n`.
//!
//! A pattern's patches come from pairing, on each face, the face's sign-changing edges:
//! two of them are paired; four (an ambiguous face, inside corners diagonal) are paired so
//! that the inside corners are separated, each pair around one inside corner, unless the
//! face is *joined*: then each pair goes around one outside corner, and the solid runs
//! across the face from one inside corner to the other. Which faces are joined is part of
//! a cell's case ([`case_key`]); the mesher decides it from the face alone (the field at
//! its middle, `leaf.rs`), so both cells sharing a face pair its edges alike. Every
//! sign-changing edge lies on two faces of the cell, so the pairing graph is 2-regular:
//! its cycles are the patches.

use std::sync::LazyLock;

/// No patch / no pair.
pub const NONE: u8 = u8::MAX;

/// The two axes after `a`, in cyclic order, so that `a = b × c`.
pub const fn other_axes(a: usize) -> (usize, usize) {
    ((a + 1) % 3, (a + 2) % 3)
}

/// The corners an edge joins: (start, end), end = start + 1 along the edge's axis.
pub const fn edge_corners(edge: usize) -> (usize, usize) {
    let a = edge / 4;
    let (b, c) = other_axes(a);
    let start = ((edge & 1) << b) | (((edge >> 1) & 1) << c);
    (start, start | (1 << a))
}

/// The edge id of the edge along `a` whose start corner has offsets `ub`, `uc` along the
/// two other axes.
pub const fn edge_id(a: usize, ub: usize, uc: usize) -> usize {
    4 * a + ub + 2 * uc
}

/// What a cell with a given corner sign pattern holds.
#[derive(Clone, Copy, Debug)]
pub struct CellCase {
    /// The number of patches (vertices).
    pub patches: u8,
    /// Per edge, the patch its crossing belongs to, or [`NONE`] when it has no crossing.
    pub edge_patch: [u8; 12],
    /// Per axis, whether the lower face of that axis is ambiguous (four crossings).
    pub lower_ambiguous: [bool; 3],
    /// Its faces with four sign-changing edges, as [`face_bit`]s (all six sides).
    pub ambiguous: u8,
    /// Per axis and edge, for the lower face of that axis when it is ambiguous: which of
    /// the face's two pairs (0 or 1) the edge belongs to, else [`NONE`].
    pub lower_pair: [[u8; 12]; 3],
}

/// The case of every sign pattern and choice of joined faces, at [`case_key`]: the first
/// 256 are the sign patterns with no face joined (bit `c` set when corner `c` is inside).
pub static CASES: LazyLock<Vec<CellCase>> = LazyLock::new(|| {
    (0..1usize << 14)
        .map(|key| build_case(key as u8, (key >> 8) as u8))
        .collect()
});

/// The bit of face (axis `n`, `side` 0 for the lower, 1 for the upper) in a set of faces.
pub const fn face_bit(n: usize, side: usize) -> u8 {
    1 << (2 * n + side)
}

/// Where the case of a cell with corner signs `signs` and joined faces `joined` (a set of
/// [`face_bit`]s; bits of faces that are not ambiguous change nothing) is in [`CASES`].
pub fn case_key(signs: u8, joined: u8) -> usize {
    usize::from(signs) | usize::from(joined & 0x3f) << 8
}

fn inside(signs: u8, corner: usize) -> bool {
    signs >> corner & 1 == 1
}

/// True when the edge's corners differ in sign.
pub fn crosses(signs: u8, edge: usize) -> bool {
    let (s, e) = edge_corners(edge);
    inside(signs, s) != inside(signs, e)
}

/// The 4 edges of face (axis `n`, side `side`), and, for each, which face corners it joins.
fn face_edges(n: usize, side: usize) -> [usize; 4] {
    let mut out = [0; 4];
    let mut k = 0;
    for edge in 0..12 {
        let a = edge / 4;
        if a == n {
            continue;
        }
        let (b, _c) = other_axes(a);
        let offset = if b == n { edge & 1 } else { (edge >> 1) & 1 };
        if offset == side {
            out[k] = edge;
            k += 1;
        }
    }
    out
}

/// Pairs the sign-changing edges of one face. Returns the pairs (edge ids); one pair for
/// a plain face, two for an ambiguous one, ordered by the lower inside corner (outside
/// corner, when `joined`).
fn face_pairs(signs: u8, n: usize, side: usize, joined: bool) -> Vec<[usize; 2]> {
    let edges = face_edges(n, side);
    let crossing: Vec<usize> = edges
        .iter()
        .copied()
        .filter(|&e| crosses(signs, e))
        .collect();
    match crossing.len() {
        2 => vec![[crossing[0], crossing[1]]],
        4 => {
            // Inside corners separated: each pair is the two face edges at one inside corner;
            // joined, at one outside corner.
            let mut corners: Vec<usize> = (0..8)
                .filter(|&c| (c >> n) & 1 == side && inside(signs, c) != joined)
                .collect();
            corners.sort_unstable();
            corners
                .iter()
                .map(|&corner| {
                    let at: Vec<usize> = edges
                        .iter()
                        .copied()
                        .filter(|&e| {
                            let (s, t) = edge_corners(e);
                            s == corner || t == corner
                        })
                        .collect();
                    [at[0], at[1]]
                })
                .collect()
        }
        _ => Vec::new(),
    }
}

fn build_case(signs: u8, joined: u8) -> CellCase {
    // Each crossing edge gets its partner on each of its two faces.
    let mut partners: [[usize; 2]; 12] = [[usize::MAX; 2]; 12];
    let mut lower_ambiguous = [false; 3];
    let mut lower_pair = [[NONE; 12]; 3];
    let mut ambiguous = 0;
    for n in 0..3 {
        for side in 0..2 {
            let pairs = face_pairs(signs, n, side, joined & face_bit(n, side) != 0);
            if pairs.len() == 2 {
                ambiguous |= face_bit(n, side);
            }
            if side == 0 && pairs.len() == 2 {
                lower_ambiguous[n] = true;
                for (k, pair) in pairs.iter().enumerate() {
                    for &e in pair {
                        lower_pair[n][e] = k as u8;
                    }
                }
            }
            for [p, q] in pairs {
                let slot = usize::from(partners[p][0] != usize::MAX);
                partners[p][slot] = q;
                let slot = usize::from(partners[q][0] != usize::MAX);
                partners[q][slot] = p;
            }
        }
    }
    let mut edge_patch = [NONE; 12];
    let mut patches = 0u8;
    for start in 0..12 {
        if !crosses(signs, start) || edge_patch[start] != NONE {
            continue;
        }
        // Walk the cycle through `start`.
        let (mut prev, mut cur) = (usize::MAX, start);
        loop {
            edge_patch[cur] = patches;
            let [p, q] = partners[cur];
            let next = if p != prev { p } else { q };
            prev = cur;
            cur = next;
            if cur == start {
                break;
            }
        }
        patches += 1;
    }
    CellCase {
        patches,
        edge_patch,
        lower_ambiguous,
        ambiguous,
        lower_pair,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_crossing_edge_has_a_patch_and_patches_are_cycles() {
        for key in 0..CASES.len() {
            let (signs, case) = (key as u8, &CASES[key]);
            let mut sizes = vec![0; case.patches as usize];
            for e in 0..12 {
                if crosses(signs, e) {
                    assert_ne!(case.edge_patch[e], NONE);
                    sizes[case.edge_patch[e] as usize] += 1;
                } else {
                    assert_eq!(case.edge_patch[e], NONE);
                }
            }
            // A patch is a polygon: at least 3 crossings.
            assert!(sizes.iter().all(|&s| s >= 3), "case {key}: {sizes:?}");
        }
        assert_eq!(CASES[0].patches, 0);
        assert_eq!(CASES[255].patches, 0);
        assert_eq!(CASES[1].patches, 1);
        // Two diagonal corners across the body: two patches.
        assert_eq!(CASES[0b1000_0001].patches, 2);
        // Two diagonal corners of the lower z face: two patches apart, one where the
        // face joins them (the solid runs across it, and the patch around both).
        let diagonal = 0b0000_1001;
        assert_eq!(CASES[diagonal as usize].ambiguous, face_bit(2, 0));
        assert_eq!(CASES[case_key(diagonal, 0)].patches, 2);
        assert_eq!(CASES[case_key(diagonal, face_bit(2, 0))].patches, 1);
        // A bit for a face that is not ambiguous changes nothing.
        let plain = CASES[case_key(diagonal, face_bit(0, 0))];
        assert_eq!(plain.edge_patch, CASES[diagonal as usize].edge_patch);
    }

    #[test]
    fn a_joined_face_pairs_its_edges_around_its_outside_corners() {
        // Lower z face with corners 0 and 3 inside: separated, the pairs meet at the
        // inside corners 0 and 3; joined, at the outside corners 1 and 2.
        let signs = 0b0000_1001;
        let at = |pairs: Vec<[usize; 2]>| -> Vec<usize> {
            pairs
                .iter()
                .map(|&[p, q]| {
                    let (a, b) = edge_corners(p);
                    let (c, d) = edge_corners(q);
                    *[a, b]
                        .iter()
                        .find(|&&x| x == c || x == d)
                        .expect("a shared corner")
                })
                .collect()
        };
        assert_eq!(at(face_pairs(signs, 2, 0, false)), vec![0, 3]);
        assert_eq!(at(face_pairs(signs, 2, 0, true)), vec![1, 2]);
    }

    #[test]
    fn edge_numbering_round_trips() {
        for a in 0..3 {
            for ub in 0..2 {
                for uc in 0..2 {
                    let e = edge_id(a, ub, uc);
                    let (s, t) = edge_corners(e);
                    assert_eq!(t, s | 1 << a);
                    assert_eq!(s >> a & 1, 0);
                }
            }
        }
    }
}
