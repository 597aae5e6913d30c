//! The last stage before the sink: vertices moved onto the surface, and triangles that stray
//! from it split until they keep within the tolerance.
//!
//! Two places where dual contouring's own output misses the surface by more than the
//! tolerance, found with `isoforge check --against` on the classic fixtures:
//!
//! * **Creases.** A crease (two surfaces meeting at an angle, as where the spheres of
//!   stacked_sphere_circle meet) runs across the lattice, and a polygon whose corners sit
//!   on both sides of it cuts the corner: at depth 8 such triangles missed the surface by
//!   3.4 tolerances. The vertices are where they should be; the chords between them are not.
//! * **Features smaller than a cell.** A finest cell's vertex stays in its cell (that keeps
//!   the mesh free of folds; it leaves the cell only for a crease or corner just beyond,
//!   where its planes meet on the surface), and where the surface bends within a cell it
//!   may sit a third of a cell off the surface (sinus_bugs).
//!
//! So each vertex whose distance by the field (|F| / |∇F|) is over half the tolerance is
//! moved onto the surface by Newton steps along the gradient, if that takes it less than
//! [`REACH`] cells. Each edge whose middle is farther than [`SPLIT_SHARE`] of the tolerance
//! from the surface (by that reading, or, beside a crease, by where Newton steps take it:
//! [`Refiner::strays`]) is split: at its middle moved onto the surface the same way, or where
//! two tangent planes meet (the crease, to first order: the ends' planes, or the plane where
//! the middle landed with either end's), whichever leaves the straighter halves and is
//! neither near an end nor within [`APART`] cells of another new vertex; a triangle whose
//! edges all hold but whose centre does not gets a vertex there, unless a piece would face
//! against the field at its corners (a fold); its pieces get no centre again unless all
//! their sides are long ([`LONG_CELLS`]). Splitting goes on in the
//! pieces (longest split edge first, as in Rivara's bisection), at most [`MAX_SPLITS`]
//! levels and down to edges of [`SHORTEST`] of a cell.
//!
//! No split may fold the mesh: a place to split is passed over when a piece of either
//! triangle beside the edge would face against the field ([`FOLD_COS`]) where the triangle
//! did not (a sliver lower than [`SLIVER_SHARE`] of the tolerance aside). So a triangle of the mesher's is held until the triangles across its edges that
//! may split have come (they come slab by slab, so within a slab or two; at most
//! [`HELD_MAX`] are held), and the pieces' new edges record the triangles beside them too.
//! Without it, on a cube turned off the lattice (a random turn; the fixture's 30° and 20°
//! happen to escape it), a crease point on one face was joined to corners on another, and
//! the pieces lay on a face the wrong way round: up to 8 % of the area folded, the surface
//! 19 % larger than the cube's at depth 6.
//!
//! Nor may a split turn a small closed blob inside out (blobs a cell or two wide, at
//! tolerances of half a cell and more, did): a split that moves an edge's middle outward
//! while taking volume away is passed over when it leaves the wedge of its two sides inside
//! out ([`inverts_the_wedge`]); a mesher's vertex left far off the surface takes no
//! splits on its edges ([`STRAY_CELLS`]); and beside one the refiner could not move onto
//! the surface at all, splits are held to a margin of their wedge and triangles get no
//! centre vertex ([`folds_beside_stuck`]).
//!
//! Nor may splitting run on where it cannot end: a short edge from one side of a sheet
//! thinner than a cell to the other splits only where one split holds ([`OPPOSITE_COS`]).
//!
//! Why the mesh stays closed and manifold: whether and where an edge splits is decided
//! once, when the first triangle beside it asks, and the second reads the answer: a split's
//! new vertex is kept in a map until both sides have used it. A "no" depends on the edge
//! alone (its two end vertices and the triangles recorded beside it) and gives the same
//! answer when asked again, except where it came from another new vertex nearby or from a
//! fold (which the second side might not see): that "no" is kept until both sides have
//! written the edge. A centre vertex is inside one triangle. Only positions of the mesher's
//! vertices change, never which triangles they belong to.
//!
//! What it costs: one gradient per vertex, and one per edge whose ends' normals say a chord
//! there could be off by a quarter of the tolerance (a circular arc of chord `l` whose
//! normals turn by `θ` is `l/2 · tan(θ/4)` from it) or that is longer than a cell
//! ([`PROBE_CELLS`]; two crease vertices may read the same face's normal): along creases,
//! along the diagonals of finest cells, and along the long chords of merged leaves. At
//! depth 8 the filter without the diagonals took spheres_chain from 0.20 to 0.39 s and
//! gyroid_sphere from 0.60 to 0.95 s (a stricter filter saved little and let curve_cyl's
//! chords miss by 3.7 tolerances instead of 2.8); the diagonals cost about 10 % more.

use std::cell::RefCell;
use std::collections::{HashMap, HashSet, VecDeque};
use std::io;

use glam::DVec3;

use isoforge_field::Bounds;

use super::left_off::LeftOff;
use super::narrowed::Narrowed;
use super::sampler::Sampler;
use crate::int_hash::IntMap;
use crate::sink::MeshSink;

/// An edge is split when its middle is farther from the surface than this share of the
/// tolerance: the field's first-order distance |F| / |∇F| is what is checked here, and
/// `check --against` measures along the gradient, which on a curved surface reads a
/// little more.
const SPLIT_SHARE: f64 = 0.8;

/// The normals' arc estimate must reach this share of the tolerance before an edge is
/// looked at by the field.
const FILTER_SHARE: f64 = 0.25;

/// Edges longer than this many finest cells are looked at by the field whatever their
/// ends' normals say. Two vertices on one face read the same normal even where another
/// face cuts in between them: on threaded_rod at depth 8 a chord 1.4 cells long between
/// two vertices on the rod's core passed under the tapered end of the thread, its middle
/// 1.03 tolerances off, and was never looked at (with [`LONG_CELLS`] here). Costs about
/// 10 % of the CPU time of gyroid_sphere and spheres_chain at depth 9.
const PROBE_CELLS: f64 = 1.0;

/// Edges longer than this many finest cells were looked at by the field whatever their
/// ends' normals say (now [`PROBE_CELLS`]), and triangles whose sides are all longer may
/// take a centre vertex again in a centre split's pieces. At a crease a vertex's normal is
/// one face's, so two vertices on a curved crease can read the same normal: on cube_holes
/// (a slicing fixture) at depth 8, a chord of the merge's crossed its 5 mm hole 0.22 mm
/// inside the rim (26 tolerances) and was never looked at. And on pins, strips of the
/// cylinders from cap to cap (64 cells long) kept their centres' pieces 1.07 tolerances
/// off. Such edges are few: the merge makes them only on flat and nearly flat parts.
const LONG_CELLS: f64 = 2.0;

/// A vertex farther than this share of the tolerance from the surface is moved onto it.
const MOVE_SHARE: f64 = 0.5;

/// The farthest a vertex moves onto the surface, in finest cells. Off by more, the
/// surface it would land on may be another part's (a thin sheet's far side). When the
/// refiner was new, 0.75 turned a one-cell blob of a random CSG test inside out, and 0.25
/// was chosen; since then the guards beside stuck and stray vertices and against
/// inverted wedges came, and with [`FAR_MOVE`] and [`THICK_CELLS`] 0.75 holds. At depth
/// 8, 0.25 left threaded_rod's tooth tips with vertices up to 0.3 cells off (3.2
/// tolerances; now 0.86, held), sinus_bugs 6.4 and drilled_import 5.4 tolerances off (now
/// 4.2 and 3.8). At 1.0 spaceship went from 5.3 to 6.4 tolerances (vertices near
/// [`STRAY_CELLS`] moved rather than left unsplit).
const REACH: f64 = 0.75;

/// A vertex moved farther than this many finest cells is held like one that could not be
/// moved ([`folds_beside_stuck`]; no centre beside it), and moves so far only where the
/// surface is thick ([`THICK_CELLS`]). Moves up to a quarter of a cell were free before,
/// and still are.
const FAR_MOVE: f64 = 0.25;

/// A vertex moves farther than [`FAR_MOVE`] only where the surface has this many finest
/// cells of the other side beyond where it lands, and of its own side behind where it
/// starts (each checked halfway and at the end). Without it, balls 0.86 and 1.03 cells
/// wide (seeds of the random CSG test, at the default tolerance and at half a cell) came
/// out inside out; checked beyond alone, the second still did (its vertex started inside).
/// At 1.0 a ball 1.14 cells wide at a tolerance of 3 cells did too: the merge left it a
/// flat tetrahedron with one corner 1.6 cells off, and two corners moved half a cell onto
/// the ball turned it over (a seed of the same test, session 31). At 1.25 no fixture's
/// largest distance at depth 8 changed, and five fixtures' triangle counts by under 1 %.
const THICK_CELLS: f64 = 1.25;

/// A mesher's vertex farther from the surface than this many finest cells (by the field's
/// first-order distance) that could not be moved onto it within [`REACH`] takes no splits
/// on its edges: pieces joining a point on the surface to one so far off make spikes, and
/// on a ball under a cell wide at a tolerance of 3 cells (the merge put a vertex 1.6 cells
/// from it) they turned the ball inside out. Of the fixtures at depth 8 only spaceship has
/// such vertices (about a hundred); with every vertex the refiner could not move left
/// unsplit, its largest distance went from 5.3 to 6.4 tolerances, at 0.9 cells it stays 5.3.
const STRAY_CELLS: f64 = 0.9;

/// Edges shorter than this many finest cells are never split. A crease cut by a chord of
/// length `l` is missed by at most about `l/2`, so this bounds the error at creases to
/// about 0.03 of a cell whatever the tolerance asked.
const SHORTEST: f64 = 1.0 / 16.0;

/// How far a new vertex may move onto the surface, as a share of the edge it splits (or
/// of the shortest side of the triangle it is the centre of): under a half, so that the
/// pieces of an edge are at most three quarters of it and splitting ends.
const MID_REACH: f64 = 0.5;

/// Splits of splits at most: an edge of the mesher's becomes at most 2^8 pieces. What
/// makes splitting end: where the surface between two vertices is far from their chord (a
/// thin wall seen edge-on), each new middle moved onto the surface can leave a chord as long
/// as before, and levels bound that.
///
/// An edge at least [`LONG_CELLS`] long goes on to twice as many ([`Refiner::capped`]): a
/// fan's spokes (the chords from one corner to the new vertices along its far side) take
/// their far end's level without getting shorter, and on stacked_sphere_circle at depth 8
/// a spoke 2.6 cells long across the groove was left at level 8, 1.14 tolerances off
/// (session 41). Twice as many levels for every edge made spaceship worse (5.3 to 6.5
/// tolerances; sessions 29 and 41): short edges at the cap are where splitting does not end.
const MAX_SPLITS: u8 = 8;

/// The mesher's triangles held at most while they wait for their neighbours. The mesh
/// comes slab by slab, so a triangle's neighbours come within a slab or two.
const HELD_MAX: usize = 1 << 18;

/// A split's piece facing against the field by more than this (cosine, 154°) at its
/// centre, where the triangle it comes from did not, is a fold the split would make: a
/// crease point on a far face joined to corners on another (a cube turned off the lattice
/// got pieces lying on a face the wrong way round, up to 8 % of its area folded). Pieces
/// nearer square to it are left alone: at 90° sphere_circle and spheres_chain no longer
/// held the tolerance (1.8 and 2.5 tolerances), the chords along their creases unsplit.
const FOLD_COS: f64 = -0.9;

/// Pieces smaller than this many square finest cells are folds only where they also face
/// against the normals at all three corners: at creases the field at a small piece's centre
/// may be the other face's, and dual contouring leaves small folds of its own (checked at the
/// centre alone at any size, and with [`EDGE_ON_COS`] at 154°, spaceship went from 5.6 to 6.3
/// tolerances and spheres_chain from 0.8 to 2.0). Not looked at, a ball under two cells
/// wide, clipped by the region's corner and collapsed to six triangles, was split inside out.
const FOLD_AREA: f64 = 0.25;

/// A piece lower than this share of the tolerance (twice its area over its longest side) is
/// never a fold: all of it lies that near its longest side, so whichever way it faces, it
/// cannot take the mesh farther from the surface than that. Where a crease point lands a
/// hair from the far corner of one side (on lecture_bezier's flat edges, 0.02 cells from
/// it), that side's pieces are such slivers, facing anywhere; counted as folds, they kept
/// the chord across the crease whole, 1.75 tolerances off (session 41).
const SLIVER_SHARE: f64 = 0.25;

/// A triangle facing against the field at its centre by more than this (cosine, 96°) is a
/// fold already, and its pieces are not checked. One nearer edge-on is not: on the ball of
/// [`FOLD_AREA`] the first bad split was of a triangle edge-on to the field (cosine −0.016)
/// into pieces facing against it by 170°, and at 90° it was passed over. At 107° (cosine
/// −0.3) spheres_chain no longer held the tolerance (1.8 tolerances).
const EDGE_ON_COS: f64 = -0.1;

/// Triangles lower than this share of their longest side are slivers, left out of
/// [`inverts_the_wedge`]: along drope_block's ridge, pairs of slivers folded over it fail
/// it, and without their splits drope_block missed the tolerance (2.3 tolerances).
const THIN: f64 = 0.1;

/// Below this share of the split threshold by the first-order distance, a point is taken
/// to hold without Newton steps ([`Refiner::strays`]): beside faces meeting at 60° and more,
/// the distance to their crease is at most twice the distance to the nearer face's plane.
const BAND_SHARE: f64 = 0.5;

/// Two vertex normals closer than this (cosine, 60°) do not make a crease between them.
const CREASE_COS: f64 = 0.5;

/// How far a crease may be from the middle of the edge that spans it, in lengths of the
/// edge: a groove narrower than a cell is not seen by the lattice, and the polygons bridge
/// it; its bottom can be several times deeper than the groove is wide where they do.
const CREASE_REACH: f64 = 4.0;

/// How far the crease point may move onto the surface, in lengths of the edge: where the
/// faces curve, tangent planes meet up to a fraction of the distance off the true crease.
const CREASE_SNAP: f64 = 0.5;

/// A crease point farther than this many lengths of the edge from its middle must have
/// halves that hold the tolerance along their length (`halves_hold`).
const FAR_CREASE: f64 = 0.75;

/// Two new vertices are kept at least this many cells apart: where they land a hair apart
/// (two edges' splits onto one straight crease), every way of joining the pieces has a
/// needle, whose normal single-precision readers get wrong (ADMesh "fixed" them).
///
/// 1/32 until session 41. But a fan's chords across one crease split at points a few
/// hundredths of a cell apart (three mesher vertices within 0.07 cells of each other at
/// lecture_bezier's sheet corner, joined to one vertex across the crease), and 1/32
/// refused all but the first: with [`SLIVER_SHARE`], 1/128 took sinus_sphere from 4.43 to
/// 2.66 tolerances at depth 8 and lecture_bezier to 0.80, where 1/64 left sinus_sphere at
/// 4.73; ADMesh fixes nothing on any fixture's mesh at depths 6, 8 and 9.
const APART: f64 = 1.0 / 128.0;

/// A new vertex nearer an end of its edge than this share of the edge is not made.
const NEAR_END: f64 = 0.1;

/// An edge whose ends' normals are farther apart than this cosine (162°) runs from one side
/// of a sheet or a slot to the other, where the two sides are near parallel: a split puts
/// the middle on one side and leaves a half that crosses again, level after level, and no
/// split brings it within the tolerance (the middle of a chord through a sheet is half the
/// sheet's thickness off). Such an edge is split only where one split brings both halves'
/// middles within the split threshold. Without it, a gyroid sheet 0.7 cells thick in a
/// ball (found by a hunt over random scripts) went from 95,378 triangles out of the
/// collapses to 424,100 written, for the same largest distance (3.51 tolerances): 156,773
/// splits, most at levels 3 to 8. At −0.5 grooves where spheres meet at 160° (normals up
/// to 154° apart) lost their splits too: spheres_chain at depth 8 went from 0.82 to 1.25
/// tolerances. Only edges up to [`LONG_CELLS`] are held so (a sheet a chord crosses is
/// thinner than a cell): on a turned cube an edge of the collapses 50 cells long ran from
/// one face to the opposite one, and its splits are what unfold it.
const OPPOSITE_COS: f64 = -0.95;

/// Positions remembered to keep vertices apart, in each of two generations: vertices come
/// slab by slab, and one moved onto the surface lands within a cell of where it was made.
const RECENT_KEPT: usize = 1 << 18;

/// Newton steps onto the surface at most.
const NEWTON_STEPS: usize = 6;

/// Recursion depth at most when splitting one triangle: a guard only (edges halve at
/// every level and stop at [`SHORTEST`] long before).
const MAX_LEVEL: u32 = 40;

/// One output vertex.
#[derive(Clone, Copy, Debug)]
struct Vert {
    pos: [f32; 3],
    /// The field's unit gradient there; zero where the field says nothing.
    normal: [f32; 3],
    /// 0 for the mesher's vertices; one more than the higher end's for a split edge's
    /// middle.
    level: u8,
    /// A mesher's vertex left far off the surface (see [`STRAY_CELLS`]): edges to it are
    /// not split.
    stray: bool,
    /// A mesher's vertex the refiner could not move onto the surface (it was more than the
    /// tolerance's share [`MOVE_SHARE`] off), or moved farther than [`FAR_MOVE`]: an edge to
    /// it splits only where that keeps its wedge the right way out by a margin (see
    /// [`folds_beside_stuck`]).
    stuck: bool,
    /// A mesher's vertex the refiner could not move onto the surface at all, not yet given
    /// to [`Refiner::left_off`] (it is, when the first triangle on it is written).
    unmoved: bool,
}

impl Vert {
    fn at(&self) -> DVec3 {
        DVec3::from(self.pos.map(f64::from))
    }
    fn normal(&self) -> DVec3 {
        DVec3::from(self.normal.map(f64::from))
    }
}

/// Moves vertices onto the surface and splits triangles that stray from it, on the way
/// to `inner` (see the module doc).
pub struct Refiner<'a, S: Sampler> {
    sampler: &'a S,
    ev: S::Evals,
    /// The field, narrowed to boxes near the latest vertices.
    field: Narrowed<S>,
    tolerance: f64,
    /// The region's corners: a vertex moved onto the surface stays inside (Newton stops
    /// within a tenth of the tolerance, which can be a hair beyond a region's wall).
    lo: DVec3,
    hi: DVec3,
    cell: f64,
    inner: &'a mut dyn MeshSink,
    /// Every output vertex so far.
    verts: Vec<Vert>,
    /// Output index of each input vertex.
    remap: Vec<u32>,
    /// Split edges (lower, higher output index) that not both sides have used yet: the
    /// middle vertex, and how many sides have.
    splits: IntMap<(u32, u32), (u32, u8)>,
    /// Edges left whole because every place to split them was a hair from another new
    /// vertex (a decision that depends on more than the edge, so it is kept until both
    /// sides have written the edge): how many have.
    refused: IntMap<(u32, u32), u8>,
    /// New (split) vertices by grid square of [`APART`] cells, latest and older.
    near: HashMap<[i64; 3], Vec<u32>>,
    near_older: HashMap<[i64; 3], Vec<u32>>,
    /// Positions of the latest vertices, and of those before them.
    recent: HashSet<[u32; 3]>,
    older: HashSet<[u32; 3]>,
    /// The mesher's triangles waiting for their neighbours, by arrival, with how many of
    /// their edges have not yet been seen from the other side.
    held: IntMap<u64, ([u32; 3], u8)>,
    /// Arrival order of the held triangles.
    queue: VecDeque<u64>,
    /// Arrivals so far.
    arrived: u64,
    /// The mesher's edges: the vertices opposite them, in the triangles on either side.
    across: IntMap<(u32, u32), Across>,
    /// The mesher's triangles with an edge from one side of a part to the other (at most
    /// [`LONG_CELLS`] long, its ends' normals more than 162° apart): there the part is
    /// thinner than the lattice resolves.
    pub thin_triangles: u64,
    /// Where to keep the places on the mesh farther from the surface than an edge splits
    /// for, left so because every split there would fold the mesh or none could be placed
    /// (a chord's middle, a triangle's centre), and the mesher's vertices that could not
    /// be moved onto it (`left_off.rs`); none kept without it.
    left_off: Option<&'a RefCell<LeftOff>>,
}

/// What is known about one of the mesher's edges.
#[derive(Clone, Copy, Debug)]
struct Across {
    /// The vertices opposite the edge, `seen` of them (a piece's edge on a split edge also
    /// records the corners of the split triangles), each with whether its triangle runs
    /// along the edge from the lower index to the higher (counter-clockwise).
    apex: [(u32, bool); 3],
    seen: u8,
    /// The held triangle that waits for the second side.
    waiting: Option<u64>,
    /// Sides written.
    released: u8,
}

impl<'a, S: Sampler> Refiner<'a, S> {
    /// Refines to within `tolerance` (model units) on a lattice of `cell`-sized cells, on
    /// the way to `inner`.
    pub fn new(
        sampler: &'a S,
        tolerance: f64,
        region: &Bounds,
        cell: f64,
        inner: &'a mut dyn MeshSink,
    ) -> Self {
        Refiner {
            lo: DVec3::from(region.min),
            hi: DVec3::from(region.max),
            sampler,
            ev: sampler.evals(),
            field: Narrowed::new(sampler, cell),
            tolerance,
            cell,
            inner,
            verts: Vec::new(),
            remap: Vec::new(),
            splits: IntMap::default(),
            refused: IntMap::default(),
            near: HashMap::new(),
            near_older: HashMap::new(),
            recent: HashSet::new(),
            older: HashSet::new(),
            held: IntMap::default(),
            queue: VecDeque::new(),
            arrived: 0,
            across: IntMap::default(),
            thin_triangles: 0,
            left_off: None,
        }
    }

    /// Keeps the places left off the surface in `places`.
    pub fn keeping_places(mut self, places: &'a RefCell<LeftOff>) -> Self {
        self.left_off = Some(places);
        self
    }

    /// Writes the triangles still waiting for a neighbour (none, on a closed mesh); call
    /// once everything has come.
    pub fn finish(&mut self) -> io::Result<()> {
        while let Some(s) = self.queue.pop_front() {
            if let Some((t, _)) = self.held.remove(&s) {
                self.tessellate(t, 0, false)?;
            }
        }
        Ok(())
    }

    /// Takes one of the mesher's triangles: held until the triangles across its edges have
    /// come, so that a split of an edge is chosen knowing both triangles beside it.
    fn arrive(&mut self, t: [u32; 3]) -> io::Result<()> {
        let seq = self.arrived;
        self.arrived += 1;

        let mut missing = 0u8;
        let mut ready = Vec::new();
        if (0..3).any(|k| self.across_a_part(t[k], t[(k + 1) % 3])) {
            self.thin_triangles += 1;
        }
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            // An edge whose ends' normals say its chord holds is never split: neither side
            // needs the other's corner (most edges, on smooth parts).
            let (va, vb) = (self.verts[a as usize], self.verts[b as usize]);
            if !self.may_stray(&va, &vb, (va.at() - vb.at()).length()) {
                continue;
            }
            let e = self.across.entry((a.min(b), a.max(b))).or_insert(Across {
                apex: [(c, a < b); 3],
                seen: 0,
                waiting: None,
                released: 0,
            });
            match e.seen {
                0 => {
                    e.apex[0] = (c, a < b);
                    e.seen = 1;
                    e.waiting = Some(seq);
                    missing += 1;
                }
                1 => {
                    e.apex[1] = (c, a < b);
                    e.seen = 2;
                    if let Some(w) = e.waiting.take()
                        && let Some(h) = self.held.get_mut(&w)
                    {
                        h.1 -= 1;
                        if h.1 == 0 {
                            ready.push(w);
                        }
                    }
                }
                // A third triangle on one edge: not a manifold input; split it as before.
                _ => {}
            }
        }
        if missing == 0 {
            ready.push(seq);
            self.held.insert(seq, (t, 0));
        } else {
            self.held.insert(seq, (t, missing));
            self.queue.push_back(seq);
        }
        for w in ready {
            if let Some((h, _)) = self.held.remove(&w) {
                self.tessellate(h, 0, false)?;
            }
        }
        // Bounded memory whatever the order triangles come in: the oldest go on with what
        // is known of their neighbours.
        while self.held.len() > HELD_MAX {
            let Some(s) = self.queue.pop_front() else {
                break;
            };
            if let Some((h, _)) = self.held.remove(&s) {
                self.tessellate(h, 0, false)?;
            }
        }
        if self.queue.len() > 2 * HELD_MAX {
            let held = &self.held;
            self.queue.retain(|s| held.contains_key(s));
        }
        Ok(())
    }

    /// Whether edge `a`–`b` runs from one side of a part to the other: short, its ends'
    /// normals nearly opposite.
    fn across_a_part(&self, a: u32, b: u32) -> bool {
        let (va, vb) = (self.verts[a as usize], self.verts[b as usize]);
        (va.at() - vb.at()).length() <= LONG_CELLS * self.cell
            && va.normal().dot(vb.normal()) < OPPOSITE_COS
    }

    /// Records the vertices opposite a new edge of the pieces (`apex`, and the other side's
    /// where it is known).
    fn note_across(&mut self, a: u32, b: u32, apex: &[(u32, bool)]) {
        let mut e = Across {
            apex: [(u32::MAX, true); 3],
            seen: 0,
            waiting: None,
            released: 0,
        };
        for (slot, &z) in e.apex.iter_mut().zip(apex) {
            *slot = z;
            e.seen += 1;
        }
        // Never replaced: the other side must see what the first saw.
        self.across.entry((a.min(b), a.max(b))).or_insert(e);
    }

    /// Counts a written side of each edge of `t`; the second forgets the edge.
    fn forget_written(&mut self, t: [u32; 3]) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(e) = self.across.get_mut(&key) {
                e.released += 1;
                if e.released >= 2 {
                    self.across.remove(&key);
                }
            }
        }
    }

    /// F and the unit gradient at `p`, with |F| / |∇F|; `None` where the field says
    /// nothing useful (NaN, a zero gradient).
    fn probe(&mut self, p: DVec3) -> Option<(f64, DVec3, f64)> {
        let local = self.field.around(self.sampler, &mut self.ev, p)?;
        let g = self.sampler.grad(&mut self.ev, local, p.to_array());
        let grad = DVec3::new(g[1], g[2], g[3]);
        let slope = grad.length();
        if !g[0].is_finite() || !slope.is_finite() || slope <= 0.0 {
            return None;
        }
        Some((g[0], grad / slope, g[0].abs() / slope))
    }

    /// Whether `p` is farther from the surface than the split threshold: F there, and where
    /// Newton steps within `reach` put it on the surface (the first candidate for a split).
    ///
    /// The first-order distance |F| / |∇F| reads one branch of a `max` or `min`: just
    /// outside a ridge (or inside a valley) it is the distance to the nearer face's plane,
    /// where the surface is the crease beyond it, up to √2 farther for faces at right
    /// angles. A chord along the crease where two of booleans' holes meet (an ellipse) had
    /// its middle 0.78 tolerances off by that reading and 1.02 in truth. So between
    /// [`BAND_SHARE`] and the threshold, the distance is how far Newton steps (which go to
    /// where both faces' planes meet at a crease) take the point to the surface.
    ///
    /// On a smooth part the reading is right only where the field is a distance. Where it
    /// is not, it may read short: on knurled_knob's textured faces a chord's middle read
    /// 0.79 tolerances and was 1.09 off. So the reading is taken only where one
    /// first-order step lands on the surface. And where it reads long (inside a hull, whose
    /// field there is a bound a few tenths of a millimetre below the distance), the
    /// distance is where the Newton steps land, when they do.
    fn strays(&mut self, p: DVec3, reach: f64) -> Option<(f64, Option<(DVec3, DVec3)>)> {
        let (f, n, d) = self.probe(p)?;
        let threshold = self.tolerance * SPLIT_SHARE;
        if d <= threshold * BAND_SHARE {
            return None;
        }
        // Where one first-order step lands on the surface, the reading was right.
        if d <= threshold
            && self
                .probe(p - n * (f.signum() * d))
                .is_some_and(|(_, _, d1)| d1 <= self.tolerance * 0.1)
        {
            return None;
        }
        let along = self.onto_surface(p, reach);
        let far = match along {
            Some((q, _)) => (q - p).length() > threshold,
            None => d > threshold,
        };
        far.then_some((f, along))
    }

    /// `p` moved onto the surface by Newton steps along the gradient, with the unit
    /// gradient there; `None` if that does not bring it within a tenth of the tolerance
    /// within `reach` of where it started.
    ///
    /// Near a crease of a `max` or `min` the gradient is one branch's, and the branch in
    /// charge changes from step to step: one branch at a time, Newton zigzags across the
    /// crease and closes in slowly (by cos² of the angle between the faces per pair of steps;
    /// on gyroid_sphere's sharp rims it had not arrived after six). Where the normal turns
    /// past [`CREASE_COS`] between two steps, the step goes to where both branches' tangent
    /// planes meet instead, which arrives in one or two.
    fn onto_surface(&mut self, p: DVec3, reach: f64) -> Option<(DVec3, DVec3)> {
        let mut q = p;
        // The last step's value, gradient and point.
        let mut last: Option<(f64, DVec3, DVec3)> = None;
        for _ in 0..NEWTON_STEPS {
            let (f, n, d) = self.probe(q)?;
            if d <= self.tolerance * 0.1 {
                return ((q - p).length() <= reach).then_some((q, n));
            }
            let g = n * (f.abs() / d);
            let step = last
                .filter(|(_, gl, _)| n.dot(gl.normalize()) < CREASE_COS)
                .and_then(|(fl, gl, ql)| both_planes_step(f, g, fl + gl.dot(q - ql), gl));
            last = Some((f, g, q));
            q += step.unwrap_or(-n * (f.signum() * d));
            if (q - p).length() > reach {
                return None;
            }
        }
        let (_, n, d) = self.probe(q)?;
        (d <= self.tolerance * 0.1).then_some((q, n))
    }

    /// Whether the sides of the surface on either end of a move from `p` to `q` (with its
    /// normal `nq`) go on for [`THICK_CELLS`]: beyond `q` along its normal, and behind `p`
    /// along the move. A vertex moved far onto a ball or a wall thinner than that, or out
    /// of one, may land on its far side. `fp` is the field at `p`, already probed by the
    /// caller.
    fn thick_around(&mut self, p: DVec3, fp: f64, (q, nq): (DVec3, DVec3)) -> bool {
        let dir = (q - p).normalize_or_zero();
        // Beyond `q` along its normal, to the other side: a move along a face's plane (a
        // vertex in the plane of a cap, outside its rim) probed along itself reads the
        // face's own zero.
        let across = -nq * fp.signum();
        [0.5, 1.0].iter().all(|&k| {
            let step = dir * (k * THICK_CELLS * self.cell);
            let beyond = self.probe(q + across * (k * THICK_CELLS * self.cell));
            let behind = self.probe(p - step);
            beyond.is_some_and(|(f, _, _)| f.signum() != fp.signum())
                && behind.is_some_and(|(f, _, _)| f.signum() == fp.signum())
        })
    }

    /// A new output vertex.
    fn emit_vertex(&mut self, p: DVec3, normal: DVec3, level: u8) -> io::Result<u32> {
        let id = u32::try_from(self.verts.len())
            .map_err(|_| io::Error::other("more than 2^32 vertices"))?;
        let pos = self.distinct(p.clamp(self.lo, self.hi).as_vec3().to_array());
        self.inner.vertex(pos)?;
        self.verts.push(Vert {
            pos,
            normal: normal.as_vec3().to_array(),
            level,
            stray: false,
            stuck: false,
            unmoved: false,
        });
        Ok(id)
    }

    /// `pos`, or the nearest f32 point after it along x that no recent vertex has: STL
    /// keeps no indices and its readers weld by position, so a vertex moved onto the
    /// surface must not land exactly where another is (Newton steps from two nearby points
    /// can end on the same float point near a corner of the region).
    fn distinct(&mut self, mut pos: [f32; 3]) -> [f32; 3] {
        let key = |p: [f32; 3]| p.map(f32::to_bits);
        while self.recent.contains(&key(pos)) || self.older.contains(&key(pos)) {
            pos[0] = pos[0].next_up();
        }
        if self.recent.len() >= RECENT_KEPT {
            self.older = std::mem::take(&mut self.recent);
        }
        self.recent.insert(key(pos));
        pos
    }

    /// Whether the chord between two vertices can be off by the tolerance, by their
    /// normals (the module doc); true where a normal is unknown or the chord is longer
    /// than a cell ([`PROBE_CELLS`]).
    fn may_stray(&self, a: &Vert, b: &Vert, len: f64) -> bool {
        let (na, nb) = (a.normal(), b.normal());
        if na == DVec3::ZERO || nb == DVec3::ZERO || len > PROBE_CELLS * self.cell {
            return true;
        }
        let theta = na.dot(nb).clamp(-1.0, 1.0).acos();
        len * 0.5 * (theta * 0.25).tan() > self.tolerance * FILTER_SHARE
    }

    /// The middle vertex of edge `a`–`b`, if it is split (made now, or found from the other
    /// side). The decision depends only on the two vertices, in index order.
    fn split(&mut self, a: u32, b: u32, apex: [(DVec3, DVec3); 3]) -> io::Result<Option<u32>> {
        let key = (a.min(b), a.max(b));
        if let Some(&(m, _)) = self.splits.get(&key) {
            return Ok(Some(m));
        }
        if self.refused.contains_key(&key) {
            return Ok(None);
        }
        self.decide_split(key, apex)
    }

    /// Whether and where edge `key` (output indices, lower first) splits, by the field.
    fn decide_split(
        &mut self,
        key: (u32, u32),
        apex: [(DVec3, DVec3); 3],
    ) -> io::Result<Option<u32>> {
        let (va, vb) = (self.verts[key.0 as usize], self.verts[key.1 as usize]);
        let (pa, pb) = (va.at(), vb.at());
        let len = (pb - pa).length();
        let level = va.level.max(vb.level);
        let mid = (pa + pb) * 0.5;
        if Self::capped(level, len / self.cell)
            || va.stray
            || vb.stray
            || len < SHORTEST * self.cell
            || !self.may_stray(&va, &vb, len)
        {
            return Ok(None);
        }
        let reach = len * MID_REACH;
        // +1 where the middle is inside the solid (a split moves it outward), −1 outside.
        let Some((f, along)) = self.strays(mid, reach) else {
            return Ok(None);
        };
        let outward = -f.signum();
        let across_a_sheet = self.across_a_part(key.0, key.1);
        // Where tangent planes meet: the ends' (a crease between them), and, when one end
        // sits on the crease itself and has the same face's normal as the other, the
        // plane where the middle landed with each end's.
        let ends = [(pa, va.normal()), (pb, vb.normal())];
        let mut pairs = vec![(ends[0], ends[1])];
        if let Some(landed) = along {
            pairs.extend([(ends[0], landed), (landed, ends[1])]);
        }
        // The triangles beside the edge, checked for folds: the ones recorded for it, not
        // the asking piece (whose corner may be another split's vertex), so that both sides
        // come to the same answer.
        let (ea, eb) = ((pa, va.normal()), (pb, vb.normal()));
        let sides: Vec<[(DVec3, DVec3); 3]> = match self.across.get(&key) {
            Some(e) if e.seen > 0 => e.apex[..usize::from(e.seen)]
                .iter()
                .map(|&(z, forward)| {
                    let v = self.verts[z as usize];
                    let c = (v.at(), v.normal());
                    if forward { [ea, eb, c] } else { [eb, ea, c] }
                })
                .collect(),
            _ => vec![apex],
        };
        // Too near an end, a new vertex would make a sliver (or, written as STL and read
        // back, the same point twice).
        let clear_of_ends = |q: DVec3| (q - pa).length().min((q - pb).length()) >= len * NEAR_END;
        // Each candidate with its halves' error, the straightest first.
        let mut candidates: Vec<(f64, (DVec3, DVec3))> = Vec::new();
        if let Some(g) = along.filter(|g| clear_of_ends(g.0)) {
            candidates.push((self.halves_error(pa, pb, g.0), g));
        }
        for (plane_a, plane_b) in pairs {
            let Some(x) = crease_point(plane_a, plane_b, mid)
                .filter(|x| (*x - mid).length() <= len * CREASE_REACH)
            else {
                continue;
            };
            let Some(c) = self
                .onto_surface(x, len * CREASE_SNAP)
                .filter(|c| clear_of_ends(c.0))
            else {
                continue;
            };
            if (c.0 - mid).length() > len * FAR_CREASE && !self.halves_hold(pa, pb, c.0) {
                continue;
            }
            candidates.push((self.halves_error(pa, pb, c.0), c));
        }
        candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut chosen = None;
        for &(halves, (q, n)) in &candidates {
            if (!across_a_sheet || halves <= self.tolerance * SPLIT_SHARE)
                && !self.folds_a_side(&sides, (q, n))
                && !inverts_the_wedge(&sides, q, outward)
                && !((va.stuck || vb.stuck) && folds_beside_stuck(&sides, q, outward))
                && !self.crowded(q)
            {
                chosen = Some((q, n));
                break;
            }
        }
        let Some((q, n)) = chosen else {
            self.leave_off(mid);
            // Every candidate was crowded or folds a side: a "no" that depends on more than
            // the edge.
            if !candidates.is_empty() {
                self.refused.insert(key, 0);
            }
            return Ok(None);
        };
        let m = self.emit_vertex(q, n, level + 1)?;
        self.remember_near(m, q);
        self.splits.insert(key, (m, 0));
        Ok(Some(m))
    }

    /// Records a place on the mesh left farther from the surface than the split threshold.
    fn leave_off(&mut self, p: DVec3) {
        if let Some(places) = self.left_off {
            places.borrow_mut().add(p.to_array());
        }
    }

    /// Whether an edge `cells` long with an end at split `level` is split no further
    /// ([`MAX_SPLITS`]).
    fn capped(level: u8, cells: f64) -> bool {
        level >= 2 * MAX_SPLITS || (level >= MAX_SPLITS && cells < LONG_CELLS)
    }

    /// The grid square of `p` for [`Refiner::near`].
    fn square(&self, p: DVec3) -> Option<[i64; 3]> {
        let key = (p / (APART * self.cell)).floor();
        (key.is_finite() && key.abs().max_element() < 1e15).then(|| key.as_i64vec3().to_array())
    }

    /// Whether a new vertex at `q` would be within [`APART`] cells of another new vertex.
    fn crowded(&self, q: DVec3) -> bool {
        let Some(k) = self.square(q) else {
            return false;
        };
        let apart = APART * self.cell;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let key = [k[0] + dx, k[1] + dy, k[2] + dz];
                    for map in [&self.near, &self.near_older] {
                        let Some(ids) = map.get(&key) else { continue };
                        if ids
                            .iter()
                            .any(|&i| (self.verts[i as usize].at() - q).length() < apart)
                        {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }

    /// Files new vertex `m` at `q` for [`Refiner::crowded`].
    fn remember_near(&mut self, m: u32, q: DVec3) {
        let Some(k) = self.square(q) else { return };
        if self.near.len() >= RECENT_KEPT {
            self.near_older = std::mem::take(&mut self.near);
        }
        self.near.entry(k).or_default().push(m);
    }

    /// Counts the sides written of refused edges among `t`'s; the second frees them.
    fn written(&mut self, t: [u32; 3]) {
        if self.refused.is_empty() {
            return;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(n) = self.refused.get_mut(&key) {
                *n += 1;
                if *n >= 2 {
                    self.refused.remove(&key);
                }
            }
        }
    }

    /// How far the middles of the two halves of `a`–`b` split at `m` are from the surface
    /// (the larger).
    fn halves_error(&mut self, a: DVec3, b: DVec3, m: DVec3) -> f64 {
        let mut worst = 0.0f64;
        for p in [(a + m) * 0.5, (m + b) * 0.5] {
            worst = worst.max(self.probe(p).map_or(f64::INFINITY, |x| x.2));
        }
        worst
    }

    /// Whether the halves of `a`–`b` split at `m` keep within the split threshold at their
    /// quarters: a crease point far from the edge is taken only if its halves lie on the
    /// surface, not just their middles (on a sheet a cell thick, tangent planes a few cells
    /// apart meet where there is no crease, and such splits folded gyroid_sphere at depth 5
    /// into 1.16 of its volume).
    fn halves_hold(&mut self, a: DVec3, b: DVec3, m: DVec3) -> bool {
        for (u, v) in [(a, m), (m, b)] {
            for t in [0.25, 0.75] {
                let d = self.probe(u.lerp(v, t)).map_or(f64::INFINITY, |x| x.2);
                if d > self.tolerance * SPLIT_SHARE {
                    return false;
                }
            }
        }
        true
    }

    /// Whether splitting the first edge of any of `sides` (triangles, counter-clockwise, with
    /// their corners' normals) at `q` (with its normal) leaves a piece facing against the
    /// field at its centre where the triangle did not: a fold made by the split (a crease
    /// point on a far face, joined to corners on another).
    fn folds_a_side(&mut self, sides: &[[(DVec3, DVec3); 3]], (q, nq): (DVec3, DVec3)) -> bool {
        let smallest = FOLD_AREA * self.cell * self.cell;
        for &[(a, na), (b, nb), (c, nc)] in sides {
            // Twice the pieces' areas along their normals, with their corners' normals.
            let pieces = [[(a, na), (q, nq), (c, nc)], [(q, nq), (b, nb), (c, nc)]]
                .map(|[(u, nu), (v, nv), (w, nw)]| ((v - u).cross(w - u), u + v + w, [nu, nv, nw]));
            let whole = (b - a).cross(c - a);
            // A small piece is a fold only where it also faces against every corner's
            // normal: at a crease the field at its centre may be the other face's. A
            // sliver never is.
            let sliver = self.tolerance * SLIVER_SHARE;
            let corners = [[a, q, c], [q, b, c]];
            let exempt = [0, 1].map(|k| {
                let (f, _, normals) = pieces[k];
                height(corners[k]) < sliver
                    || (f.length() * 0.5 < smallest && normals.iter().any(|m| f.dot(*m) >= 0.0))
            });
            if exempt.iter().all(|&e| e) {
                continue;
            }
            // Pieces within 60° of the triangle cannot face against the field by 154° unless
            // the field turns by more than 94° between their centres: not worth its probes.
            // A piece larger than twice its triangle (a sliver's edge split far off it) is
            // checked whatever the triangle's facing: a sliver's normal says little.
            let grows = pieces
                .iter()
                .any(|(f, _, _)| f.length() > 2.0 * whole.length());
            if !grows
                && pieces
                    .iter()
                    .all(|(f, _, _)| f.dot(whole) >= CREASE_COS * f.length() * whole.length())
            {
                continue;
            }
            let Some((_, n, _)) = self.probe((a + b + c) / 3.0) else {
                continue;
            };
            if !grows && whole.dot(n) < EDGE_ON_COS * whole.length() {
                continue;
            }
            for ((facing, sum, _), exempt) in pieces.into_iter().zip(exempt) {
                if exempt {
                    continue;
                }
                if let Some((_, n, _)) = self.probe(sum / 3.0)
                    && facing.dot(n) < FOLD_COS * facing.length()
                {
                    return true;
                }
            }
        }
        false
    }

    /// Records that one side has been divided at the split edge `a`–`b`; the second side
    /// frees it.
    fn used(&mut self, a: u32, b: u32) {
        let key = (a.min(b), a.max(b));
        if let Some(e) = self.splits.get_mut(&key) {
            e.1 += 1;
            if e.1 >= 2 {
                self.splits.remove(&key);
                self.across.remove(&key);
            }
        }
    }

    /// Whether every side of triangle `t` is longer than [`LONG_CELLS`] cells.
    fn long_sided(&self, t: [u32; 3]) -> bool {
        let p = t.map(|i| self.verts[i as usize].at());
        (0..3).all(|k| (p[k] - p[(k + 1) % 3]).length() > LONG_CELLS * self.cell)
    }

    /// A vertex at the centre of triangle `t`, on the surface, if the centre strays and
    /// no edge of it was split.
    fn centre(&mut self, t: [u32; 3]) -> io::Result<Option<u32>> {
        let v = t.map(|i| self.verts[i as usize]);
        let p = v.map(|x| x.at());
        let lens = [
            (p[1] - p[0]).length(),
            (p[2] - p[1]).length(),
            (p[0] - p[2]).length(),
        ];
        let shortest = lens.iter().copied().fold(f64::INFINITY, f64::min);
        // Not beside a vertex left off the surface: its edges' splits are held to their
        // wedges (`folds_beside_stuck`), and a centre has none to be held to (on a bitten
        // ball under a cell wide, a centre put in the tetrahedron the collapses left turned
        // it inside out).
        if lens.iter().copied().fold(0.0, f64::max) < SHORTEST * self.cell
            || v.iter().any(|x| x.stuck)
            || !(0..3).any(|k| self.may_stray(&v[k], &v[(k + 1) % 3], lens[k]))
        {
            return Ok(None);
        }
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let Some((_, Some((q, n)))) = self.strays(c, shortest * MID_REACH) else {
            return Ok(None);
        };
        // Not if a piece would face against the field both at the new vertex and at its
        // own edge's ends (a fold: the centre is within this one triangle, so leaving it
        // out changes nothing elsewhere).
        let folds = (0..3).any(|k| {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let piece = (b.at() - a.at()).cross(q - a.at());
            piece.dot(n) < 0.0 && piece.dot(a.normal()) < 0.0 && piece.dot(b.normal()) < 0.0
        });
        if folds {
            self.leave_off(c);
            return Ok(None);
        }
        let level = v.iter().map(|x| x.level).max().unwrap_or(0);
        self.emit_vertex(q, n, level + 1).map(Some)
    }

    /// Splits triangle `t` (output indices, counter-clockwise) until its pieces hold the
    /// tolerance, and writes them.
    fn tessellate(&mut self, t: [u32; 3], level: u32, centred: bool) -> io::Result<()> {
        if level < MAX_LEVEL {
            // The longest edge that splits goes first.
            let mut best: Option<(f64, usize, u32)> = None;
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let apex = [a, b, t[(k + 2) % 3]].map(|i| {
                    let v = self.verts[i as usize];
                    (v.at(), v.normal())
                });
                if let Some(m) = self.split(a, b, apex)? {
                    let len = (self.verts[a as usize].at() - self.verts[b as usize].at()).length();
                    if best.is_none_or(|(l, _, _)| len > l) {
                        best = Some((len, k, m));
                    }
                }
            }
            if let Some((_, k, m)) = best {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                // The pieces' new edges, with the triangles beside them: along a-m and m-b
                // this piece and those recorded across a-b (on this side running the same
                // way, on the other the opposite way); m-c lies between the two pieces.
                let recorded: Vec<(u32, bool)> = self
                    .across
                    .get(&(a.min(b), a.max(b)))
                    .map(|e| e.apex[..usize::from(e.seen)].to_vec())
                    .unwrap_or_default();
                let this_way = a < b;
                let along = |x: u32, y: u32| {
                    let mut v = vec![(c, x < y)];
                    v.extend(
                        recorded
                            .iter()
                            .filter(|&&(z, _)| z != c)
                            .map(|&(z, f)| (z, if f == this_way { x < y } else { y < x })),
                    );
                    v.truncate(3);
                    v
                };
                let (am, mb) = (along(a, m), along(m, b));
                self.used(a, b);
                self.note_across(a, m, &am);
                self.note_across(m, b, &mb);
                self.note_across(m, c, &[(a, m < c), (b, c < m)]);
                self.tessellate([a, m, c], level + 1, centred)?;
                return self.tessellate([m, b, c], level + 1, centred);
            }
            if (!centred || self.long_sided(t))
                && let Some(m) = self.centre(t)?
            {
                for k in 0..3 {
                    // Between pieces (t[k-1], t[k], m) and (t[k], t[k+1], m).
                    let (prev, next) = (t[(k + 2) % 3], t[(k + 1) % 3]);
                    self.note_across(t[k], m, &[(prev, t[k] < m), (next, m < t[k])]);
                }
                for k in 0..3 {
                    self.tessellate([t[k], t[(k + 1) % 3], m], level + 1, true)?;
                }
                return Ok(());
            }
        }
        // Written, an unmoved vertex is a place of the mesh off the surface.
        for v in t {
            let vert = &mut self.verts[v as usize];
            if vert.unmoved {
                vert.unmoved = false;
                let at = vert.at();
                self.leave_off(at);
            }
        }
        self.written(t);
        self.forget_written(t);
        let corners = t.map(|i| self.verts[i as usize].pos);
        self.inner.triangle(t, corners)
    }
}

/// The step from a point, in the plane of two gradients, to where two linear functions
/// with values `f1`, `f2` there and gradients `g1`, `g2` are both zero; `None` when the
/// gradients are too near parallel to say.
fn both_planes_step(f1: f64, g1: DVec3, f2: f64, g2: DVec3) -> Option<DVec3> {
    let (a11, a12, a22) = (g1.dot(g1), g1.dot(g2), g2.dot(g2));
    let det = a11 * a22 - a12 * a12;
    // Written so that a NaN determinant says no, too.
    if det.partial_cmp(&(0.05 * a11 * a22)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    // step = α·g1 + β·g2 with g1·step = −f1 and g2·step = −f2.
    let alpha = (-f1 * a22 + a12 * f2) / det;
    let beta = (-f2 * a11 + a12 * f1) / det;
    Some(g1 * alpha + g2 * beta)
}

/// Whether moving the middle of a split edge outward to `q` takes volume away and leaves
/// the wedge of its two sides (the tetrahedron of the edge and their far corners, positive
/// where the surface is convex across the edge) inside out: the split folds the sides over,
/// and a small closed blob can turn inside out (a ball a cell wide did). `outward` is +1
/// where the middle is inside the solid. A side's change of volume is a sixth of the move
/// dotted with its area vector (twice the area, along its normal). Only with both sides
/// known, and neither a sliver, whose facing says little; and only outward: inward moves
/// adding volume to convex wedges along spheres_chain's grooves fail the mirrored test, and
/// without those splits it missed the tolerance (2.0 tolerances).
fn inverts_the_wedge(sides: &[[(DVec3, DVec3); 3]], q: DVec3, outward: f64) -> bool {
    let Some([a, b, c, d]) = wedge_of(sides) else {
        return false;
    };
    let thin = |corners: [DVec3; 3]| height(corners) < THIN * longest_side(corners);
    if outward <= 0.0 || thin([a, b, c]) || thin([b, a, d]) {
        return false;
    }
    let (change, wedge) = split_volumes([a, b, c, d], q);
    change < 0.0 && wedge + change < 0.0
}

/// The longest side of triangle `corners`.
pub(super) fn longest_side([u, v, w]: [DVec3; 3]) -> f64 {
    (v - u).length().max((w - v).length()).max((u - w).length())
}

/// The height of triangle `corners` over its longest side (twice its area over that side);
/// zero for a point.
pub(super) fn height(corners: [DVec3; 3]) -> f64 {
    let [u, v, w] = corners;
    let longest = longest_side(corners);
    if longest > 0.0 {
        (v - u).cross(w - u).length() / longest
    } else {
        0.0
    }
}

/// The edge `a b` and its two sides' far corners `c` and `d`: the first side, and the first
/// that runs along the edge the other way (a piece's edge may also have the corners of the
/// triangles split beside it). `None` until both sides are known.
fn wedge_of(sides: &[[(DVec3, DVec3); 3]]) -> Option<[DVec3; 4]> {
    let &[(a, _), (b, _), (c, _)] = sides.first()?;
    let d = sides.iter().find(|s| s[0].0 == b && s[1].0 == a)?[2].0;
    Some([a, b, c, d])
}

/// Six times the volume a split at `q` adds (the move of the edge's middle dotted with its
/// sides' area vectors), and six times the volume of its wedge (the tetrahedron of the edge
/// and the far corners, positive where the surface is convex across the edge).
fn split_volumes([a, b, c, d]: [DVec3; 4], q: DVec3) -> (f64, f64) {
    let moved = q - (a + b) * 0.5;
    let (abc, bad) = ((b - a).cross(c - a), (a - b).cross(d - b));
    (moved.dot(abc) + moved.dot(bad), -(d - a).dot(abc))
}

/// Whether a split beside a mesher's vertex the refiner could not move onto the surface
/// folds its wedge (the tetrahedron of the edge and its sides' far corners): an outward
/// move that takes away more than half of it, or an inward one that takes away more than
/// all of a convex one. Blobs a cell wide at large tolerances turned inside out there
/// (random CSG cases, session 25): the collapses left a tetrahedron with a corner stuck
/// 0.29 of a cell inside a ball, and two outward splits at that corner, each within the
/// whole-wedge rule of [`inverts_the_wedge`], together took more than the tetrahedron held;
/// on a ball under a cell wide, bitten, a split of a split's edge moved inward and took
/// 0.0016 from a wedge of 0.0003 (six times the volumes).
fn folds_beside_stuck(sides: &[[(DVec3, DVec3); 3]], q: DVec3, outward: f64) -> bool {
    let Some(corners) = wedge_of(sides) else {
        return false;
    };
    let (change, wedge) = split_volumes(corners, q);
    if outward > 0.0 {
        change < 0.0 && wedge + 2.0 * change < 0.0
    } else {
        wedge > 0.0 && wedge + change < 0.0
    }
}

/// Where two tangent planes (a point and its unit normal) on either side of a crease meet,
/// nearest to `mid`: the crease, to first order (as dual contouring's QEF finds it in a
/// cell). `None` when the planes are too near parallel to say.
fn crease_point((pa, na): (DVec3, DVec3), (pb, nb): (DVec3, DVec3), mid: DVec3) -> Option<DVec3> {
    let c = na.dot(nb);
    let det = 1.0 - c * c;
    if na == DVec3::ZERO || nb == DVec3::ZERO || c > CREASE_COS || det < 0.05 {
        return None;
    }
    // mid + α·na + β·nb on both planes.
    let (ra, rb) = (-na.dot(mid - pa), -nb.dot(mid - pb));
    let alpha = (ra - c * rb) / det;
    let beta = (rb - c * ra) / det;
    Some(mid + na * alpha + nb * beta)
}

impl<S: Sampler> MeshSink for Refiner<'_, S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        let at = DVec3::from(p.map(f64::from));
        let (mut stray, mut stuck, mut unmoved) = (false, false, false);
        let (pos, normal) = match self.probe(at) {
            Some((f, n, d)) if d > self.tolerance * MOVE_SHARE => {
                let mut far = false;
                let moved = self.onto_surface(at, REACH * self.cell).filter(|&(q, nq)| {
                    far = (q - at).length() > FAR_MOVE * self.cell;
                    !far || self.thick_around(at, f, (q, nq))
                });
                stray = moved.is_none() && d > STRAY_CELLS * self.cell;
                stuck = moved.is_none() || far;
                unmoved = moved.is_none();
                moved.unwrap_or((at, n))
            }
            Some((_, n, _)) => (at, n),
            None => (at, DVec3::ZERO),
        };
        let id = self.emit_vertex(pos, normal, 0)?;
        if let Some(v) = self.verts.get_mut(id as usize) {
            v.stray = stray;
            v.stuck = stuck;
            v.unmoved = unmoved;
        }
        self.remap.push(id);
        Ok(())
    }

    fn triangle(&mut self, t: [u32; 3], _corners: [[f32; 3]; 3]) -> io::Result<()> {
        let mapped = t.map(|i| self.remap.get(i as usize).copied());
        let [Some(a), Some(b), Some(c)] = mapped else {
            return Err(io::Error::other(format!(
                "triangle {t:?} names a vertex not given yet"
            )));
        };
        self.arrive([a, b, c])
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use isoforge_field::{Bounds, ClippedField, Shape};

    use super::Refiner;
    use crate::check::check;
    use crate::dc::sampler::TapeSampler;
    use crate::deviation::deviation;
    use crate::mesh::Mesh;
    use crate::sink::MeshSink;
    use crate::{MeshSettings, mesh_shape};

    /// Two unit spheres whose centres are 1.95 apart, united: a sharp groove where they
    /// meet (the normals there are 154° apart), as in stacked_sphere_circle.
    fn two_spheres() -> (Shape, Bounds) {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = |c: f64| (x.square() + y.square() + (&z - c).square()).sqrt() - 1.0;
        let shape = ball(0.0).min(&ball(1.95));
        (
            shape,
            Bounds::new([-1.3, -1.3, -1.3], [1.3, 1.3, 3.1]).unwrap(),
        )
    }

    /// The uniform mesh through a refiner.
    fn refined(shape: &Shape, bounds: Bounds, depth: u8, tolerance: f64) -> (Mesh, Mesh) {
        let mut settings = MeshSettings::new(bounds, depth);
        settings.tolerance = Some(0.0);
        let uniform = mesh_shape(shape, &settings);
        let sampler = TapeSampler::new(ClippedField::new(shape, bounds));
        let mut out = Mesh::default();
        let mut refiner = Refiner::new(&sampler, tolerance, &bounds, settings.cell(), &mut out);
        for &v in &uniform.vertices {
            refiner.vertex(v).unwrap();
        }
        for &t in &uniform.triangles {
            refiner
                .triangle(t, t.map(|i| uniform.vertices[i as usize]))
                .unwrap();
        }
        refiner.finish().unwrap();
        (uniform, out)
    }

    #[test]
    fn chords_across_a_groove_are_split_onto_it() {
        let (shape, bounds) = two_spheres();
        let depth = 5;
        let cell = bounds.longest_side() / 32.0;
        let tolerance = 0.1 * cell;
        let (uniform, out) = refined(&shape, bounds, depth, tolerance);
        let field = ClippedField::new(&shape, bounds);
        let before = deviation(&uniform, &field);
        let after = deviation(&out, &field);
        // The fault is there first: chords across the groove miss it by 3.9 tolerances.
        assert!(before.max > 3.0 * tolerance, "before: {before:?}");
        // Then 1.4 (the groove is a third of a cell wide where the chords cross it).
        assert!(
            after.max < 0.4 * before.max,
            "after: {after:?}, before {before:?}"
        );
        assert!(
            after.max <= 1.5 * tolerance,
            "after: {after:?}, tolerance {tolerance}"
        );
        assert!(
            check(&out).is_closed_manifold(),
            "{:?}",
            check(&out).problems()
        );
        assert!(out.triangles.len() > uniform.triangles.len());
    }

    #[test]
    fn newton_arrives_at_the_edge_of_a_sharp_wedge() {
        // max(y − tan(20°)·x, −y − tan(20°)·x): a wedge 40° wide about the x axis, its
        // edge on the z axis. From a point outside, just beyond the edge, one branch at a
        // time zigzags between the faces (cos² 40° ≈ 0.59 closer per pair of steps).
        let (x, y) = (Shape::x(), Shape::y());
        let t = 20f64.to_radians().tan();
        let wedge = (&y - &x * t).max(&(-&y - &x * t));
        let bounds = Bounds::new([-1.0; 3], [1.0; 3]).unwrap();
        let sampler = TapeSampler::new(ClippedField::new(&wedge, bounds));
        let mut out = Mesh::default();
        let tolerance = 1e-4;
        let mut refiner = Refiner::new(&sampler, tolerance, &bounds, 0.1, &mut out);
        let start = DVec3::new(-0.05, 0.001, 0.3);
        let (q, _) = refiner.onto_surface(start, 0.2).expect("arrives");
        let d = q.y.abs() - q.x * t;
        assert!(d.abs() < tolerance, "{q:?} is {d} off");
        // And it is the edge, not a point of a face far from it.
        assert!(q.x.abs() < 0.002 && q.y.abs() < 0.002, "{q:?}");
    }

    #[test]
    fn a_triangle_facing_into_the_solid_gets_no_centre() {
        // A small equilateral triangle on the unit sphere near its pole: its edges' middles
        // hold the tolerance (0.0070 deep, under 0.8 of 0.01) and its centre does not
        // (0.0094), so it gets a vertex at its centre. Wound the other way, it faces into
        // the ball (a fold, as dual contouring leaves some at creases), and a centre would
        // only make three folded pieces of it.
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let bounds = Bounds::new([-1.5; 3], [1.5; 3]).unwrap();
        let sampler = TapeSampler::new(ClippedField::new(&ball, bounds));
        let rho = 0.237 / 3f64.sqrt();
        let corners: Vec<[f32; 3]> = (0..3)
            .map(|k| {
                let a = f64::from(k) * 120f64.to_radians();
                [rho * a.cos(), rho * a.sin(), (1.0 - rho * rho).sqrt()].map(|c| c as f32)
            })
            .collect();
        let pieces = |t: [u32; 3]| {
            let mut out = Mesh::default();
            let mut refiner = Refiner::new(&sampler, 0.01, &bounds, 0.1, &mut out);
            for p in &corners {
                refiner.vertex(*p).unwrap();
            }
            refiner.triangle(t, t.map(|i| corners[i as usize])).unwrap();
            refiner.finish().unwrap();
            out.triangles.len()
        };
        assert_eq!(pieces([0, 1, 2]), 3, "facing out: centred");
        assert_eq!(pieces([0, 2, 1]), 1, "facing in: left whole");
    }

    #[test]
    fn new_vertices_keep_apart() {
        // A wedge whose sharp edge runs across the lattice at a slant: the chords across it
        // split onto one straight crease line, where two edges' new vertices could land a
        // hair apart and make needles.
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let t = 25f64.to_radians().tan();
        let across = &x * 0.8 + &z * 0.6;
        let slab = (&y - &across * t).max(&(-&y - &across * t));
        let shape = slab.max(&((&across - 0.9).max(&(-&across - 0.9))));
        let bounds = Bounds::new([-1.1; 3], [1.1; 3]).unwrap();
        let cell = 2.2 / 64.0;
        let (uniform, out) = refined(&shape, bounds, 6, 0.1 * cell);
        let new: Vec<glam::DVec3> = out.vertices[uniform.vertices.len()..]
            .iter()
            .map(|p| glam::Vec3::from(*p).as_dvec3())
            .collect();
        assert!(
            new.len() > 50,
            "the fault's setting: {} new vertices",
            new.len()
        );
        let mut closest = f64::INFINITY;
        for (i, a) in new.iter().enumerate() {
            for b in &new[i + 1..] {
                closest = closest.min((*a - *b).length());
            }
        }
        assert!(closest >= cell * super::APART * 0.999, "{closest} apart");
        assert!(
            check(&out).is_closed_manifold(),
            "{:?}",
            check(&out).problems()
        );
    }

    #[test]
    fn smooth_parts_go_through_unchanged() {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.0;
        let bounds = Bounds::new([-1.3; 3], [1.3; 3]).unwrap();
        let (uniform, out) = refined(&ball, bounds, 6, 0.1 * 2.6 / 64.0);
        // The same triangles, in an order of their own: a triangle waits for its
        // neighbours across the edges the refiner looks at.
        let sorted = |m: &Mesh| {
            let mut t = m.triangles.clone();
            t.sort_unstable();
            t
        };
        assert_eq!(sorted(&uniform), sorted(&out));
        assert_eq!(uniform.vertices, out.vertices);
    }

    /// cube_holes (fixtures/slice): a 20 mm block with vertical holes 3, 5 and 6 mm across.
    fn block_with_holes() -> (Shape, Bounds) {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let block = (x.abs() - 10.0)
            .max(&(y.abs() - 10.0))
            .max(&((&z - 10.0).abs() - 10.0));
        let hole =
            |cx: f64, cy: f64, r: f64| -(((&x - cx).square() + (&y - cy).square()).sqrt() - r);
        let shape = block
            .max(&hole(-5.0, -5.0, 1.5))
            .max(&hole(5.0, -5.0, 2.5))
            .max(&hole(0.0, 5.0, 3.0));
        (
            shape,
            Bounds::new([-11.0, -11.0, -1.0], [11.0, 11.0, 21.0]).unwrap(),
        )
    }

    #[test]
    fn the_tolerance_holds_at_a_hole_s_rim() {
        // The merge leaves long chords on the block's flat bottom, some between two
        // vertices on a hole's rim, with a flap folded back under them. Both vertices'
        // normals are the bottom's, so by the normals alone the chord could not stray; it
        // crossed the 5 mm hole 0.22 mm inside its rim: 6.4, 12.8 and 26 tolerances at
        // depths 6, 7 and 8 before `LONG_CELLS` and the flaps' flips (`decimate/flaps.rs`).
        let (shape, bounds) = block_with_holes();
        holds_the_tolerance(&shape, bounds, &[6, 7, 8]);
    }

    /// pins (fixtures/slice): five vertical cylinders 1 to 5 mm across, 10 mm tall.
    fn pins() -> (Shape, Bounds) {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let pin = |d: f64, x0: f64| {
            (((&x - x0).square() + y.square()).sqrt() - d / 2.0).max(&((&z - 5.0).abs() - 5.0))
        };
        let shape = pin(1.0, -16.0)
            .min(&pin(2.0, -8.0))
            .min(&pin(3.0, 0.0))
            .min(&pin(4.0, 8.0))
            .min(&pin(5.0, 16.0));
        (
            shape,
            Bounds::new([-20.0, -4.0, -1.0], [20.0, 4.0, 11.0]).unwrap(),
        )
    }

    #[test]
    fn the_tolerance_holds_beside_a_cap_s_rim() {
        // The collapses made strips of the cylinders from cap to cap whose chords on the
        // caps' rims were 1.9 tolerances from the cylinder; the field reads 0 at a chord's
        // middle (it lies on the cap), so the mesh missed by 1.1 tolerances at depth 8
        // before the collapses' samples beside long edges (`decimate::BESIDE_LONG_CELLS`).
        // At depths 6 and 7 it still misses (1.2 and 1.4).
        let (shape, bounds) = pins();
        holds_the_tolerance(&shape, bounds, &[8, 9]);
    }

    #[test]
    fn the_tolerance_holds_where_two_holes_meet() {
        // A block drilled through along x, y and z, as docs/examples/modern/booleans.rhai
        // is: the holes' walls meet on ellipses. Just outside such a ridge the field reads
        // the nearer wall, and at depth 8 a chord along one was 0.78 tolerances off by that
        // reading and 1.02 in truth (`Refiner::strays`).
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let zc = &z - 12.0;
        let block = (x.abs() - 15.0)
            .max(&(y.abs() - 15.0))
            .max(&(zc.abs() - 10.0));
        let hole = |u: &Shape, v: &Shape| -((u.square() + v.square()).sqrt() - 4.0);
        let shape = block
            .max(&hole(&x, &y))
            .max(&hole(&x, &zc))
            .max(&hole(&y, &zc));
        let bounds = Bounds::new([-24.0, -24.0, -4.0], [24.0, 24.0, 28.0]).unwrap();
        holds_the_tolerance(&shape, bounds, &[8]);
    }

    #[test]
    fn the_mesher_holds_the_tolerance_at_a_groove() {
        let (shape, bounds) = two_spheres();
        holds_the_tolerance(&shape, bounds, &[6, 7]);
    }

    /// The whole mesher at each depth, at its default tolerance: within it by the field,
    /// closed and manifold.
    fn holds_the_tolerance(shape: &Shape, bounds: Bounds, depths: &[u8]) {
        for &depth in depths {
            let settings = MeshSettings::new(bounds, depth);
            let mesh = mesh_shape(shape, &settings);
            let d = deviation(&mesh, &ClippedField::new(shape, bounds));
            let tolerance = settings.effective_tolerance();
            assert!(
                d.max <= tolerance,
                "depth {depth}: {d:?}, tolerance {tolerance}"
            );
            assert!(check(&mesh).is_closed_manifold(), "depth {depth}");
        }
    }
}

#[cfg(test)]
mod left_off_tests {
    use std::collections::HashSet;
    use std::sync::Arc;

    use glam::DVec3;
    use isoforge_field::{Bounds, ClippedField, Shape};

    use crate::dc::left_off::place_key;
    use crate::deviation::{deviation, farthest};
    use crate::{MeshNotes, MeshSettings, mesh_shape};

    /// The gyroid's value at the sheet's walls: its gradient is about 5 here, so the sheet
    /// is about 0.06 thick, a cell and a bit at depth 6 (0.25 and more: no place is left).
    const SHEET: f64 = 0.15;

    /// A gyroid sheet in a ball, the sheet thinner than the lattice resolves at depth 6:
    /// where the lattice bridges it, the splits onto the surface would fold the mesh.
    fn sheet_in_a_ball() -> (Shape, Bounds) {
        let (x, y, z) = (Shape::x(), Shape::y(), Shape::z());
        let k = 4.0;
        let (sx, sy, sz) = ((&x * k).sin(), (&y * k).sin(), (&z * k).sin());
        let (cx, cy, cz) = ((&x * k).cos(), (&y * k).cos(), (&z * k).cos());
        let gyroid = (sx * cy + sy * cz + sz * cx).abs() - SHEET;
        let ball = (x.square() + y.square() + z.square()).sqrt() - 1.5;
        (gyroid.max(&ball), Bounds::new([-1.6; 3], [1.6; 3]).unwrap())
    }

    #[test]
    fn places_left_off_are_points_of_the_mesh_and_measure_its_misses() {
        let (shape, bounds) = sheet_in_a_ball();
        let notes = Arc::new(MeshNotes::default());
        let mut settings = MeshSettings::new(bounds, 6);
        settings.notes = Some(notes.clone());
        let mesh = mesh_shape(&shape, &settings);
        let places = notes.left_off.lock().unwrap().clone();
        // The fault first: there are places, and the mesh misses its tolerance.
        assert!(!places.is_empty(), "no place left off");
        let found = notes
            .left_off_found
            .load(std::sync::atomic::Ordering::Relaxed);
        assert_eq!(found, places.len() as u64, "all kept, each once");
        let field = ClippedField::new(&shape, bounds);
        let tolerance = settings.effective_tolerance();
        let whole = deviation(&mesh, &field);
        assert!(whole.max > tolerance, "{whole:?}");

        // Each place is a corner, an edge's middle or a centre of a triangle written.
        let mut on_mesh = HashSet::new();
        for &t in &mesh.triangles {
            let [a, b, c] = t.map(|i| DVec3::from(mesh.vertices[i as usize].map(f64::from)));
            for p in [a, b, c, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5] {
                on_mesh.insert(place_key(p.to_array()));
            }
            for centre in [(a + b + c) / 3.0, (b + c + a) / 3.0, (c + a + b) / 3.0] {
                on_mesh.insert(place_key(centre.to_array()));
            }
        }
        let off: Vec<_> = places
            .iter()
            .filter(|p| !on_mesh.contains(&place_key(**p)))
            .collect();
        assert!(
            off.is_empty(),
            "{} of {} not on the mesh: {off:?}",
            off.len(),
            places.len()
        );

        // Measured, the farthest misses the tolerance, by no more than the whole mesh does
        // (its sample points include every place), and it is one of the mesh's farthest
        // sample points' distances only if the whole measure found it there.
        let (largest, at) = farthest(&field, &places).expect("places");
        assert!(
            largest > tolerance,
            "largest place {largest}, tolerance {tolerance}"
        );
        assert!(largest <= whole.max + 1e-12, "{largest} > {}", whole.max);
        assert!(places.contains(&at));
    }
}
