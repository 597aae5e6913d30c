//! Polygons: one per sign-changing edge on the boundary of leaves (Ju et al. 2002; patches
//! as in Nielson 2004 and Schaefer, Ju, Warren 2007).
//!
//! Each crossing finest edge gets the polygon through the vertices of the leaves around it:
//! the leaves holding its four cells, in order around the edge. When a leaf holds two of
//! them (the edge lies inside a face of a larger leaf) it counts once and the polygon is a
//! triangle; when two leaves hold all four (the edge lies inside a face between two leaves)
//! or one does (inside a leaf), the edge is not a leaf edge and has no polygon. A leaf's
//! edge longer than a finest edge holds at most one crossing (`topology.rs`), so no leaf
//! edge gets two polygons.
//!
//! Why this is always a closed 2-manifold: the polygons are the dual of the marching-cubes
//! surface that the face pairing defines on the leaves' faces (leaf patch ↔ vertex,
//! crossing ↔ polygon, face segment ↔ polygon edge). That surface is closed, and each leaf's
//! ring of segments is one loop (`topology.rs` says why for merged leaves), so every dual
//! edge borders exactly two polygons and every vertex's polygons form one fan. The one way
//! the dual fails as a triangle mesh is when two segments join the same two patches: both
//! lie on one finest face (a merged leaf's faces are never ambiguous), which is then
//! ambiguous (four crossings, two pairs), and vA–vB would be two different polygon edges.
//! So on every ambiguous finest face we add one vertex per pair (at the middle of its two
//! crossings) and route the polygon edge that crosses that face through it: vA–f–vB.
//! Polygons with such a vertex are fanned around a new centre vertex (the edge's crossing),
//! never from a corner, which could bring back the doubled edge. Plain quads are split
//! along their shorter diagonal; a diagonal joins two leaves that share only (part of) the
//! polygon's edge line, and a leaf edge on that line longer than a finest edge holds one
//! crossing, so no other polygon can hold that diagonal.

use super::cell::{CASES, case_key, edge_id, other_axes};
use super::leaf::{BlockOut, CANDIDATE, CellOut, NO_VERT, OwnedEdge};
use super::octree::Grid;

/// Which vertex a polygon corner is, before it has a global index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ref {
    /// Vertex `vert` of the block with index `block` (in the octree's block list).
    Local {
        /// The block.
        block: u32,
        /// Its vertex.
        vert: u32,
    },
    /// The leaf that holds the block at these coordinates, which merged whole: which leaf
    /// that is, the blocks around it decide later.
    Candidate([i64; 3]),
    /// A vertex already given to the sink.
    Global(u32),
    /// The vertex of one pair of an ambiguous fine face on a seam (`refined.rs`): the
    /// face's normal axis and lowest corner on the fine lattice, and the pair.
    SeamFace(u8, [i64; 3], u8),
}

/// One corner of a polygon.
#[derive(Clone, Copy, Debug)]
pub struct Slot {
    /// Which vertex.
    pub r: Ref,
    /// Its position (unset for a candidate until it is resolved).
    pub pos: [f32; 3],
    /// True for a face vertex (on an ambiguous finest face), false for a leaf's vertex.
    pub face: bool,
}

/// The polygon of one crossing edge, wound counter-clockwise seen from outside.
#[derive(Clone, Copy, Debug)]
pub struct Polygon {
    /// Its corners, `len` of them.
    pub slots: [Slot; 8],
    /// How many.
    pub len: u8,
    /// The edge's crossing: the centre of a fan when the polygon has face vertices.
    pub centre: [f32; 3],
}

impl Polygon {
    /// The corners in use.
    pub fn corners(&self) -> &[Slot] {
        &self.slots[..self.len as usize]
    }

    /// The corners in use, to change.
    pub fn corners_mut(&mut self) -> &mut [Slot] {
        &mut self.slots[..self.len as usize]
    }
}

/// The 4 cells around an edge, as offsets along its two other axes, in counter-clockwise
/// order seen from the edge's positive end; and for each step to the next cell, the axis
/// crossed (0 = b, 1 = c) and which of the two cells has that face as its lower face.
pub const AROUND: [(i64, i64); 4] = [(-1, -1), (0, -1), (0, 0), (-1, 0)];
pub const STEPS: [(usize, usize); 4] = [(0, 1), (1, 2), (0, 2), (1, 3)];

/// A cell around a crossing edge, with its block.
#[derive(Clone, Copy)]
pub struct Around<'a> {
    /// The block's index (in the record list).
    pub block: u32,
    /// The block's coordinates (its own lattice's block units), for a candidate's leaf.
    pub coords: [i64; 3],
    /// The block's output.
    pub out: &'a BlockOut,
    /// The cell.
    pub cell: CellOut,
    /// The cell's own edge (`cell.rs` numbering) that the crossing edge lies on, which
    /// picks a finest cell's patch and its faces' pairs. For a coarse cell around a fine
    /// edge inside one of its faces (`refined.rs`), an edge of that face at an end of the
    /// curve the fine edge lies on.
    pub edge: usize,
    /// True for a cell of the finer lattice of a refined block. A face vertex joins two
    /// cells of one lattice only: a seam's fine faces are never ambiguous (`seam.rs`).
    pub fine: bool,
}

impl Around<'_> {
    fn leaf(&self) -> Slot {
        if self.cell.vert == CANDIDATE {
            return Slot {
                r: Ref::Candidate(self.coords),
                pos: [0.0; 3],
                face: false,
            };
        }
        let patch = if self.cell.finest {
            u32::from(CASES[case_key(self.cell.signs, self.cell.joined)].edge_patch[self.edge])
        } else {
            0
        };
        let vert = self.cell.vert + patch;
        Slot {
            r: Ref::Local {
                block: self.block,
                vert,
            },
            pos: self.out.vertices[vert as usize],
            face: false,
        }
    }
}

/// What lies at an offset from a block, for [`polygons`].
pub enum Near<'a> {
    /// A block with its cells: index, coordinates and output.
    Cells(u32, [i64; 3], &'a BlockOut),
    /// No block with cells (empty, full, or not built).
    Nothing,
    /// A block of the other lattice (`refined.rs`): an edge beside it is a seam's.
    Seam,
}

/// The polygons of a block's own edges, appended to `out`. `neighbour(d)` says what lies at
/// offset `d` (each component −1 or 0). An edge with a block of the other lattice around it
/// is a seam's and goes to `seams` instead, for `refined.rs`. Returns the number of edges
/// whose cells could not be found (zero unless a bug).
pub fn polygons<'a>(
    grid: &Grid,
    me: (u32, [i64; 3], &'a BlockOut),
    neighbour: impl Fn([i64; 3]) -> Near<'a>,
    out: &mut Vec<Polygon>,
    seams: &mut Vec<OwnedEdge>,
) -> usize {
    let b = grid.block as i64;
    let (me_block, me_coords, me_out) = me;
    let mut missing = 0;
    'edges: for edge in &me_out.owned {
        let a = edge.axis as usize;
        let (ab, ac) = other_axes(a);
        let mut cells: [Option<Around<'a>>; 4] = [None; 4];
        for (slot, &(db, dc)) in cells.iter_mut().zip(AROUND.iter()) {
            let mut l = edge.at.map(i64::from);
            l[ab] += db;
            l[ac] += dc;
            let mut off = [0i64; 3];
            for v in 0..3 {
                if l[v] < 0 {
                    off[v] = -1;
                    l[v] += b;
                }
            }
            let blk = if off == [0; 3] {
                Some((me_block, me_coords, me_out))
            } else {
                match neighbour(off) {
                    Near::Cells(i, c, o) => Some((i, c, o)),
                    Near::Nothing => None,
                    Near::Seam => {
                        seams.push(*edge);
                        continue 'edges;
                    }
                }
            };
            let idx = (l[0] + b * (l[1] + b * l[2])) as u16;
            *slot = blk.and_then(|(block, coords, o)| {
                o.cell(idx).map(|c| Around {
                    block,
                    coords,
                    out: o,
                    cell: *c,
                    edge: edge_id(a, usize::from(db == -1), usize::from(dc == -1)),
                    fine: false,
                })
            });
        }
        let [Some(c0), Some(c1), Some(c2), Some(c3)] = cells else {
            missing += 1;
            continue;
        };
        if let Some(poly) = polygon(a, [c0, c1, c2, c3], edge.pos, edge.start_inside, |_| None) {
            out.push(poly);
        }
    }
    missing
}

/// The polygon of a crossing edge along `axis` from the vertices of the leaves of the four
/// cells around it (in [`AROUND`] order), or `None` when the edge is no leaf's edge (inside
/// one leaf, or inside a face between two). `centre` is the crossing; `start_inside` the
/// sign of the edge's lower end, which sets the winding. A step from cell `q` to the next
/// between cells of two lattices crosses a seam's fine face; `seam_face(q)` gives that
/// face's vertex when it is ambiguous.
#[inline]
pub fn polygon(
    axis: usize,
    cells: [Around<'_>; 4],
    centre: [f32; 3],
    start_inside: bool,
    seam_face: impl Fn(usize) -> Option<Slot>,
) -> Option<Polygon> {
    let (ab, ac) = other_axes(axis);
    let placeholder = Slot {
        r: Ref::Global(0),
        pos: [0.0; 3],
        face: false,
    };
    let leaves: [Slot; 4] = std::array::from_fn(|q| cells[q].leaf());
    let same = |p: usize, q: usize| leaves[p].r == leaves[q].r;
    // Distinct leaves around the edge; the polygon starts after a change of leaf.
    let start = (0..4).find(|&q| !same(q, (q + 3) % 4))?;
    let distinct = (0..4).filter(|&q| !same(q, (q + 3) % 4)).count();
    if distinct < 3 {
        return None; // inside a face between two leaves
    }
    let mut poly = Polygon {
        slots: [placeholder; 8],
        len: 0,
        centre,
    };
    for step in 0..4 {
        let q = (start + step) % 4;
        let next = (q + 1) % 4;
        if step == 0 || !same(q, (q + 3) % 4) {
            poly.slots[poly.len as usize] = leaves[q];
            poly.len += 1;
        }
        if same(q, next) {
            continue;
        }
        // The face crossed from cell q to the next: a face vertex when it is an
        // ambiguous finest face between two different leaves.
        if cells[q].fine != cells[next].fine {
            if let Some(slot) = seam_face(q) {
                poly.slots[poly.len as usize] = slot;
                poly.len += 1;
            }
            continue;
        }
        if !(cells[q].cell.finest || cells[next].cell.finest) {
            continue;
        }
        let (step_axis, owner) = STEPS[q];
        let m = if step_axis == 0 { ab } else { ac };
        let o = &cells[owner];
        if o.cell.face[m] != NO_VERT {
            let pair = CASES[case_key(o.cell.signs, o.cell.joined)].lower_pair[m][o.edge];
            let vert = o.cell.face[m] + u32::from(pair.min(1));
            poly.slots[poly.len as usize] = Slot {
                r: Ref::Local {
                    block: o.block,
                    vert,
                },
                pos: o.out.vertices[vert as usize],
                face: true,
            };
            poly.len += 1;
        }
    }
    if !start_inside {
        poly.corners_mut().reverse();
    }
    Some(poly)
}

/// The triangles of a polygon whose corners all have global indices: a fan around the
/// centre (index `centre`) when it has a face vertex, else one triangle, or a quad split
/// along its shorter diagonal. Corners of one leaf that became neighbours (candidates that
/// merged) count once; a polygon left with fewer than three leaves has no triangles.
pub fn triangulate(
    corners: &[(u32, [f32; 3], bool)],
    centre: impl FnOnce() -> (u32, [f32; 3]),
    out: &mut Vec<([u32; 3], [[f32; 3]; 3])>,
) {
    let mut v: Vec<(u32, [f32; 3], bool)> = Vec::with_capacity(corners.len());
    for &c in corners {
        if v.last().map(|l| l.0) != Some(c.0) {
            v.push(c);
        }
    }
    while v.len() > 1 && v.first().map(|f| f.0) == v.last().map(|l| l.0) {
        v.pop();
    }
    let leaves = v.iter().filter(|c| !c.2).count();
    if leaves < 3 {
        return;
    }
    if v.iter().any(|c| c.2) {
        let (ci, cp) = centre();
        for q in 0..v.len() {
            let (a, b) = (v[q], v[(q + 1) % v.len()]);
            out.push(([ci, a.0, b.0], [cp, a.1, b.1]));
        }
        return;
    }
    match v.len() {
        3 => out.push(([v[0].0, v[1].0, v[2].0], [v[0].1, v[1].1, v[2].1])),
        4 => {
            let d02 = dist2(v[0].1, v[2].1);
            let d13 = dist2(v[1].1, v[3].1);
            let (p, q, r, s) = if d02 <= d13 {
                (0, 1, 2, 3)
            } else {
                (1, 2, 3, 0)
            };
            out.push(([v[p].0, v[q].0, v[r].0], [v[p].1, v[q].1, v[r].1]));
            out.push(([v[p].0, v[r].0, v[s].0], [v[p].1, v[r].1, v[s].1]));
        }
        _ => {
            // Not reachable from four cells; fan from the first corner to stay closed.
            for q in 1..v.len() - 1 {
                out.push(([v[0].0, v[q].0, v[q + 1].0], [v[0].1, v[q].1, v[q + 1].1]));
            }
        }
    }
}

fn dist2(p: [f32; 3], q: [f32; 3]) -> f32 {
    (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum()
}
