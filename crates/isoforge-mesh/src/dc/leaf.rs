//! A block's leaves: its finest cells merged, bottom up, into as few cells as the tolerance
//! and the topology allow (Ju et al. 2002, §4), and the vertices of the leaves that remain.
//!
//! Inside a block the octree is implicit: cell `(i, j, k)` has the Morton code that
//! interleaves the bits of i, j and k, and the cells of a node at level `l` are the codes
//! sharing its prefix. Only the cells with surface (a sign change on one of their edges) are
//! listed, sorted by code, so a node is a range of that list. A node becomes a leaf when its
//! children are leaves (or empty), the 27 signs pass [`topology::collapsible`], and its QEF
//! vertex, kept in its box, is within the tolerance of every crossing's plane and of the
//! surface itself (the field sampled there). A block that merges whole is a *candidate*: the
//! blocks around it decide later whether it merges further (see `merge.rs`).

use glam::DVec3;

use super::cell::{CASES, NONE, case_key, edge_corners, face_bit, other_axes};
use super::hermite::{Crossing, EdgeRef, corner_index};
use super::octree::Grid;
use super::qef::Qef;
use super::sampler::Sampler;
use super::topology;

/// No vertex.
pub const NO_VERT: u32 = u32::MAX;

/// Marks a cell of a block that merged whole: its vertex is the candidate's, decided later.
pub const CANDIDATE: u32 = u32::MAX - 1;

/// Vertices are kept this fraction of a finest cell inside their leaf, so that no two
/// leaves' vertices share a position: readers of STL (which has no shared vertices) weld by
/// position, and two of our vertices welded together would break manifoldness.
const INSET: f64 = 1e-3;

/// Newton steps that move a box-held vertex onto the surface: on planar faces one lands
/// exactly; the second serves curved ones.
const SURFACE_STEPS: usize = 2;

/// A vertex whose field normal is more than 120° (this cosine) from its cell's direction
/// from inside corners to outside ones is on the wrong side of a feature narrower than the
/// cell ([`Merger::facing_its_cell`]). The turned cube's corner cells reach −0.37, with
/// their vertices where they should be; the balls that came out inside out, −0.85 to −1.
const FACING_BACK: f64 = -0.5;

/// How far beyond its box a finest cell's vertex may go to where its planes meet, in
/// cells ([`Merger::beyond_its_box`]). At 0.3 neither lecture_coons nor the transforms
/// example held the tolerance at depth 8 (their creases run up to half a cell outside);
/// at 0.6 ripple_tile missed it by 1.75 tolerances at a corner of its region, which holds
/// (0.78) from 1.0 to 4.0 alike, as then do knurled_knob with 14 % fewer triangles and
/// everything else as before, but for curve_cyl's 14° wedge (2.75 -> 3.39, missed either
/// way).
const FREE_REACH: f64 = 1.0;

/// The planes must meet there within this, in cells: the root mean square of the distances
/// to them, per crossing. A looser fit (0.01) changed nothing on the fixtures.
const FREE_FIT: f64 = 0.003;

/// And the field must put the point within this of the surface, in cells (|F| / |∇F|).
const FREE_ON: f64 = 0.005;

/// Bisection steps for [`Merger::facing_its_cell`]'s crossing: to 1e-6 of a cell.
const CROSSING_STEPS: usize = 20;

/// How far leaves may merge.
#[derive(Clone, Copy, Debug)]
pub struct Merging {
    /// Largest distance allowed from a merged vertex to the plane of any crossing in its
    /// leaf; 0 turns merging off.
    pub plane: f64,
    /// Largest distance allowed from a merged vertex to the surface (|F| / |∇F| there).
    pub surface: f64,
}

impl Merging {
    /// No merging: every leaf a finest cell.
    pub const OFF: Merging = Merging {
        plane: 0.0,
        surface: 0.0,
    };

    /// True when cells may merge at all.
    pub fn on(&self) -> bool {
        self.plane > 0.0
    }

    /// The same merging with both distances `k` times as large (off stays off).
    pub fn scaled(self, k: f64) -> Merging {
        Merging {
            plane: self.plane * k,
            surface: self.surface * k,
        }
    }
}

/// A cell with surface: its leaf's vertex, and its own face vertices.
#[derive(Clone, Copy, Debug)]
pub struct CellOut {
    /// Local cell index within the block (`i + b (j + b k)`).
    pub cell: u16,
    /// Corner sign pattern.
    pub signs: u8,
    /// Its ambiguous faces that the solid runs across, as `cell::face_bit`s.
    pub joined: u8,
    /// True when the cell is a leaf itself (one vertex per patch); false when it lies in a
    /// merged leaf (one vertex for all of it).
    pub finest: bool,
    /// Block-local index of its leaf's first vertex, or [`CANDIDATE`].
    pub vert: u32,
    /// Per axis, block-local index of the first of the two vertices on its lower face of
    /// that axis when that face is ambiguous, else [`NO_VERT`].
    pub face: [u32; 3],
}

/// A sign-changing edge owned by a block (its start corner is in the block's half-open
/// range).
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

/// What a block that merged whole offers to its parent.
#[derive(Clone, Copy, Debug)]
pub struct Candidate {
    /// Its corner sign pattern.
    pub signs: u8,
    /// All its crossings' planes.
    pub qef: Qef,
    /// Its vertex.
    pub vertex: DVec3,
}

/// What a block contributes: its leaves' vertices, its cells with surface, its own edges.
#[derive(Clone, Debug, Default)]
pub struct BlockOut {
    /// Leaf and face vertices.
    pub vertices: Vec<[f32; 3]>,
    /// Cells with surface, sorted by `cell`.
    pub cells: Vec<CellOut>,
    /// Its sign-changing edges.
    pub owned: Vec<OwnedEdge>,
    /// Set when the whole block is one leaf.
    pub candidate: Option<Candidate>,
    /// The corner signs of the block (bit `c` for corner `c`, as cells number them).
    pub corners: u8,
}

impl BlockOut {
    /// The cell with local index `idx`, if it has surface.
    pub fn cell(&self, idx: u16) -> Option<&CellOut> {
        self.cells
            .binary_search_by_key(&idx, |c| c.cell)
            .ok()
            .map(|i| &self.cells[i])
    }
}

/// A cell with surface, as the merge sees it.
#[derive(Clone, Copy, Debug)]
struct Surface {
    /// Morton code within the block.
    code: u32,
    /// Local coordinates.
    at: [usize; 3],
    /// Corner sign pattern.
    signs: u8,
    /// Its ambiguous faces that the solid runs across ([`joined_faces`]).
    joined: u8,
    /// Its crossings: `crossing_ids[first..first + count]`.
    first: u32,
    count: u8,
}

/// A node's state in the bottom-up merge.
#[derive(Clone, Copy, Debug)]
enum Node {
    /// No surface in it.
    Homogeneous,
    /// One vertex for all of it. `vertex` is `None` for a finest cell (placed only if it
    /// stays a leaf).
    Leaf { qef: Qef, vertex: Option<DVec3> },
    /// Its children stay separate (or it is a finest cell with several patches).
    Split,
}

/// Reusable buffers for [`build`].
#[derive(Default)]
pub struct LeafScratch {
    surface: Vec<Surface>,
    crossing_ids: Vec<u32>,
    /// Per surface cell (in `surface` order), the block-local index of its leaf's first
    /// vertex and whether the leaf is the cell itself.
    leaf_of: Vec<(u32, bool)>,
    leaf_at: Vec<u32>,
    qefs: [Qef; 4],
}

/// Everything [`build`] reads about a block.
pub struct BlockInput<'a> {
    /// The lattice.
    pub grid: &'a Grid,
    /// Block coordinates.
    pub coords: [i64; 3],
    /// Agreed corner signs (1 = inside), `corner_index` order.
    pub signs: &'a [u8],
    /// `edge_slot[axis * s³ + corner]`: the crossing of that edge, or `u32::MAX`.
    pub edge_slot: &'a [u32],
    /// The sign-changing edges, in crossing order.
    pub edges: &'a [EdgeRef],
    /// Their crossings.
    pub crossings: &'a [Crossing],
    /// How far to merge.
    pub merging: Merging,
    /// Whether the block may become one leaf whose fate its neighbours decide (a
    /// [`Candidate`]); a refined block's fine blocks may not (`refined.rs`).
    pub whole: bool,
    /// The joined rule of a finest face that lies on a seam (`seam.rs`), by the cell's
    /// lowest lattice corner, the face's axis and side; `None` elsewhere, where the field
    /// decides.
    pub seam_joined: Option<&'a SeamJoined<'a>>,
    /// The block's faces that lie on a seam (bit `2 axis + side`): no leaf that touches one
    /// merges. Where a fine leaf met a coarse one across an ambiguous fine face, two of
    /// that face's edges had their polygons (the leaves on each side the same) and two did
    /// not, and the face's vertices were left with one polygon each (a random seam test).
    pub seam_sides: u8,
}

/// See [`BlockInput::seam_joined`].
pub type SeamJoined<'a> = dyn Fn([i64; 3], usize, usize) -> Option<bool> + Sync + 'a;

/// Interleaves the low `bits` bits of x, y, z (x lowest).
fn morton(at: [usize; 3], bits: u32) -> u32 {
    let mut code = 0u32;
    for bit in 0..bits {
        for (a, &v) in at.iter().enumerate() {
            code |= (((v >> bit) & 1) as u32) << (3 * bit + a as u32);
        }
    }
    code
}

/// Merges a block's cells into leaves and places their vertices; fills `out`. `root` is
/// the whole field (see [`joined_faces`]), `local` the field narrowed to the block.
pub fn build<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    (root, local): (&S::Local, &S::Local),
    input: &BlockInput<'_>,
    scratch: &mut LeafScratch,
    out: &mut BlockOut,
) {
    let grid = input.grid;
    let b = grid.block;
    let s = b + 1;
    let n = s * s * s;
    let bits = b.trailing_zeros();
    let base = input.coords.map(|c| c * b as i64);
    let origin = DVec3::from(grid.corner(base));
    let corner_sign = |l: [usize; 3]| input.signs[corner_index(s, l[0], l[1], l[2])];
    out.corners = (0..8)
        .map(|c| corner_sign([(c & 1) * b, (c >> 1 & 1) * b, (c >> 2 & 1) * b]) << c)
        .fold(0, |acc, bit| acc | bit);

    // The cells with surface, with their crossings, in Morton order.
    let sc = scratch;
    sc.surface.clear();
    sc.crossing_ids.clear();
    for k in 0..b {
        for j in 0..b {
            for i in 0..b {
                let mut pattern = 0u8;
                for c in 0..8 {
                    pattern |= corner_sign([i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)]) << c;
                }
                if pattern == 0 || pattern == 255 {
                    continue;
                }
                let first = sc.crossing_ids.len() as u32;
                for e in 0..12 {
                    if CASES[pattern as usize].edge_patch[e] == NONE {
                        continue;
                    }
                    let (start, _) = edge_corners(e);
                    let ci = corner_index(
                        s,
                        i + (start & 1),
                        j + (start >> 1 & 1),
                        k + (start >> 2 & 1),
                    );
                    let slot = input.edge_slot[(e / 4) * n + ci];
                    if (slot as usize) < input.crossings.len() {
                        sc.crossing_ids.push(slot);
                    }
                }
                let lattice = [base[0] + i as i64, base[1] + j as i64, base[2] + k as i64];
                let joined =
                    joined_faces(sampler, ev, root, grid, lattice, pattern, input.seam_joined);
                sc.surface.push(Surface {
                    code: morton([i, j, k], bits),
                    at: [i, j, k],
                    signs: pattern,
                    joined,
                    first,
                    count: (sc.crossing_ids.len() as u32 - first) as u8,
                });
            }
        }
    }
    sc.surface.sort_unstable_by_key(|c| c.code);
    sc.leaf_of.clear();
    sc.leaf_of.resize(sc.surface.len(), (NO_VERT, true));

    let mut m = Merger {
        sampler,
        ev,
        local,
        input,
        origin,
        base,
        surface: &sc.surface,
        crossing_ids: &sc.crossing_ids,
        leaf_of: &mut sc.leaf_of,
        qefs: &mut sc.qefs,
        vertices: &mut out.vertices,
    };
    let root = m.node(bits, 0, 0, sc.surface.len());
    match root {
        Node::Leaf { qef, vertex } if !sc.surface.is_empty() && input.whole => {
            let vertex = vertex.unwrap_or_else(|| m.finest_vertex(&sc.surface[0]));
            out.candidate = Some(Candidate {
                signs: out.corners,
                qef,
                vertex,
            });
            for l in sc.leaf_of.iter_mut() {
                *l = (CANDIDATE, false);
            }
        }
        // One leaf that stays one: its vertex is the block's own.
        Node::Leaf { vertex, .. } if !sc.surface.is_empty() => {
            let vertex = vertex.unwrap_or_else(|| m.finest_vertex(&sc.surface[0]));
            let vert = m.push_vertex(vertex);
            let finest = bits == 0;
            for l in sc.leaf_of.iter_mut() {
                *l = (vert, finest);
            }
        }
        Node::Leaf { .. } => {}
        Node::Homogeneous | Node::Split => {}
    }

    // Cells with their leaves, and face vertices on their ambiguous lower faces.
    let crossing_of = |at: [usize; 3], e: usize| {
        let (start, _) = edge_corners(e);
        let ci = corner_index(
            s,
            at[0] + (start & 1),
            at[1] + (start >> 1 & 1),
            at[2] + (start >> 2 & 1),
        );
        input
            .crossings
            .get(input.edge_slot[(e / 4) * n + ci] as usize)
    };
    for (cell, &(vert, finest)) in sc.surface.iter().zip(sc.leaf_of.iter()) {
        let case = &CASES[case_key(cell.signs, cell.joined)];
        let mut face = [NO_VERT; 3];
        for (axis, slot) in face.iter_mut().enumerate() {
            if !case.lower_ambiguous[axis] {
                continue;
            }
            *slot = out.vertices.len() as u32;
            // Each pair's vertex where its two crossings' tangent lines meet in the face,
            // kept in the face and moved onto the surface's curve there: the chord's middle
            // cut the corner of a crease crossing the face (the turned cube's face vertices
            // were 0.19 of a cell inside at depth 6 and 9).
            let (lo, hi) = face_box(grid, base, cell.at, axis);
            let mut placed = [DVec3::ZERO; 2];
            let mut middles = [DVec3::ZERO; 2];
            for (pair, (v, middle)) in placed.iter_mut().zip(middles.iter_mut()).enumerate() {
                let mut qef = Qef::new(origin);
                for e in 0..12 {
                    if usize::from(case.lower_pair[axis][e]) == pair
                        && let Some(x) = crossing_of(cell.at, e)
                    {
                        qef.add(x.pos, x.normal);
                    }
                }
                *middle = qef.mass_point();
                *v = onto_surface(
                    sampler,
                    ev,
                    local,
                    qef.solve_in(lo, hi),
                    (lo, hi),
                    Some(axis),
                );
            }
            // Two patches' vertices must stay two points, as written (f32) too: both can
            // step onto the same stretch of the surface's curve.
            let apart = placed[0].distance(placed[1]) > grid.cell * INSET
                && placed[0].as_vec3() != placed[1].as_vec3();
            let pick = if apart { placed } else { middles };
            for v in pick {
                out.vertices.push(v.as_vec3().to_array());
            }
        }
        let [i, j, k] = cell.at;
        out.cells.push(CellOut {
            cell: (i + b * (j + b * k)) as u16,
            signs: cell.signs,
            joined: cell.joined,
            finest,
            vert,
            face,
        });
    }
    out.cells.sort_unstable_by_key(|c| c.cell);

    // Edges inside a leaf, or inside a face between two leaves of this block, have no
    // polygon: leave them out now, while the block's leaves are at hand.
    sc.leaf_at.clear();
    sc.leaf_at.resize(b * b * b, NO_VERT);
    for c in &out.cells {
        // A finest cell is a leaf of its own: give it an id no other cell has.
        sc.leaf_at[c.cell as usize] = if c.finest {
            CANDIDATE - 1 - u32::from(c.cell)
        } else {
            c.vert
        };
    }
    for (x, edge) in input.crossings.iter().zip(input.edges) {
        let c = edge.corner as usize;
        let at = [c % s, (c / s) % s, c / (s * s)];
        if at.iter().all(|&v| v < b) {
            if inner_edge(&sc.leaf_at, b, at, edge.axis as usize) {
                continue;
            }
            out.owned.push(OwnedEdge {
                axis: edge.axis,
                at: at.map(|v| v as u8),
                start_inside: input.signs[c] == 1,
                pos: x.pos.as_vec3().to_array(),
            });
        }
    }
}

/// A vertex that its box held back from where its planes meet, moved along the field's
/// gradient towards the surface as far as the box allows (along the plane across `flat`
/// only, when given). Where a crease runs just outside a cell whose crossings lie on both
/// of its faces, the box-held QEF point sits between the two planes, inside the solid: on
/// the turned cube (fixtures/flat) at depth 7 such vertices were 0.092 of a cell from the
/// surface, measured exactly, and 0.011 after these steps. A step is kept only when it
/// brings |F| down.
fn onto_surface<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    local: &S::Local,
    x: DVec3,
    (lo, hi): (DVec3, DVec3),
    flat: Option<usize>,
) -> DVec3 {
    let mut field = |p: DVec3| {
        let g = sampler.grad(ev, local, p.to_array());
        let mut grad = DVec3::new(g[1], g[2], g[3]);
        if let Some(a) = flat {
            grad[a] = 0.0;
        }
        (g[0], grad)
    };
    let (mut x, (mut f, mut grad)) = (x, field(x));
    for _ in 0..SURFACE_STEPS {
        let slope2 = grad.length_squared();
        if !(f.is_finite() && slope2 > 0.0 && slope2.is_finite()) || f == 0.0 {
            break;
        }
        let next = (x - grad * (f / slope2)).clamp(lo, hi);
        let (nf, ngrad) = field(next);
        let better = nf.abs() < f.abs();
        if !next.is_finite() || !better {
            break;
        }
        (x, f, grad) = (next, nf, ngrad);
    }
    x
}

/// The ambiguous faces of the cell with lowest corner `at` (lattice coordinates) and corner
/// signs `signs` that the solid runs across: those whose middle the field puts inside.
///
/// Marching cubes' fixed rule keeps an ambiguous face's inside corners apart. Across a
/// solid thinner than a cell that lies diagonally on a face (a gyroid's sheet, a wedge
/// between a ball and a sheet), that pinches the solid in two at the face, and the
/// face's vertices, each held between the crossings of both sides, sat half a cell inside
/// it: on gyroid_sphere at depth 8 all 684 ambiguous faces had their middle inside, and
/// 678 of them such a vertex more than a tenth of a cell off. The middle is read from the
/// whole field (`root`), not the block's narrowed one, so both cells sharing the face,
/// in one block or two, decide alike.
fn joined_faces<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    root: &S::Local,
    grid: &Grid,
    at: [i64; 3],
    signs: u8,
    seam: Option<&SeamJoined<'_>>,
) -> u8 {
    let ambiguous = CASES[usize::from(signs)].ambiguous;
    let mut joined = 0;
    for n in 0..3 {
        for side in 0..2 {
            let bit = face_bit(n, side);
            if ambiguous & bit == 0 {
                continue;
            }
            if let Some(rule) = seam.and_then(|f| f(at, n, side)) {
                if rule {
                    joined |= bit;
                }
                continue;
            }
            let mut lo = at;
            lo[n] += side as i64;
            if sampler.grad(ev, root, face_middle(grid, lo, n))[0] < 0.0 {
                joined |= bit;
            }
        }
    }
    joined
}

/// The middle of the lattice face normal to `n` whose lowest corner is `lo`: where the
/// joined rule reads the field, here and on seams (`refined.rs`), so both read alike.
pub fn face_middle(grid: &Grid, lo: [i64; 3], n: usize) -> [f64; 3] {
    let mut middle = grid.corner(lo);
    let (b, c) = other_axes(n);
    middle[b] += 0.5 * grid.cell;
    middle[c] += 0.5 * grid.cell;
    middle
}

/// The square of the lower face of `axis` of the cell at local `at` of the block whose
/// lowest cell is `base`, inset like a vertex box, as a box flat along `axis`.
fn face_box(grid: &Grid, base: [i64; 3], at: [usize; 3], axis: usize) -> (DVec3, DVec3) {
    let lo = grid.corner([0, 1, 2].map(|a| base[a] + at[a] as i64));
    let (mut vlo, mut vhi) = grid.vertex_box(lo, grid.cell, grid.cell * INSET);
    vlo[axis] = lo[axis];
    vhi[axis] = lo[axis];
    (DVec3::from(vlo), DVec3::from(vhi))
}

/// True when the four cells around the edge along `axis` from local corner `at` all lie in
/// this block and in fewer than three leaves (`leaf_at` holds a leaf id per cell), so the
/// edge is no leaf's edge.
fn inner_edge(leaf_at: &[u32], b: usize, at: [usize; 3], axis: usize) -> bool {
    let (ab, ac) = other_axes(axis);
    if at[ab] == 0 || at[ac] == 0 {
        return false;
    }
    let id = |db: usize, dc: usize| {
        let mut l = at;
        l[ab] -= db;
        l[ac] -= dc;
        leaf_at[l[0] + b * (l[1] + b * l[2])]
    };
    // Around the edge in order: the leaf changes at most twice when there are two leaves.
    let ids = [id(1, 1), id(0, 1), id(0, 0), id(1, 0)];
    let changes = (0..4).filter(|&q| ids[q] != ids[(q + 3) % 4]).count();
    changes < 3
}

/// The bottom-up merge over one block.
struct Merger<'a, 'b, S: Sampler> {
    sampler: &'a S,
    ev: &'a mut S::Evals,
    local: &'a S::Local,
    input: &'a BlockInput<'b>,
    origin: DVec3,
    base: [i64; 3],
    surface: &'a [Surface],
    crossing_ids: &'a [u32],
    leaf_of: &'a mut Vec<(u32, bool)>,
    qefs: &'a mut [Qef; 4],
    vertices: &'a mut Vec<[f32; 3]>,
}

impl<S: Sampler> Merger<'_, '_, S> {
    /// The node at `level` whose cells have codes `prefix << 3 level ..`, holding the
    /// surface cells `from..to`.
    fn node(&mut self, level: u32, prefix: u32, from: usize, to: usize) -> Node {
        if from == to {
            return Node::Homogeneous;
        }
        if level == 0 {
            return self.finest(from);
        }
        let shift = 3 * (level - 1);
        let mut children = [Node::Homogeneous; 8];
        let mut ranges = [(0usize, 0usize); 8];
        let mut start = from;
        for (c, child) in children.iter_mut().enumerate() {
            let code = ((prefix << 3) | c as u32) << shift;
            let next = code + (1 << shift);
            let end = start + self.surface[start..to].partition_point(|x| x.code < next);
            ranges[c] = (start, end);
            *child = self.node(level - 1, (prefix << 3) | c as u32, start, end);
            start = end;
        }
        let merged = if children.iter().any(|c| matches!(c, Node::Split)) {
            None
        } else {
            self.try_merge(level, prefix, &children, from, to)
        };
        match merged {
            Some(node) => node,
            None => {
                // The children stay: each leaf child becomes a leaf of the block.
                for (c, child) in children.iter().enumerate() {
                    if let Node::Leaf { vertex, .. } = child {
                        let (a, z) = ranges[c];
                        let v = match vertex {
                            Some(v) => *v,
                            None => {
                                let cell = self.surface[a];
                                self.finest_vertex(&cell)
                            }
                        };
                        let vert = self.push_vertex(v);
                        for l in &mut self.leaf_of[a..z] {
                            *l = (vert, level - 1 == 0);
                        }
                    }
                }
                Node::Split
            }
        }
    }

    /// A finest cell: a leaf candidate with one patch, or a leaf of its own with several.
    fn finest(&mut self, at: usize) -> Node {
        let cell = self.surface[at];
        let case = &CASES[case_key(cell.signs, cell.joined)];
        // A joined face pairs its edges unlike the patterns `topology::collapsible` knows:
        // such a cell never merges, and neither does its neighbour across the face.
        if case.patches == 1 && cell.joined == 0 {
            let mut qef = Qef::new(self.origin);
            for &id in self.crossings(&cell) {
                let x = &self.input.crossings[id as usize];
                qef.add(x.pos, x.normal);
            }
            return Node::Leaf { qef, vertex: None };
        }
        // Several patches, or a joined face: one vertex per patch, placed now (this cell
        // never merges).
        let vert = self.vertices.len() as u32;
        self.place_patches(&cell);
        self.leaf_of[at] = (vert, true);
        Node::Split
    }

    fn crossings(&self, cell: &Surface) -> &[u32] {
        &self.crossing_ids[cell.first as usize..cell.first as usize + cell.count as usize]
    }

    /// The box of the node at `level` with Morton prefix `prefix`, inset, in absolute
    /// coordinates.
    fn node_box(&self, level: u32, lo_cell: [usize; 3]) -> (DVec3, DVec3) {
        let grid = self.input.grid;
        let lo = DVec3::from(grid.corner([0, 1, 2].map(|a| self.base[a] + lo_cell[a] as i64)));
        let size = grid.cell * f64::from(1u32 << level);
        let (lo, hi) = grid.vertex_box(lo.to_array(), size, grid.cell * INSET);
        (DVec3::from(lo), DVec3::from(hi))
    }

    fn push_vertex(&mut self, v: DVec3) -> u32 {
        self.vertices.push(v.as_vec3().to_array());
        (self.vertices.len() - 1) as u32
    }

    /// The vertex of a finest cell with one patch.
    fn finest_vertex(&mut self, cell: &Surface) -> DVec3 {
        let mut qef = Qef::new(self.origin);
        for &id in self.crossings(cell) {
            let x = &self.input.crossings[id as usize];
            qef.add(x.pos, x.normal);
        }
        let (lo, hi) = self.node_box(0, cell.at);
        let (x, held) = qef.solve_held(lo, hi);
        let x = match held {
            Some(free) => match self.beyond_its_box(&qef, free, lo, hi) {
                Some(free) => free,
                None => self.onto_surface(x, lo, hi),
            },
            None => x,
        };
        self.facing_its_cell(x, cell, (lo, hi))
    }

    /// `free`, the free QEF point of a box-held finest cell, where the planes meet just
    /// beyond the box (within [`FREE_REACH`]), meet there well ([`FREE_FIT`]) and the field
    /// puts that point on the surface ([`FREE_ON`]); `None` otherwise, and always at
    /// `--tolerance 0`, whose uniform mesh keeps every vertex in its cell.
    ///
    /// Where a crease or a corner runs just outside a cell whose crossings lie on both of
    /// its faces, the box holds the vertex on the cell's wall, off the crease, and the
    /// chords from it cut the crease's corner: by 2.2 tolerances on lecture_coons at depth
    /// 8, and by 3.1 on the transforms example. fidget leaves such vertices where their
    /// planes meet, in or out of the cell. Out of the cell a vertex may end up beside its
    /// neighbour's, so the refiner (which looks at every chord longer than a cell, and
    /// keeps vertices from landing on each other) is what makes it safe, and the uniform
    /// mesh, which has no refiner, does not do it.
    fn beyond_its_box(&mut self, qef: &Qef, free: DVec3, lo: DVec3, hi: DVec3) -> Option<DVec3> {
        if !self.input.merging.on() {
            return None;
        }
        let grid = self.input.grid;
        let cell = grid.cell;
        let out = (lo - free).max(free - hi).max_element();
        let in_region =
            free.cmpge(DVec3::from(grid.origin)).all() && free.cmple(DVec3::from(grid.top)).all();
        let within = out.is_finite() && out <= FREE_REACH * cell;
        if !(within && in_region) {
            return None;
        }
        let fit = FREE_FIT * cell;
        if qef.error(free) > f64::from(qef.count()) * fit * fit {
            return None;
        }
        let g = self.sampler.grad(self.ev, self.local, free.to_array());
        let slope = DVec3::new(g[1], g[2], g[3]).length();
        let on = g[0].abs() <= FREE_ON * cell * slope;
        on.then_some(free)
    }

    /// The vertex `x`, or, where the field at `x` faces back towards the cell's inside
    /// corners, the point where the surface crosses the line from their middle towards the
    /// outside corners' middle.
    ///
    /// Where a ball narrower than a cell holds one lattice corner, the cell beside it that
    /// holds most of the ball has crossings on the ball's far side, whose tangent planes
    /// meet far outside the cell; its vertex lands in the corner (held there by the box, or
    /// where the near planes meet), on the ball's near side, and the triangles there face
    /// into the ball (a random CSG case at depth 4: a ball 0.98 cells wide was
    /// meshed to 1% of its volume, half of its triangles facing in, and the refiner turned
    /// it inside out). The surface between the corners is the cell's own piece.
    fn facing_its_cell(&mut self, x: DVec3, cell: &Surface, (lo, hi): (DVec3, DVec3)) -> DVec3 {
        let grid = self.input.grid;
        let corner = DVec3::from(grid.corner([0, 1, 2].map(|a| self.base[a] + cell.at[a] as i64)));
        let (mut inner, mut outer, mut count) = (DVec3::ZERO, DVec3::ZERO, 0u32);
        for c in 0..8u8 {
            let p = corner
                + DVec3::new(
                    f64::from(c & 1),
                    f64::from(c >> 1 & 1),
                    f64::from(c >> 2 & 1),
                ) * grid.cell;
            if cell.signs >> c & 1 == 1 {
                inner += p;
                count += 1;
            } else {
                outer += p;
            }
        }
        if count == 0 || count == 8 {
            return x;
        }
        let (a, b) = (inner / f64::from(count), outer / f64::from(8 - count));
        let mut field = |p: DVec3| self.sampler.grad(self.ev, self.local, p.to_array());
        let g = field(x);
        let n = DVec3::new(g[1], g[2], g[3]);
        // A NaN gradient compares as nothing, and says no, too.
        let back = FACING_BACK * n.length() * (b - a).length();
        if n.dot(b - a).partial_cmp(&back) != Some(std::cmp::Ordering::Less) {
            return x;
        }
        // On, from the inside corners' middle past the outside corners' to the cell's wall
        // (the outside corners' middle may be inside the ball).
        let dir = b - a;
        let far = corner + DVec3::splat(grid.cell);
        let wall = [0, 1, 2]
            .into_iter()
            .filter(|&k| dir[k] != 0.0)
            .map(|k| {
                let to = if dir[k] > 0.0 { far[k] } else { corner[k] };
                (to - a[k]) / dir[k]
            })
            .fold(f64::INFINITY, f64::min);
        let b = a + dir * wall;
        let (fa, fb) = (field(a)[0], field(b)[0]);
        let brackets = wall.is_finite() && fa < 0.0 && fb > 0.0;
        if !brackets {
            return x;
        }
        let (mut a, mut b) = (a, b);
        for _ in 0..CROSSING_STEPS {
            let m = (a + b) * 0.5;
            if field(m)[0] < 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        ((a + b) * 0.5).clamp(lo, hi)
    }

    /// A box-held vertex moved onto the surface (see [`onto_surface`]).
    fn onto_surface(&mut self, x: DVec3, lo: DVec3, hi: DVec3) -> DVec3 {
        onto_surface(self.sampler, self.ev, self.local, x, (lo, hi), None)
    }

    /// One vertex per patch of a finest cell, each kept in the cell; all at their patches'
    /// mass points if two would coincide (distinct patches must stay distinct points).
    fn place_patches(&mut self, cell: &Surface) {
        let case = &CASES[case_key(cell.signs, cell.joined)];
        let patches = case.patches as usize;
        for q in self.qefs.iter_mut().take(patches) {
            q.reset(self.origin);
        }
        let (s, n) = (self.input.grid.block + 1, {
            let s = self.input.grid.block + 1;
            s * s * s
        });
        for e in 0..12 {
            let p = case.edge_patch[e];
            if p == NONE {
                continue;
            }
            let (start, _) = edge_corners(e);
            let ci = corner_index(
                s,
                cell.at[0] + (start & 1),
                cell.at[1] + (start >> 1 & 1),
                cell.at[2] + (start >> 2 & 1),
            );
            if let Some(x) = self
                .input
                .crossings
                .get(self.input.edge_slot[(e / 4) * n + ci] as usize)
            {
                self.qefs[p as usize].add(x.pos, x.normal);
            }
        }
        let (lo, hi) = self.node_box(0, cell.at);
        let start = self.vertices.len();
        for p in 0..patches {
            let (v, held) = self.qefs[p].solve_held(lo, hi);
            let v = if held.is_some() {
                self.onto_surface(v, lo, hi)
            } else {
                v
            };
            self.vertices.push(v.as_vec3().to_array());
        }
        let placed = &self.vertices[start..];
        let clash =
            (0..placed.len()).any(|i| (i + 1..placed.len()).any(|j| placed[i] == placed[j]));
        if clash {
            self.vertices.truncate(start);
            for q in self.qefs.iter().take(patches) {
                let v = q.mass_point().clamp(lo, hi);
                self.vertices.push(v.as_vec3().to_array());
            }
        }
    }

    /// Merges the children of a node into one leaf, if the topology and the tolerance
    /// allow.
    fn try_merge(
        &mut self,
        level: u32,
        prefix: u32,
        children: &[Node; 8],
        from: usize,
        to: usize,
    ) -> Option<Node> {
        if !self.input.merging.on() {
            return None;
        }
        // The node's lowest cell, from its Morton prefix.
        let code = prefix << (3 * level);
        let mut lo_cell = [0usize; 3];
        for bit in 0..self.input.grid.block.trailing_zeros() {
            for (a, v) in lo_cell.iter_mut().enumerate() {
                *v |= ((code >> (3 * bit + a as u32)) & 1) as usize * (1 << bit);
            }
        }
        let size = 1usize << level;
        let touches = self.input.seam_sides != 0
            && (0..3).any(|a| {
                let sides = self.input.seam_sides >> (2 * a);
                (sides & 1 == 1 && lo_cell[a] == 0)
                    || (sides & 2 == 2 && lo_cell[a] + size == self.input.grid.block)
            });
        if touches {
            return None;
        }
        let half = 1usize << (level - 1);
        let s = self.input.grid.block + 1;
        let mut signs27 = 0u32;
        for k in 0..3 {
            for j in 0..3 {
                for i in 0..3 {
                    let l = [
                        lo_cell[0] + i * half,
                        lo_cell[1] + j * half,
                        lo_cell[2] + k * half,
                    ];
                    if self.input.signs[corner_index(s, l[0], l[1], l[2])] == 1 {
                        signs27 |= 1 << (i + 3 * j + 9 * k);
                    }
                }
            }
        }
        if !topology::collapsible(signs27) {
            return None;
        }
        let mut qef = Qef::new(self.origin);
        for child in children {
            if let Node::Leaf { qef: q, .. } = child {
                qef.merge(q);
            }
        }
        let (lo, hi) = self.node_box(level, lo_cell);
        let x = qef.solve_in(lo, hi);
        // Every crossing's plane within the tolerance of the vertex.
        let limit = self.input.merging.plane;
        for cell in &self.surface[from..to] {
            for &id in self.crossings(cell) {
                let c = &self.input.crossings[id as usize];
                if c.normal.dot(x - c.pos).abs() > limit {
                    return None;
                }
            }
        }
        // And the vertex on the surface, as the field says.
        let g = self.sampler.grad(self.ev, self.local, x.to_array());
        let slope = DVec3::new(g[1], g[2], g[3]).length();
        let distance = g[0].abs() / slope;
        if distance.is_nan() || distance > self.input.merging.surface {
            return None;
        }
        Some(Node::Leaf {
            qef,
            vertex: Some(x),
        })
    }
}
