//! Vertices per patch and polygons per sign-changing edge (Ju et al. 2002; patches as in
//! Nielson 2004 and Schaefer, Ju, Warren 2007).
//!
//! Each cell gets one vertex per patch, placed by its QEF and clamped to the cell. Each
//! sign-changing lattice edge gets the polygon through the patch vertices of its 4 cells.
//!
//! Why this is always a closed 2-manifold: the polygons are the dual of the marching-cubes
//! surface that the same face pairing defines (patch ↔ vertex, crossing ↔ polygon, face
//! segment ↔ polygon edge). That surface is closed and every patch is one cycle, so every
//! dual edge borders exactly two polygons and every vertex's polygons form one fan. The
//! one way the dual fails as a triangle mesh is when two segments join the same two
//! patches: both lie on one face shared by cells A and B, which is then ambiguous (four
//! crossings, two pairs), and vA–vB would be two different polygon edges, i.e. an edge of
//! four triangles. So on every ambiguous face we add one vertex per pair (at the middle of
//! its two crossings) and route the polygon edge that crosses that face through it:
//! vA–f–vB. Polygons with such a vertex are fanned around a new centre vertex (the edge's
//! crossing), never from a corner, which could bring back the doubled edge. Plain quads
//! are split along their shorter diagonal; a diagonal joins two cells that share only the
//! polygon's lattice edge, so no other polygon can hold it.

use glam::DVec3;

use super::cell::{CASES, NONE, edge_corners, edge_id, other_axes};
use super::hermite::{Crossing, corner_index};
use super::octree::Grid;
use super::qef::Qef;

/// No vertex.
const NO_VERT: u32 = u32::MAX;

/// Bit marking a vertex index as one of the block's polygon centres (remapped at the end).
pub const CENTRE_FLAG: u32 = 1 << 31;

/// A cell with surface: where its vertices are.
#[derive(Clone, Copy, Debug)]
pub struct CellOut {
    /// Local cell index within the block.
    pub cell: u16,
    /// Corner sign pattern.
    pub signs: u8,
    /// Block-local index of its first patch vertex.
    pub vert: u32,
    /// Per axis, block-local index of the first of the two vertices on its lower face of
    /// that axis when the face is ambiguous, else `NO_VERT`.
    pub face: [u32; 3],
}

/// A sign-changing edge owned by a block (its start corner is in the block's half-open range).
#[derive(Clone, Copy, Debug)]
pub struct OwnedEdge {
    /// The axis.
    pub axis: u8,
    /// The start corner's local coordinates.
    pub at: [u8; 3],
    /// True when the start corner is inside.
    pub start_inside: bool,
    /// The crossing.
    pub pos: [f32; 3],
}

/// What a block contributes.
#[derive(Clone, Debug, Default)]
pub struct BlockOut {
    /// Patch and face vertices.
    pub vertices: Vec<[f32; 3]>,
    /// Cells with surface, sorted by `cell`.
    pub cells: Vec<CellOut>,
    /// Its sign-changing edges.
    pub owned: Vec<OwnedEdge>,
}

impl BlockOut {
    fn cell(&self, idx: u16) -> Option<&CellOut> {
        self.cells
            .binary_search_by_key(&idx, |c| c.cell)
            .ok()
            .map(|i| &self.cells[i])
    }
}

/// Places the vertices of every cell of a block, and lists the block's own edges.
#[allow(clippy::too_many_arguments)]
pub fn cell_vertices(
    grid: &Grid,
    coords: [i64; 3],
    signs: &[u8],
    edge_slot: &[u32],
    edges: &[super::hermite::EdgeRef],
    crossings: &[Crossing],
    qefs: &mut [Qef; 4],
    out: &mut BlockOut,
) {
    let b = grid.block;
    let s = b + 1;
    let n = s * s * s;
    let base = coords.map(|c| c * b as i64);
    for k in 0..b {
        for j in 0..b {
            for i in 0..b {
                let mut pattern = 0u8;
                for c in 0..8 {
                    let ci = corner_index(s, i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1));
                    pattern |= signs[ci] << c;
                }
                let case = &CASES[pattern as usize];
                if case.patches == 0 {
                    continue;
                }
                let crossing_of = |e: usize| {
                    let (start, _) = edge_corners(e);
                    let ci = corner_index(
                        s,
                        i + (start & 1),
                        j + (start >> 1 & 1),
                        k + (start >> 2 & 1),
                    );
                    crossings.get(edge_slot[(e / 4) * n + ci] as usize)
                };
                for q in qefs.iter_mut().take(case.patches as usize) {
                    q.clear();
                }
                for e in 0..12 {
                    let p = case.edge_patch[e];
                    if p != NONE
                        && let Some(x) = crossing_of(e)
                    {
                        qefs[p as usize].add(x.pos, x.normal);
                    }
                }
                let lo = grid.corner([base[0] + i as i64, base[1] + j as i64, base[2] + k as i64]);
                let vert = out.vertices.len() as u32;
                place_vertices(
                    grid,
                    lo.into(),
                    &qefs[..case.patches as usize],
                    &mut out.vertices,
                );
                let mut face = [NO_VERT; 3];
                for (axis, slot) in face.iter_mut().enumerate() {
                    if !case.lower_ambiguous[axis] {
                        continue;
                    }
                    *slot = out.vertices.len() as u32;
                    for pair in 0..2u8 {
                        let mut sum = DVec3::ZERO;
                        let mut count = 0.0;
                        for e in 0..12 {
                            if case.lower_pair[axis][e] == pair
                                && let Some(x) = crossing_of(e)
                            {
                                sum += x.pos;
                                count += 1.0;
                            }
                        }
                        let count: f64 = if count > 0.0 { count } else { 1.0 };
                        out.vertices.push((sum / count).as_vec3().to_array());
                    }
                }
                out.cells.push(CellOut {
                    cell: (i + b * (j + b * k)) as u16,
                    signs: pattern,
                    vert,
                    face,
                });
            }
        }
    }
    for (x, edge) in crossings.iter().zip(edges) {
        let c = edge.corner as usize;
        let at = [c % s, (c / s) % s, c / (s * s)];
        if at.iter().all(|&v| v < b) {
            out.owned.push(OwnedEdge {
                axis: edge.axis,
                at: at.map(|v| v as u8),
                start_inside: signs[c] == 1,
                pos: x.pos.as_vec3().to_array(),
            });
        }
    }
}

/// Vertices are kept this fraction of a cell inside their cell, so that no two cells'
/// vertices share a position: readers of STL (which has no shared vertices) weld by
/// position, and two of our vertices welded together would break manifoldness.
const INSET: f64 = 1e-3;

/// One vertex per patch: the QEF minimizer kept inside the cell. In a cell with several
/// patches a minimizer outside the cell falls back to its patch's mass point, and so do
/// all of them if two would coincide: distinct patches must stay distinct points.
fn place_vertices(grid: &Grid, lo: DVec3, qefs: &[Qef], out: &mut Vec<[f32; 3]>) {
    let inset = grid.cell * INSET;
    let (min, max) = (lo + inset, lo + grid.cell - inset);
    // Per axis with f64::clamp, which (unlike glam's max-then-min) keeps a -0.0.
    let clamp = |v: DVec3| [0, 1, 2].map(|a| v[a].clamp(min[a], max[a]) as f32);
    let inside = |v: DVec3| v.cmpge(min).all() && v.cmple(max).all();
    let start = out.len();
    for q in qefs {
        let v = q.solve();
        let v = if qefs.len() > 1 && !inside(v) {
            q.mass_point()
        } else {
            v
        };
        out.push(clamp(v));
    }
    let placed = &out[start..];
    let clash = (0..placed.len()).any(|i| (i + 1..placed.len()).any(|j| placed[i] == placed[j]));
    if clash {
        out.truncate(start);
        out.extend(qefs.iter().map(|q| clamp(q.mass_point())));
    }
}

/// The 4 cells around an edge, as offsets along its two other axes, in counter-clockwise
/// order seen from the edge's positive end; and for each step to the next cell, the axis
/// crossed (0 = b, 1 = c) and which of the two cells has that face as its lower face.
const AROUND: [(i64, i64); 4] = [(-1, -1), (0, -1), (0, 0), (-1, 0)];
const STEPS: [(usize, usize); 4] = [(0, 1), (1, 2), (0, 2), (1, 3)];

/// Emits the polygons of a block's own edges as triangles. Vertex indices are global
/// for patch and face vertices (via `offsets`), and `CENTRE_FLAG | i` for the i-th entry
/// of `centres`. `neighbour(d)` gives the index of the ambiguous block at offset d.
/// Returns the number of edges whose cells could not be found (zero unless a bug).
pub fn emit(
    grid: &Grid,
    blocks: &[BlockOut],
    offsets: &[u32],
    me: usize,
    neighbour: impl Fn([i64; 3]) -> Option<usize>,
    tris: &mut Vec<[u32; 3]>,
    centres: &mut Vec<[f32; 3]>,
) -> usize {
    let b = grid.block as i64;
    let mut missing = 0;
    for edge in &blocks[me].owned {
        let a = edge.axis as usize;
        let (ab, ac) = other_axes(a);
        let mut cells = [(
            0usize,
            CellOut {
                cell: 0,
                signs: 0,
                vert: 0,
                face: [NO_VERT; 3],
            },
        ); 4];
        let mut found = true;
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
                Some(me)
            } else {
                neighbour(off)
            };
            let idx = (l[0] + b * (l[1] + b * l[2])) as u16;
            match blk.and_then(|bi| blocks[bi].cell(idx).map(|c| (bi, *c))) {
                Some(x) => *slot = x,
                None => found = false,
            }
        }
        if !found {
            missing += 1;
            continue;
        }
        let local_edge =
            |(db, dc): (i64, i64)| edge_id(a, usize::from(db == -1), usize::from(dc == -1));
        let mut poly: [(u32, [f32; 3]); 8] = [(0, [0.0; 3]); 8];
        let mut len = 0;
        let mut has_face = false;
        for q in 0..4 {
            let (bi, c) = cells[q];
            let case = &CASES[c.signs as usize];
            let patch = case.edge_patch[local_edge(AROUND[q])];
            let local = c.vert + u32::from(patch);
            poly[len] = (offsets[bi] + local, blocks[bi].vertices[local as usize]);
            len += 1;
            let (step_axis, owner) = STEPS[q];
            let m = if step_axis == 0 { ab } else { ac };
            let (obi, oc) = cells[owner];
            if oc.face[m] != NO_VERT {
                let pair = CASES[oc.signs as usize].lower_pair[m][local_edge(AROUND[owner])];
                let local = oc.face[m] + u32::from(pair.min(1));
                poly[len] = (offsets[obi] + local, blocks[obi].vertices[local as usize]);
                len += 1;
                has_face = true;
            }
        }
        let poly = &mut poly[..len];
        if !edge.start_inside {
            poly.reverse();
        }
        if has_face {
            let centre = CENTRE_FLAG | centres.len() as u32;
            centres.push(edge.pos);
            for q in 0..len {
                tris.push([centre, poly[q].0, poly[(q + 1) % len].0]);
            }
        } else {
            let d02 = dist2(poly[0].1, poly[2].1);
            let d13 = dist2(poly[1].1, poly[3].1);
            let v = [poly[0].0, poly[1].0, poly[2].0, poly[3].0];
            if d02 <= d13 {
                tris.push([v[0], v[1], v[2]]);
                tris.push([v[0], v[2], v[3]]);
            } else {
                tris.push([v[1], v[2], v[3]]);
                tris.push([v[1], v[3], v[0]]);
            }
        }
    }
    missing
}

fn dist2(p: [f32; 3], q: [f32; 3]) -> f32 {
    (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum()
}
