//! The mesh checker: closed, manifold, oriented; volume, area, bounds.
//!
//! Edges are found by sorting, not hashing: every triangle contributes its three edges keyed
//! by their (lower, higher) vertex pair, one parallel sort groups equal keys, and each group
//! is judged by its size (1: boundary, 2: manifold, 3+: non-manifold) and directions (an
//! interior edge must be walked once each way). Non-manifold vertices are found by joining,
//! around each vertex, the triangle corners that share a manifold edge: a vertex whose
//! corners fall into more than one fan is a pinch point (two cones tip to tip, a bow tie).

use rayon::prelude::*;

use glam::DVec3;

use crate::mesh::Mesh;

mod stream;
pub use stream::{StreamCheck, StreamReport};

/// What the checker found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshReport {
    /// Triangles in the mesh.
    pub triangles: usize,
    /// Vertices in the mesh.
    pub vertices: usize,
    /// Vertices no triangle uses (harmless, but reported).
    pub unused_vertices: usize,
    /// Triangles naming a vertex index past the last vertex (ignored by every other count).
    pub bad_indices: usize,
    /// Connected components, triangles joined through shared edges.
    pub components: usize,
    /// Edges used by one triangle only: the rims of holes.
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Edges shared by two triangles that walk it the same way: a flipped neighbour.
    pub inconsistent_edges: usize,
    /// Triangles with a repeated index or zero area.
    pub degenerate_triangles: usize,
    /// Of those, triangles with a repeated vertex index (they break the topology, so they
    /// make the mesh non-manifold; zero-area triangles with three distinct corners do not).
    pub collapsed_triangles: usize,
    /// Vertices whose triangles do not form one fan (a disk, or a half-disk on a boundary).
    pub non_manifold_vertices: usize,
    /// Signed volume by the divergence theorem, in mm³: negative when the faces point in.
    pub volume: f64,
    /// Surface area in mm².
    pub area: f64,
    /// The vertices' bounding box `[min, max]`, if there are vertices.
    pub bounds: Option<[[f64; 3]; 2]>,
    /// No boundary edges (and at least one triangle, and no bad indices).
    pub watertight: bool,
    /// No non-manifold edges or vertices, no collapsed triangles, consistently oriented.
    pub manifold: bool,
}

impl MeshReport {
    /// True when the mesh is watertight, manifold and consistently oriented.
    pub fn is_closed_manifold(&self) -> bool {
        self.watertight && self.manifold
    }

    /// What is wrong with the mesh, in words, most serious first (empty when nothing is).
    /// Includes warnings (negative volume, degenerate triangles) that do not change the
    /// verdicts.
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut say = |n: usize, what: &str| {
            if n > 0 {
                out.push(format!("{n} {what}"));
            }
        };
        if self.triangles == 0 {
            say(1, "mesh has no triangles");
        }
        say(
            self.bad_indices,
            "triangles name a vertex that does not exist",
        );
        say(self.boundary_edges, "boundary edges (the mesh has holes)");
        say(
            self.non_manifold_edges,
            "non-manifold edges (shared by 3+ triangles)",
        );
        say(
            self.inconsistent_edges,
            "inconsistently oriented edges (flipped triangles)",
        );
        say(
            self.non_manifold_vertices,
            "non-manifold vertices (surfaces touching at a point)",
        );
        say(self.collapsed_triangles, "triangles with a repeated vertex");
        let flat = self.degenerate_triangles - self.collapsed_triangles;
        say(flat, "zero-area triangles (warning)");
        if self.is_closed_manifold() && self.volume < 0.0 {
            out.push("negative volume: the faces point inward (warning)".into());
        }
        out
    }
}

/// One directed use of an undirected edge.
#[derive(Copy, Clone)]
struct EdgeUse {
    /// (lower vertex << 32) | higher vertex.
    key: u64,
    /// The triangle.
    tri: u32,
    /// Which edge of the triangle: from corner `k` to corner `(k + 1) % 3`.
    k: u8,
    /// True when the triangle walks it from the higher vertex to the lower.
    down: bool,
}

impl EdgeUse {
    /// The corner (3 * triangle + k) at the edge's lower and higher vertex.
    fn corners(&self) -> (usize, usize) {
        let t = self.tri as usize * 3;
        let start = t + self.k as usize;
        let end = t + (self.k as usize + 1) % 3;
        if self.down {
            (end, start)
        } else {
            (start, end)
        }
    }
}

/// Union-find with path halving.
struct Dsu(Vec<u32>);

impl Dsu {
    fn new(n: usize) -> Self {
        Dsu((0..n as u32).collect())
    }
    fn find(&mut self, mut a: u32) -> u32 {
        while self.0[a as usize] != a {
            let up = self.0[self.0[a as usize] as usize];
            self.0[a as usize] = up;
            a = up;
        }
        a
    }
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // Lower root wins: deterministic, and good enough with path halving.
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// Triangles summed one after another before the runs' sums are added (see [`check`]).
const SUM_RUN: usize = 1 << 14;

/// Checks a mesh.
pub fn check(mesh: &Mesh) -> MeshReport {
    let nv = mesh.vertices.len();
    let mut r = MeshReport {
        triangles: mesh.triangles.len(),
        vertices: nv,
        bounds: mesh
            .bounds()
            .map(|[lo, hi]| [lo.map(f64::from), hi.map(f64::from)]),
        ..MeshReport::default()
    };
    // Triangles too many for our u32 ids cannot come from any reader (files that large
    // exceed u32 counts); treat the excess as bad rather than panic.
    let usable = mesh.triangles.len().min(u32::MAX as usize / 3);
    r.bad_indices = mesh.triangles.len() - usable;

    // Per triangle: 0 usable, 1 bad index, 2 collapsed (repeated index).
    let status: Vec<u8> = mesh.triangles[..usable]
        .par_iter()
        .map(|t| {
            if t.iter().any(|&i| i as usize >= nv) {
                1
            } else if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
                2
            } else {
                0
            }
        })
        .collect();
    r.bad_indices += status.iter().filter(|&&s| s == 1).count();
    r.collapsed_triangles = status.iter().filter(|&&s| s == 2).count();

    // Volume, area and zero-area triangles over every triangle with valid indices.
    let centre = r
        .bounds
        .map(|[lo, hi]| (DVec3::from(lo) + DVec3::from(hi)) * 0.5)
        .unwrap_or(DVec3::ZERO);
    // Summed in fixed runs of triangles, then the runs in order: the same file gives the
    // same volume to the last bit however many threads share the work (a reduce that
    // splits as threads steal does not).
    let (six_v, twice_area, zero_area) = mesh.triangles[..usable]
        .par_chunks(SUM_RUN)
        .zip(status.par_chunks(SUM_RUN))
        .map(|(tris, statuses)| {
            let mut sums = (0.0, 0.0, 0);
            for (&t, &s) in tris.iter().zip(statuses).filter(|(_, s)| **s != 1) {
                let [a, b, c] = mesh.corners(t).map(|p| p - centre);
                let twice = (b - a).cross(c - a).length();
                sums.0 += a.dot(b.cross(c));
                sums.1 += twice;
                sums.2 += usize::from(s == 0 && twice == 0.0);
            }
            sums
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold((0.0, 0.0, 0), |x, y| (x.0 + y.0, x.1 + y.1, x.2 + y.2));
    r.volume = six_v / 6.0;
    r.area = twice_area * 0.5;
    r.degenerate_triangles = r.collapsed_triangles + zero_area;

    // Edge uses of every usable triangle, grouped by sorting.
    let mut edges: Vec<EdgeUse> = status
        .par_iter()
        .enumerate()
        .filter(|(_, s)| **s == 0)
        .flat_map_iter(|(ti, _)| {
            let t = mesh.triangles[ti];
            (0..3u8).map(move |k| {
                let (a, b) = (t[k as usize], t[(k as usize + 1) % 3]);
                let (lo, hi, down) = if a < b { (a, b, false) } else { (b, a, true) };
                EdgeUse {
                    key: (u64::from(lo) << 32) | u64::from(hi),
                    tri: ti as u32,
                    k,
                    down,
                }
            })
        })
        .collect();
    edges.par_sort_unstable_by_key(|e| e.key);

    let mut tris = Dsu::new(usable);
    let mut corners = Dsu::new(usable * 3);
    let mut used = vec![false; nv];
    for (ti, _) in status.iter().enumerate().filter(|(_, s)| **s == 0) {
        for &v in &mesh.triangles[ti] {
            used[v as usize] = true;
        }
    }
    r.unused_vertices = used.iter().filter(|&&u| !u).count();

    for group in edges.chunk_by(|a, b| a.key == b.key) {
        match group {
            [_] => r.boundary_edges += 1,
            [e, f] => {
                if e.down == f.down {
                    r.inconsistent_edges += 1;
                }
                tris.union(e.tri, f.tri);
                let (e_lo, e_hi) = e.corners();
                let (f_lo, f_hi) = f.corners();
                corners.union(e_lo as u32, f_lo as u32);
                corners.union(e_hi as u32, f_hi as u32);
            }
            _ => {
                r.non_manifold_edges += 1;
                for pair in group.windows(2) {
                    tris.union(pair[0].tri, pair[1].tri);
                }
            }
        }
    }

    // Fans per vertex: one per corner set (a root corner) around it.
    let mut fans = vec![0u8; nv];
    for (ti, _) in status.iter().enumerate().filter(|(_, s)| **s == 0) {
        r.components += usize::from(tris.find(ti as u32) == ti as u32);
        for k in 0..3 {
            let c = (ti * 3 + k) as u32;
            if corners.find(c) == c {
                let v = mesh.triangles[ti][k] as usize;
                fans[v] = fans[v].saturating_add(1);
            }
        }
    }
    r.non_manifold_vertices = fans.iter().filter(|&&f| f > 1).count();

    let usable_tris = status.iter().filter(|&&s| s == 0).count();
    r.watertight = usable_tris > 0 && r.boundary_edges == 0 && r.bad_indices == 0;
    r.manifold = r.non_manifold_edges == 0
        && r.non_manifold_vertices == 0
        && r.inconsistent_edges == 0
        && r.collapsed_triangles == 0
        && r.bad_indices == 0;
    r
}

#[cfg(test)]
mod tests;
