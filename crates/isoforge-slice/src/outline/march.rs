//! Marching squares on a grid of cells, shared by the field outline and the gyroid infill.
//!
//! Corners are numbered counter-clockwise from the cell's lower left (c0 (i, j), c1 (i+1, j),
//! c2 (i+1, j+1), c3 (i, j+1)), edges likewise (e0 bottom, e1 right, e2 top, e3 left).
//! Segments are oriented with the inside (negative values) on their left, so chained loops
//! come out counter-clockwise around material and clockwise around holes. A segment runs
//! from an edge where the cell's boundary, walked counter-clockwise, leaves the inside to
//! an edge where it re-enters it.

use std::collections::HashMap;
use std::hash::Hash;

/// An edge of the grid: `(i, j, 0)` is the horizontal edge from corner (i, j) to (i+1, j),
/// `(i, j, 1)` the vertical edge from (i, j) to (i, j+1). Both cells beside an edge name it
/// the same way, which is what makes chaining exact.
pub type EdgeKey = (i32, i32, u8);

/// The edge keys of cell (i, j), e0..e3.
pub fn cell_edges(i: i32, j: i32) -> [EdgeKey; 4] {
    [(i, j, 0), (i + 1, j, 1), (i, j + 1, 0), (i, j, 1)]
}

/// The two corners of an edge, as grid corner indices.
pub fn edge_corners(e: EdgeKey) -> [(i32, i32); 2] {
    let (i, j, d) = e;
    if d == 0 {
        [(i, j), (i + 1, j)]
    } else {
        [(i, j), (i, j + 1)]
    }
}

/// The oriented segments of one cell from its corners' inside flags. `center_inside`
/// settles the saddle cases (c0, c2 inside and c1, c3 outside, or the reverse): when the
/// centre is inside the two inside corners are joined, otherwise they are cut apart. The
/// rule only looks inside the cell, so neighbouring cells never disagree.
pub fn cell_segments(
    i: i32,
    j: i32,
    inside: [bool; 4],
    center_inside: impl FnOnce() -> bool,
    out: &mut Vec<(EdgeKey, EdgeKey)>,
) {
    let edges = cell_edges(i, j);
    let mut starts = [0usize; 2];
    let mut ends = [0usize; 2];
    let (mut ns, mut ne) = (0, 0);
    for k in 0..4 {
        let (a, b) = (inside[k], inside[(k + 1) % 4]);
        if a && !b {
            starts[ns] = k;
            ns += 1;
        } else if !a && b {
            ends[ne] = k;
            ne += 1;
        }
    }
    match ns {
        1 => out.push((edges[starts[0]], edges[ends[0]])),
        2 => {
            let joined = center_inside();
            for &s in &starts {
                let e = if joined { (s + 1) % 4 } else { (s + 3) % 4 };
                out.push((edges[s], edges[e]));
            }
        }
        _ => {}
    }
}

/// A chain of edges: closed loops, or open runs where the grid was cut off.
pub struct Chain<K> {
    /// The edges in order.
    pub edges: Vec<K>,
    /// True for a loop (the last edge connects back to the first).
    pub closed: bool,
}

/// Chains oriented segments into polylines through their shared edges. Each key must
/// start at most one segment (the callers guarantee it: a grid edge or a manifold mesh
/// edge is crossed once per side).
pub fn chain<K: Hash + Eq + Copy>(segments: &[(K, K)]) -> Vec<Chain<K>> {
    let mut next: HashMap<K, usize> = HashMap::with_capacity(segments.len());
    let mut has_pred: HashMap<K, ()> = HashMap::with_capacity(segments.len());
    for (k, (s, e)) in segments.iter().enumerate() {
        next.insert(*s, k);
        has_pred.insert(*e, ());
    }
    let mut used = vec![false; segments.len()];
    let mut chains = Vec::new();
    let walk = |first: usize, used: &mut Vec<bool>| {
        let mut edges = vec![segments[first].0];
        let mut k = first;
        let mut closed = false;
        loop {
            used[k] = true;
            let end = segments[k].1;
            match next.get(&end) {
                Some(&n) if n == first => {
                    closed = true;
                    break;
                }
                Some(&n) if !used[n] => {
                    edges.push(end);
                    k = n;
                }
                _ => {
                    edges.push(end);
                    break;
                }
            }
        }
        Chain { edges, closed }
    };
    // Open runs first (they begin where no segment ends), then the loops.
    for k in 0..segments.len() {
        if !used[k] && !has_pred.contains_key(&segments[k].0) {
            chains.push(walk(k, &mut used));
        }
    }
    for k in 0..segments.len() {
        if !used[k] {
            chains.push(walk(k, &mut used));
        }
    }
    chains
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every one of the 16 corner patterns gives segments whose ends balance (each edge
    /// with a sign change is used exactly once), with both saddle rules.
    #[test]
    fn all_sixteen_cases_balance() {
        for mask in 0..16u8 {
            for center in [false, true] {
                let inside = [0, 1, 2, 3].map(|k| mask & (1 << k) != 0);
                let mut segs = Vec::new();
                cell_segments(0, 0, inside, || center, &mut segs);
                let crossings = (0..4).filter(|&k| inside[k] != inside[(k + 1) % 4]).count();
                assert_eq!(segs.len() * 2, crossings, "mask {mask}");
            }
        }
    }

    #[test]
    fn a_single_inside_corner_makes_a_counter_clockwise_loop_on_a_grid() {
        // A 2x2 grid of cells whose only inside corner is the middle one (1, 1).
        let inside = |i: i32, j: i32| i == 1 && j == 1;
        let mut segs = Vec::new();
        for i in 0..2 {
            for j in 0..2 {
                let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(a, b)| inside(a, b));
                cell_segments(i, j, c, || false, &mut segs);
            }
        }
        let chains = chain(&segs);
        assert_eq!(chains.len(), 1);
        assert!(chains[0].closed);
        assert_eq!(chains[0].edges.len(), 4);
        // Edge midpoints around the loop; the signed area must be positive (CCW).
        let pts: Vec<[f64; 2]> = chains[0]
            .edges
            .iter()
            .map(|&e| {
                let [a, b] = edge_corners(e);
                [(a.0 + b.0) as f64 / 2.0, (a.1 + b.1) as f64 / 2.0]
            })
            .collect();
        assert!(crate::geom::signed_area(&pts) > 0.0);
    }
}
