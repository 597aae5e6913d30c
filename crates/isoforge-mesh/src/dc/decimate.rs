//! Edge collapses on the streamed mesh, checked against the field: what the octree merge
//! cannot do along sharp edges that run across the lattice.
//!
//! A leaf has one vertex, so a leaf edge may hold one crossing (`topology.rs`). Along a
//! cube's edge turned off the lattice, lattice lines enter and leave the solid within a
//! cell or two, and no leaf there grows past a few cells: the turned cube (fixtures/flat)
//! was 16,224 triangles at depth 9, nearly all of them along its 12 edges. Here those
//! triangles are collapsed away, as in Garland and Heckbert's simplification (1997) with
//! half-edge collapses (a vertex moves onto a neighbour that stays where dual contouring
//! put it, so vertices on creases and corners stay there):
//!
//! * a collapse `b → a` is tried only when both fans are complete (every triangle around
//!   `a` and `b` has come) and neither vertex has been written out;
//! * the link condition (the vertices next to both `a` and `b` are exactly the two
//!   opposite the edge) keeps the mesh a closed 2-manifold (Dey et al. 1999); no triangle
//!   may turn more than 60°, face against the field's gradient, or sweep more than a
//!   little volume;
//! * the tolerance: sample points on every new triangle within it by the field (|F| /
//!   |∇F|, exact inside a convex crease, where chords run); around a crease, where dual
//!   contouring's own triangles already miss it, as much as they did and at most twice it;
//! * only crease vertices, vertices where the area-weighted quadric says the surface is
//!   flat, and collapses onto a crease vertex are tried: smooth parts are already as coarse
//!   as the octree merge allows.
//!
//! Before the collapses, flaps (two triangles folded back onto each other across an edge,
//! as the merge leaves at some curved creases) are unfolded by flipping the edge
//! (`flaps.rs`).
//!
//! Where the field is made of planes, two more steps: before the collapses, vertices are
//! put on the planes and edges that cut a crease are split at it (`planes.rs`); after each
//! round, a vertex the collapses left may be removed and its hole filled by ear clipping
//! in its planes (`removal.rs`), which covers holes no fan from a neighbour can.
//!
//! Memory stays bounded: triangles are collapsed [`CHUNK`] at a time, the vertices of fans
//! still open at a chunk's end frozen (written, not moved) until the next chunk closes them.
//! A full chunk is collapsed only where collapsing pays ([`PAYS_PER_VERTEX`]); after one
//! that would not, the rest goes on unchanged. Smooth meshes are already as coarse as the
//! merge allows: on the gyroid sphere at depth 9, collapsing every chunk cost a third more
//! time and 14 MiB more for 15 % fewer triangles. Faceted ones are not: an imported STL
//! (drilled_import) at depth 9 came out at 162,362 triangles when only meshes of one chunk
//! were collapsed, 19,580 chunk by chunk.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::io;

use glam::DVec3;

use super::narrowed::Narrowed;
use super::sampler::Sampler;
use crate::sink::MeshSink;

mod flaps;
mod planes;
mod removal;
#[cfg(test)]
mod tests;

/// The most triangles collapsed: a few MiB of working structures. The turned cube at depth
/// 9 (16,224 merged triangles) and the heart fit; at 2^18, spheres_chain at depth 9 (176,048)
/// took 3.3 times as long and 26 MiB more to lose 7 % of its triangles.
pub const CHUNK: usize = 1 << 16;

/// A full chunk is collapsed when it has at least this many collapses to try (edges of
/// crease and flat vertices) per vertex whose fan is complete. Measured: knurled_knob's
/// first chunk at depth 8 3.30 (collapsing kept 11 % of its triangles), drilled_import's
/// (an imported STL's facets) at depth 9 3.18; smooth first chunks at depth 8: spheres_chain
/// 0.68, sinus_sphere 0.70, tetrahedron_hull 0.90, gyroid_sphere 1.13, which kept 77 to
/// 83 % for 0.3 to 1.1 s a chunk (docs/meshing.md, session 29).
const PAYS_PER_VERTEX: f64 = 2.0;

/// The collapses (and the refiner's splits) keep within this many finest cells of the
/// surface whatever the tolerance: a triangle's sample points say little about a surface
/// that bends within it. At 20 cells the thin sheets of a gyroid sphere filled in (volume
/// 1.76 for 0.8); at 1 cell a ball 3.3 cells wide in a corner of the region (tolerance 3
/// cells, a random CSG case) collapsed to 6 triangles, two of them facing into it, and the
/// refiner's splits then turned it inside out. The default tolerance is under this.
pub const MAX_CELLS: f64 = 0.5;

/// A new triangle's normal may turn at most this far from the one it replaces (cosine).
const MIN_TURN_COS: f64 = 0.5;

/// Rounds of collapses at most. On the turned cube a second round finds a few more; a
/// third none.
const ROUNDS: usize = 3;

/// Away from creases, a collapse is tried only where the quadric's mean distance is
/// below this share of the tolerance: the octree merge has already made smooth parts as
/// coarse as the tolerance allows, and trying them all cost the gyroid sphere at depth 9
/// a third more time for 15 % fewer triangles.
const FLAT_SHARE: f64 = 0.1;

/// A new triangle's normal and the field's gradient at its sample points may differ by
/// at most this much (cosine, 120°): enough to turn away a triangle folded over, while the
/// small triangles dual contouring leaves across a crease, whose normals run along it,
/// still pass (at 0 the turned cube at depth 9 kept 2,392 triangles).
const FACING_COS: f64 = -0.5;

/// Around a crease, new triangles may miss the surface by as much as the old ones did, but
/// by no more than this many tolerances. Unbounded, the allowance spread along the creases
/// of a coarse gyroid sphere (depth 5) and took a third of its volume; at 3 a one-cell blob
/// of the 256 sign patterns turned inside out; at 2 the turned cube at depth 9 is 1,576
/// triangles (2,896 with no allowance).
const CREASE_ALLOWANCE: f64 = 2.0;

/// A collapse tried only because its target is a crease vertex keeps within this share of
/// the tolerance (the refiner's split threshold).
const ONTO_CREASE_SHARE: f64 = 0.8;

/// Unit gradients nearer than this are the same plane's (a linear field's gradient is the
/// same to rounding; a unit sphere's at depth 9 turns by 0.007 per cell).
const PLANAR: f64 = 1e-6;

/// Two normals around a vertex that differ by more than this (cosine, 84°) make it a
/// crease or corner vertex. At 0.3 and 0.8 DC's small triangles on the gyroid counted as
/// creases too, and the collapses there took twice the time.
const CREASE_COS: f64 = 0.1;

/// Edges longer than this many finest cells get one more sample point, beside their
/// middle, [`BESIDE_SHARE`] of the way to the corner opposite. A chord along a convex crease
/// lies on one face, and the field reads 0 at its middle; the triangle under it, on the
/// other face, may be off: on pins (fixtures/slice) the collapses made cylinder strips from
/// cap to cap whose chords on the caps' rims were 1.9 tolerances from the cylinder, and the
/// mesh missed the tolerance by 1.1 (with the extra point: held, 794 -> 536 triangles).
const BESIDE_LONG_CELLS: f64 = 2.0;

/// How far toward the opposite corner the point beside a long edge's middle lies.
const BESIDE_SHARE: f64 = 0.1;

/// Triangles lower than this fraction of their longest side are slivers.
const SLIVER: f64 = 0.05;

/// Sample points on a new triangle, in barycentric coordinates: the edge middles and the
/// centre (its corners are vertices, placed on the surface already).
const SAMPLES: [[f64; 3]; 4] = [
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
];

/// A vertex written out whose fan is still open.
#[derive(Clone, Debug)]
struct Frozen {
    out: u32,
    pos: [f32; 3],
    /// Per neighbour, how often it starts minus ends an edge of the fan's rim so far.
    rim: Vec<(u32, i32)>,
}

/// Sums of squared distances to planes, around an origin: `xᵀ A x − 2 bᵀ x + c`.
#[derive(Clone, Copy, Debug, Default)]
struct Quadric {
    a: [f64; 6],
    b: DVec3,
    c: f64,
    /// The weights summed.
    n: f64,
}

impl Quadric {
    /// The plane through `p` with unit normal `n`, of weight `w`.
    fn plane(n: DVec3, p: DVec3, w: f64) -> Self {
        let d = n.dot(p);
        let m = n * w;
        Quadric {
            a: [
                m.x * n.x,
                m.x * n.y,
                m.x * n.z,
                m.y * n.y,
                m.y * n.z,
                m.z * n.z,
            ],
            b: m * d,
            c: w * d * d,
            n: w,
        }
    }
    fn add(&mut self, o: &Quadric) {
        for (s, t) in self.a.iter_mut().zip(o.a) {
            *s += t;
        }
        self.b += o.b;
        self.c += o.c;
        self.n += o.n;
    }
    fn at(&self, x: DVec3) -> f64 {
        let a = &self.a;
        let ax = DVec3::new(
            a[0] * x.x + a[1] * x.y + a[2] * x.z,
            a[1] * x.x + a[3] * x.y + a[4] * x.z,
            a[2] * x.x + a[4] * x.y + a[5] * x.z,
        );
        (x.dot(ax) - 2.0 * self.b.dot(x) + self.c).max(0.0)
    }
    /// The weighted mean squared distance at `x`.
    fn mean_at(&self, x: DVec3) -> f64 {
        if self.n > 0.0 {
            self.at(x) / self.n
        } else {
            0.0
        }
    }
}

/// A sink that collapses what the tolerance allows before passing the mesh on.
pub struct Decimator<'a, S: Sampler> {
    sampler: &'a S,
    ev: S::Evals,
    /// The field, narrowed to boxes around the points asked about.
    field: Narrowed<S>,
    tolerance: f64,
    /// The finest cell's size.
    cell: f64,
    inner: &'a mut dyn MeshSink,
    /// Input index of the chunk's first vertex.
    base: u32,
    /// The chunk's vertices, from `base` on.
    verts: Vec<[f32; 3]>,
    /// The chunk's triangles, in input indices.
    tris: Vec<[u32; 3]>,
    /// Written vertices with open fans, by input index.
    frozen: HashMap<u32, Frozen>,
    /// Output vertices so far.
    written: u32,
    /// Input vertices so far.
    seen: u32,
    /// Set once a full chunk would not pay: everything after it goes straight on.
    through: Option<Through>,
    /// At most this many triangles per chunk ([`CHUNK`]; smaller in tests).
    chunk: usize,
}

/// Where passing straight on began: input vertices from `base` on are written as they come,
/// numbered from `out`; earlier ones are frozen vertices of the last chunk.
#[derive(Clone, Copy)]
struct Through {
    base: u32,
    out: u32,
}

impl<'a, S: Sampler> Decimator<'a, S> {
    /// Collapses within `tolerance` (model units) on the way to `inner`.
    pub fn new(sampler: &'a S, tolerance: f64, cell: f64, inner: &'a mut dyn MeshSink) -> Self {
        Decimator {
            sampler,
            ev: sampler.evals(),
            field: Narrowed::new(sampler, cell),
            tolerance,
            cell,
            inner,
            base: 0,
            verts: Vec::new(),
            tris: Vec::new(),
            frozen: HashMap::new(),
            written: 0,
            seen: 0,
            through: None,
            chunk: CHUNK,
        }
    }

    /// The same with chunks of at most `chunk` triangles (tests run the seams on small
    /// meshes).
    #[cfg(test)]
    pub fn with_chunk(mut self, chunk: usize) -> Self {
        self.chunk = chunk.max(1);
        self
    }

    /// Collapses and writes what is held; call once the mesher is done.
    pub fn finish(&mut self) -> io::Result<()> {
        if self.through.is_some() {
            return Ok(());
        }
        self.flush(false)
    }

    /// One round: collapse, write, keep the open fans' vertices frozen. A `full` chunk
    /// (more may come) is collapsed only where that pays; if not, it is written as it came
    /// and so is everything after it. The last chunk, or a mesh of one, always is.
    fn flush(&mut self, full: bool) -> io::Result<()> {
        let mut chunk = Chunk::new(self)?;
        let pays = !full || chunk.pays(self.tolerance);
        if pays {
            chunk.collapse(self);
        }
        chunk.write(self)?;
        if !pays {
            // All held vertices were written or frozen by `write`; from here on they go
            // straight on, numbered after the written ones.
            self.through = Some(Through {
                base: self.seen,
                out: self.written,
            });
        }
        Ok(())
    }

    /// The output index of input vertex `v` once passing straight on.
    fn through_index(&self, th: Through, v: u32) -> io::Result<u32> {
        if v >= th.base {
            return Ok(th.out + (v - th.base));
        }
        self.frozen
            .get(&v)
            .map(|f| f.out)
            .ok_or_else(|| io::Error::other("internal error: a vertex of a closed fan came again"))
    }
}

impl<S: Sampler> MeshSink for Decimator<'_, S> {
    fn vertex(&mut self, p: [f32; 3]) -> io::Result<()> {
        if self.through.is_some() {
            self.seen += 1;
            self.written += 1;
            return self.inner.vertex(p);
        }
        self.verts.push(p);
        self.seen += 1;
        Ok(())
    }

    fn triangle(&mut self, t: [u32; 3], corners: [[f32; 3]; 3]) -> io::Result<()> {
        if let Some(th) = self.through {
            let ids = [
                self.through_index(th, t[0])?,
                self.through_index(th, t[1])?,
                self.through_index(th, t[2])?,
            ];
            return self.inner.triangle(ids, corners);
        }
        self.tris.push(t);
        if self.tris.len() >= self.chunk {
            self.flush(true)?;
        }
        Ok(())
    }
}

/// The working structures of one round, in chunk-local vertex indices: the chunk's own
/// vertices first, then the frozen ones its triangles use.
struct Chunk {
    pos: Vec<DVec3>,
    /// Input index of each local vertex.
    input: Vec<u32>,
    /// Fan complete (and not frozen): may take part in a collapse.
    free: Vec<bool>,
    /// On a crease or corner: the normals around it spread wide.
    crease: Vec<bool>,
    alive_v: Vec<bool>,
    quadric: Vec<Quadric>,
    /// Triangles around each vertex (indices into `tris`; dead ones filtered when read).
    around: Vec<Vec<u32>>,
    tris: Vec<[u32; 3]>,
    alive_t: Vec<bool>,
    /// Each triangle's distance from the surface at its sample points, once measured
    /// (NaN until then).
    dev: Vec<f64>,
    /// Around this point the quadrics are summed (precision).
    origin: DVec3,
    /// The field's plane at each vertex (`planes.rs`), once measured.
    plane: Vec<Option<planes::Plane>>,
    /// Vertices added on creases so far.
    added: u32,
}

impl Chunk {
    fn new<S: Sampler>(d: &mut Decimator<'_, S>) -> io::Result<Self> {
        let n = d.verts.len();
        let mut input: Vec<u32> = (0..n as u32).map(|i| d.base + i).collect();
        let mut pos: Vec<DVec3> = d.verts.iter().map(|&p| to_d(p)).collect();
        let mut frozen = vec![false; n];
        let mut local_of_frozen: HashMap<u32, u32> = HashMap::new();
        let tris_in = std::mem::take(&mut d.tris);
        let mut tris = Vec::with_capacity(tris_in.len());
        for t in tris_in {
            let mut lt = [0u32; 3];
            for (l, &v) in lt.iter_mut().zip(&t) {
                *l = if v >= d.base {
                    v - d.base
                } else if let Some(&l) = local_of_frozen.get(&v) {
                    l
                } else {
                    // Earlier vertices are either frozen or had complete fans.
                    let f = d.frozen.get(&v).ok_or_else(|| {
                        io::Error::other("internal error: a triangle of a finished vertex")
                    })?;
                    input.push(v);
                    pos.push(to_d(f.pos));
                    frozen.push(true);
                    local_of_frozen.insert(v, (input.len() - 1) as u32);
                    (input.len() - 1) as u32
                };
            }
            tris.push(lt);
        }
        let m = pos.len();
        let origin = pos.first().copied().unwrap_or(DVec3::ZERO);
        let mut around = vec![Vec::new(); m];
        let mut quadric = vec![Quadric::default(); m];
        let mut rim: Vec<Vec<(u32, i32)>> = vec![Vec::new(); m];
        for (i, t) in tris.iter().enumerate() {
            let [p, q, r] = t.map(|v| pos[v as usize] - origin);
            let n = (q - p).cross(r - p);
            // Weighted by area: a sliver's plane says little about the surface.
            let plane = if n.length_squared() > 0.0 {
                Quadric::plane(n.normalize(), p, n.length() / 2.0)
            } else {
                Quadric::default()
            };
            for k in 0..3 {
                let v = t[k] as usize;
                around[v].push(i as u32);
                quadric[v].add(&plane);
                tally(&mut rim[v], t[(k + 1) % 3], 1);
                tally(&mut rim[v], t[(k + 2) % 3], -1);
            }
        }
        let free = (0..m)
            .map(|v| !frozen[v] && !around[v].is_empty() && rim[v].iter().all(|e| e.1 == 0))
            .collect();
        let crease = (0..m)
            .map(|v| {
                let normals: Vec<DVec3> = around[v]
                    .iter()
                    .map(|&t| tris[t as usize].map(|w| pos[w as usize]))
                    .filter(|t| !sliver(t))
                    .map(|t| (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero())
                    .collect();
                normals
                    .iter()
                    .enumerate()
                    .any(|(i, n)| normals[i + 1..].iter().any(|o| n.dot(*o) < CREASE_COS))
            })
            .collect();
        Ok(Chunk {
            crease,
            alive_v: vec![true; m],
            alive_t: vec![true; tris.len()],
            dev: vec![f64::NAN; tris.len()],
            pos,
            input,
            free,
            quadric,
            around,
            tris,
            origin,
            plane: Vec::new(),
            added: 0,
        })
    }

    /// The live triangles around `v`.
    fn fan(&self, v: u32) -> impl Iterator<Item = u32> + '_ {
        self.around[v as usize]
            .iter()
            .copied()
            .filter(|&t| self.alive_t[t as usize])
    }

    /// The vertices next to `v`, sorted.
    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut out: Vec<u32> = self
            .fan(v)
            .flat_map(|t| self.tris[t as usize])
            .filter(|&w| w != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn cost(&self, b: u32, a: u32) -> f64 {
        let mut q = self.quadric[a as usize];
        q.add(&self.quadric[b as usize]);
        q.mean_at(self.pos[a as usize] - self.origin)
    }

    /// Whether collapsing `b` (at quadric cost `cost`) would be tried whatever its target:
    /// `b` is a crease vertex, or the surface there is flat.
    fn tried_for_itself(&self, b: u32, cost: f64, flat: f64) -> bool {
        self.crease[b as usize] || cost <= flat
    }

    /// Whether collapsing this chunk pays: enough collapses to try per vertex that may
    /// take part ([`PAYS_PER_VERTEX`]).
    fn pays(&self, tolerance: f64) -> bool {
        let flat = flat_cost(tolerance);
        let (mut tries, mut free) = (0usize, 0usize);
        for v in 0..self.pos.len() as u32 {
            if !self.free[v as usize] {
                continue;
            }
            free += 1;
            tries += self
                .neighbours(v)
                .into_iter()
                .filter(|&w| self.to_try(v, w, flat).is_some())
                .count();
        }
        tries as f64 >= PAYS_PER_VERTEX * free as f64
    }

    /// The quadric cost of collapsing `b → a` when that collapse is to be tried: both fans
    /// complete, and `b` a crease vertex or on a flat surface, or `a` on a crease.
    fn to_try(&self, b: u32, a: u32, flat: f64) -> Option<f64> {
        if !(self.free[b as usize] && self.free[a as usize]) {
            return None;
        }
        let cost = self.cost(b, a);
        (self.tried_for_itself(b, cost, flat) || self.crease[a as usize]).then_some(cost)
    }

    /// Greedy collapses, cheapest first, in rounds until a round finds none (a collapse
    /// can unblock one next to it that was refused before).
    fn collapse<S: Sampler>(&mut self, d: &mut Decimator<'_, S>) {
        let flat = flat_cost(d.tolerance);
        if flat.is_nan() || flat <= 0.0 {
            return;
        }
        let mut heap = BinaryHeap::new();
        // Crease vertices are tried whatever their quadric (the triangles cutting the
        // crease weigh in it), and so are collapses onto them: a face's vertex a fraction
        // of a cell from a crease has the triangles cutting it in its quadric but is no
        // crease vertex itself, and it stops every collapse along the crease past it (the
        // triangles between would turn over). Elsewhere only where the surface is flat.
        let push = |c: &Chunk, heap: &mut BinaryHeap<_>, b: u32, a: u32| {
            if let Some(cost) = c.to_try(b, a, flat) {
                heap.push(Reverse((cost.to_bits(), b, a)));
            }
        };
        self.unfold_flaps(d);
        self.measure_planes(d);
        self.snap_onto_planes(d);
        self.split_across_creases(d);
        self.snap_onto_planes(d);
        for _ in 0..ROUNDS {
            let mut done = 0usize;
            for v in 0..self.pos.len() as u32 {
                if !self.free[v as usize] || !self.alive_v[v as usize] {
                    continue;
                }
                for w in self.neighbours(v) {
                    push(self, &mut heap, v, w);
                }
            }
            while let Some(Reverse((bits, b, a))) = heap.pop() {
                if !(self.alive_v[b as usize] && self.alive_v[a as usize]) {
                    continue;
                }
                // Quadrics only grow: a changed cost goes back in its new place.
                if self.cost(b, a).to_bits() != bits {
                    push(self, &mut heap, b, a);
                    continue;
                }
                if !self.can_collapse(d, b, a) {
                    continue;
                }
                self.apply(b, a);
                done += 1;
                for w in self.neighbours(a) {
                    push(self, &mut heap, w, a);
                    push(self, &mut heap, a, w);
                }
            }
            // Where collapses stop on planes, a vertex may still go with its hole filled
            // otherwise (`removal.rs`); the collapses next to it are tried again after.
            for v in 0..self.pos.len() as u32 {
                if self.free[v as usize] && self.alive_v[v as usize] && self.try_remove(d, v) {
                    done += 1;
                }
            }
            if done == 0 {
                break;
            }
        }
    }

    /// True when `b → a` keeps the mesh a closed 2-manifold (the link condition, no
    /// tetrahedron folded flat), turns no triangle over, and keeps the surface within
    /// the tolerance by the field.
    fn can_collapse<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, b: u32, a: u32) -> bool {
        let (na, nb) = (self.neighbours(a), self.neighbours(b));
        if nb.binary_search(&a).is_err() {
            return false;
        }
        let shared: Vec<u32> = na
            .iter()
            .copied()
            .filter(|v| nb.binary_search(v).is_ok())
            .collect();
        let opposite: Vec<u32> = self
            .fan(b)
            .map(|t| self.tris[t as usize])
            .filter(|t| t.contains(&a))
            .map(|t| t.iter().copied().find(|&v| v != a && v != b).unwrap_or(a))
            .collect();
        if opposite.len() != 2 || shared.len() != 2 || !opposite.iter().all(|v| shared.contains(v))
        {
            return false;
        }
        // `a` keeps at least three neighbours, or a tetrahedron would fold flat; with three,
        // a closed tetrahedron must stay the right way out.
        let kept = na.len() + nb.len() - shared.len() - 2;
        if kept < 3 || kept == 3 && !self.leaves_a_tetrahedron_outward(b, a, &na, &nb) {
            return false;
        }
        let pa = self.pos[a as usize];
        let pb = self.pos[b as usize];
        let min_area = (d.tolerance * d.tolerance) * 1e-6;
        let mut new_tris = Vec::new();
        // The volume the collapse sweeps, signed, against the fan's area: a tolerance's
        // depth over the fan at most, or the surface folds (a small closed blob can turn
        // inside out with every triangle turning a little).
        let (mut six_volume, mut twice_area) = (0.0, 0.0);
        for t in self.fan(b) {
            let [p, q, r] = self.tris[t as usize].map(|v| self.pos[v as usize] - pb);
            twice_area += (q - p).cross(r - p).length();
            // Tetrahedron from b's old place to b's new one under this triangle.
            let k = self.tris[t as usize]
                .iter()
                .position(|&v| v == b)
                .unwrap_or(0);
            let (u, w) = ([p, q, r][(k + 1) % 3], [p, q, r][(k + 2) % 3]);
            six_volume += (pa - pb).dot(u.cross(w));
        }
        if six_volume.abs() / 6.0 > d.tolerance * CREASE_ALLOWANCE * twice_area / 2.0 {
            return false;
        }
        for t in self.fan(b) {
            let tri = self.tris[t as usize];
            if tri.contains(&a) {
                continue;
            }
            let old = tri.map(|v| self.pos[v as usize]);
            let new = tri.map(|v| if v == b { pa } else { self.pos[v as usize] });
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]);
            let n_new = (new[1] - new[0]).cross(new[2] - new[0]);
            if n_new.length_squared() <= min_area * min_area {
                return false;
            }
            let turn = n_new.normalize().dot(n_old.normalize_or_zero());
            if turn.is_nan() || turn < MIN_TURN_COS {
                return false;
            }
            new_tris.push(new);
        }
        // A collapse tried only because `a` is on a crease keeps a margin, as the refiner's
        // splits do: the field's first-order distance reads a little less than the
        // distance along the gradient that `check --against` measures (at the full
        // tolerance, sphere_circle at depth 8 missed it by 1.001 tolerances).
        let bound = if self.tried_for_itself(b, self.cost(b, a), flat_cost(d.tolerance)) {
            d.tolerance
        } else {
            ONTO_CREASE_SHARE * d.tolerance
        };
        if new_tris
            .iter()
            .all(|t| self.deviation(d, t, bound, true) <= bound)
        {
            return true;
        }
        // Where the triangles around a crease already missed the tolerance (dual
        // contouring cuts creases), the new ones may miss it by as much, never more: the
        // worst place does not get worse. So may a collapse onto a crease between planes.
        let at_crease =
            self.crease[b as usize] || self.crease[a as usize] && self.planes_around(d, b, a);
        if !at_crease {
            return false;
        }
        let fan: Vec<u32> = self.fan(b).collect();
        let mut allowance = d.tolerance;
        for t in fan {
            allowance = allowance.max(self.known_deviation(d, t));
        }
        let allowance = allowance.min(d.tolerance * CREASE_ALLOWANCE);
        allowance > d.tolerance
            && new_tris
                .iter()
                .all(|t| self.deviation(d, t, allowance, true) <= allowance)
    }

    /// Whether collapsing `b` onto `a`, where `a` is left with three neighbours, leaves a
    /// closed tetrahedron the right way out (or no tetrahedron at all): a blob smaller than
    /// a cell can come down to four vertices nearly in one plane, and the last collapse
    /// decides which way it faces (a ball under a cell wide came out inside out). `na` and
    /// `nb` are the neighbours of `a` and `b`.
    fn leaves_a_tetrahedron_outward(&self, b: u32, a: u32, na: &[u32], nb: &[u32]) -> bool {
        let mut around: Vec<u32> = na.to_vec();
        around.extend(nb);
        around.sort_unstable();
        around.dedup();
        around.retain(|&v| v != a && v != b);
        let &[x, y, z] = around.as_slice() else {
            return true;
        };
        // The base: a live triangle on the three neighbours, in whichever order it runs.
        let Some(base) = self
            .fan(x)
            .map(|t| self.tris[t as usize])
            .find(|t| t.contains(&y) && t.contains(&z))
        else {
            return true;
        };
        let pa = self.pos[a as usize];
        let [p, q, r] = base.map(|v| self.pos[v as usize] - pa);
        // The base faces away from `a` on a tetrahedron the right way out.
        p.dot(q.cross(r)) > 0.0
    }

    /// Whether the field is planar on each side of the crease through `a` next to `b`: its
    /// unit gradients at `a`, `b` and their neighbours take at most two values. Only
    /// there does a collapse onto the crease get the crease's allowance: the refiner's
    /// crease points (where tangent planes meet) lie on the crease exactly when the faces
    /// are planes, and its splits then take the allowance back; on curved faces they did not
    /// (sphere_circle missed the tolerance by 1.8, stacked_sphere_circle by 3.6).
    fn planes_around<S: Sampler>(&self, d: &mut Decimator<'_, S>, b: u32, a: u32) -> bool {
        let mut around = self.neighbours(b);
        around.extend(self.neighbours(a));
        around.sort_unstable();
        around.dedup();
        let normals = around.into_iter().map(|v| self.normal_at(d, v));
        planes::at_most_two(normals, |m, n| m.distance(*n) < PLANAR).is_some()
    }

    /// The largest distance from the surface, by the field, of a triangle's sample
    /// points; infinite as soon as one is beyond `stop` (or the field says nothing), or,
    /// with `facing`, as soon as the field's gradient there points against the triangle's
    /// normal (a fold: with every triangle turning less than the limit, a small closed
    /// blob could still turn inside out at a large tolerance).
    fn deviation<S: Sampler>(
        &self,
        d: &mut Decimator<'_, S>,
        t: &[DVec3; 3],
        stop: f64,
        facing: bool,
    ) -> f64 {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let mut worst = 0.0f64;
        // Beside each long edge too: a chord along a convex crease lies on one face, where
        // the field reads 0 at its middle, while the triangle under it on the other face
        // is off ([`BESIDE_LONG_CELLS`]).
        let beside = (0..3)
            .filter(|&k| (t[(k + 1) % 3] - t[k]).length() > BESIDE_LONG_CELLS * d.cell)
            .map(|k| {
                let mut w = [0.0; 3];
                w[k] = 0.5 * (1.0 - BESIDE_SHARE);
                w[(k + 1) % 3] = 0.5 * (1.0 - BESIDE_SHARE);
                w[(k + 2) % 3] = BESIDE_SHARE;
                w
            });
        for w in SAMPLES.iter().copied().chain(beside) {
            let p = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
            let g = d.field.grad(d.sampler, &mut d.ev, p);
            let grad = DVec3::new(g[1], g[2], g[3]);
            let distance = g[0].abs() / grad.length();
            let faces_out = grad.dot(n) > FACING_COS * grad.length() * n.length();
            if distance.is_nan() || distance > stop || facing && !faces_out {
                return f64::INFINITY;
            }
            worst = worst.max(distance);
        }
        worst
    }

    /// The largest distance of triangle `t`'s sample points from the surface, measured
    /// once.
    fn known_deviation<S: Sampler>(&mut self, d: &mut Decimator<'_, S>, t: u32) -> f64 {
        let known = self.dev[t as usize];
        if !known.is_nan() {
            return known;
        }
        let tri = self.tris[t as usize].map(|v| self.pos[v as usize]);
        // Where the field says nothing (NaN), the triangle allows nothing more.
        let e = self.deviation(d, &tri, f64::MAX, false);
        let e = if e.is_finite() { e } else { 0.0 };
        self.dev[t as usize] = e;
        e
    }

    /// A new vertex at `p` (on a crease, `planes.rs`), on `plane`, whose fan is to come
    /// whole. Its input index counts down from the top, where no mesher's vertex is.
    fn add_vertex(&mut self, p: DVec3, plane: Option<planes::Plane>) -> u32 {
        let id = self.pos.len() as u32;
        self.added += 1;
        self.pos.push(p);
        self.input.push(u32::MAX - self.added);
        self.free.push(true);
        self.crease.push(true);
        self.alive_v.push(true);
        self.quadric.push(Quadric::default());
        self.around.push(Vec::new());
        self.plane.push(plane);
        id
    }

    /// A new live triangle.
    fn add_triangle(&mut self, t: [u32; 3]) {
        let id = self.tris.len() as u32;
        self.tris.push(t);
        self.alive_t.push(true);
        self.dev.push(f64::NAN);
        for v in t {
            self.around[v as usize].push(id);
        }
    }

    fn apply(&mut self, b: u32, a: u32) {
        let fan: Vec<u32> = self.fan(b).collect();
        for t in fan {
            let tri = &mut self.tris[t as usize];
            if tri.contains(&a) {
                self.alive_t[t as usize] = false;
                continue;
            }
            for v in tri.iter_mut() {
                if *v == b {
                    *v = a;
                }
            }
            self.dev[t as usize] = f64::NAN;
            self.around[a as usize].push(t);
        }
        self.crease[a as usize] |= self.crease[b as usize];
        let qb = self.quadric[b as usize];
        self.quadric[a as usize].add(&qb);
        self.alive_v[b as usize] = false;
        self.around[b as usize].clear();
    }

    /// Writes the live triangles and the vertices they use; vertices with open fans stay
    /// frozen for the next chunk.
    fn write<S: Sampler>(self, d: &mut Decimator<'_, S>) -> io::Result<()> {
        let m = self.pos.len();
        let own = d.verts.len();
        let mut out = vec![u32::MAX; m];
        for (v, o) in out.iter_mut().enumerate().skip(own) {
            if let Some(f) = d.frozen.get(&self.input[v]) {
                *o = f.out;
            }
        }
        // Rims of the fans as written, to tell which stay open.
        let mut rim: Vec<Vec<(u32, i32)>> = vec![Vec::new(); m];
        for (t, tri) in self.tris.iter().enumerate() {
            if !self.alive_t[t] {
                continue;
            }
            for k in 0..3 {
                let v = tri[k] as usize;
                if out[v] == u32::MAX {
                    out[v] = d.written;
                    d.written += 1;
                    d.inner.vertex(self.position(d, v))?;
                }
                let (p, q) = (
                    self.input[tri[(k + 1) % 3] as usize],
                    self.input[tri[(k + 2) % 3] as usize],
                );
                tally(&mut rim[v], p, 1);
                tally(&mut rim[v], q, -1);
            }
            let ids = tri.map(|v| out[v as usize]);
            let corners = tri.map(|v| self.position(d, v as usize));
            if ids.contains(&u32::MAX) {
                return Err(io::Error::other("internal error: a vertex never written"));
            }
            d.inner.triangle(ids, corners)?;
        }
        // Vertices that came but have no triangle yet are open too: their triangles wait
        // for merges above the blocks.
        for v in 0..own {
            if !self.alive_v[v] {
                continue;
            }
            let open = self.around[v].iter().all(|&t| !self.alive_t[t as usize])
                || rim[v].iter().any(|e| e.1 != 0);
            if !open {
                continue;
            }
            if out[v] == u32::MAX {
                out[v] = d.written;
                d.written += 1;
                d.inner.vertex(d.verts[v])?;
            }
            d.frozen.insert(
                d.base + v as u32,
                Frozen {
                    out: out[v],
                    pos: d.verts[v],
                    rim: std::mem::take(&mut rim[v]),
                },
            );
        }
        for (&key, rim) in self.input.iter().zip(&rim).skip(own) {
            let closed = match d.frozen.get_mut(&key) {
                Some(f) => {
                    for &(w, n) in rim {
                        tally(&mut f.rim, w, n);
                    }
                    f.rim.iter().all(|e| e.1 == 0)
                }
                None => false,
            };
            if closed {
                d.frozen.remove(&key);
            }
        }
        d.base = d.seen;
        d.verts.clear();
        Ok(())
    }

    /// Where vertex `v` is written: the mesher's own (or moved) vertices, frozen ones as
    /// they were written, and vertices added on creases (`planes.rs`) where they were put.
    fn position<S: Sampler>(&self, d: &Decimator<'_, S>, v: usize) -> [f32; 3] {
        match d.verts.get(v) {
            Some(p) => *p,
            None => match d.frozen.get(&self.input[v]) {
                Some(f) => f.pos,
                None => self.pos[v].as_vec3().to_array(),
            },
        }
    }
}

/// The quadric cost under which a vertex counts as on a flat surface (see [`FLAT_SHARE`]).
fn flat_cost(tolerance: f64) -> f64 {
    (tolerance * FLAT_SHARE).powi(2)
}

/// True when a triangle's height is below [`SLIVER`] of its longest side.
fn sliver(t: &[DVec3; 3]) -> bool {
    let longest2 = (0..3)
        .map(|k| t[k].distance_squared(t[(k + 1) % 3]))
        .fold(0.0, f64::max);
    let twice_area = (t[1] - t[0]).cross(t[2] - t[0]).length();
    // height = 2 area / longest side
    twice_area * twice_area < SLIVER * SLIVER * longest2 * longest2
}

fn to_d(p: [f32; 3]) -> DVec3 {
    DVec3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

/// Adds `n` to `w`'s count.
fn tally(rim: &mut Vec<(u32, i32)>, w: u32, n: i32) {
    match rim.iter_mut().find(|e| e.0 == w) {
        Some(e) => e.1 += n,
        None => rim.push((w, n)),
    }
}
