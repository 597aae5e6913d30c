//! Hermite data of a block: corner signs agreed with the neighbours, the crossing on every
//! sign-changing lattice edge (batched bisection) and the surface normal there.
//!
//! Corner signs must be one value per lattice corner, or cells on both sides of a block
//! face would disagree about the surface between them. Each block samples its own corners
//! (`own_signs`); a corner on a block's boundary then takes, in every block that holds it,
//! the same value ([`canonical_signs`]): empty or full if any block holding it was proved
//! empty or full by intervals (that is a proof, and it guarantees that no sign change
//! touches a pruned block), else the sample of its owner, the block whose half-open range
//! holds it.

use glam::DVec3;

use super::octree::{Class, Grid};
use super::sampler::Sampler;

/// Bisection rounds on each crossing. After 6 halvings the bracket is 1/64 of a cell;
/// the final linear interpolation on the bracket makes smooth surfaces far finer.
const BISECTION_ROUNDS: usize = 6;

/// A crossing of the surface on a lattice edge.
#[derive(Clone, Copy, Debug)]
pub struct Crossing {
    /// Where F changes sign.
    pub pos: DVec3,
    /// Unit outward normal.
    pub normal: DVec3,
}

/// Reusable per-thread buffers.
#[derive(Default)]
pub struct Scratch {
    xs: Vec<f64>,
    ys: Vec<f64>,
    zs: Vec<f64>,
    out: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    flo: Vec<f64>,
    fhi: Vec<f64>,
}

/// Corners per block side.
pub fn side(grid: &Grid) -> usize {
    grid.block + 1
}

/// Local corner index.
pub fn corner_index(s: usize, i: usize, j: usize, k: usize) -> usize {
    i + s * (j + s * k)
}

/// Samples F at every corner of a block and packs "inside" bits.
#[allow(clippy::too_many_arguments)]
pub fn own_signs<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    local: &S::Local,
    grid: &Grid,
    coords: [i64; 3],
    scratch: &mut Scratch,
    bits: &mut [u64],
) {
    let s = side(grid);
    let n = s * s * s;
    let base = coords.map(|c| c * grid.block as i64);
    let sc = scratch;
    sc.xs.clear();
    sc.ys.clear();
    sc.zs.clear();
    for k in 0..s {
        for j in 0..s {
            for i in 0..s {
                let p = grid.corner([base[0] + i as i64, base[1] + j as i64, base[2] + k as i64]);
                sc.xs.push(p[0]);
                sc.ys.push(p[1]);
                sc.zs.push(p[2]);
            }
        }
    }
    sc.out.clear();
    sc.out.resize(n, 0.0);
    sampler.batch(ev, local, &sc.xs, &sc.ys, &sc.zs, &mut sc.out);
    bits.fill(0);
    for (c, &f) in sc.out.iter().enumerate() {
        if f < 0.0 {
            bits[c / 64] |= 1 << (c % 64);
        }
    }
}

/// The agreed sign of every corner of a block (1 = inside). `neighbours[(dx+1) + 3(dy+1) +
/// 9(dz+1)]` is the class of the block at offset (dx, dy, dz); `bits_of(b)` the own signs
/// of ambiguous block `b`.
pub fn canonical_signs<'b>(
    grid: &Grid,
    neighbours: &[Class; 27],
    bits_of: impl Fn(u32) -> &'b [u64],
    out: &mut Vec<u8>,
) {
    let s = side(grid);
    let b = grid.block;
    out.clear();
    out.resize(s * s * s, 0);
    let Class::Block(me) = neighbours[13] else {
        return;
    };
    let mine = bits_of(me);
    for k in 0..s {
        for j in 0..s {
            for i in 0..s {
                let c = corner_index(s, i, j, k);
                let l = [i, j, k];
                let interior = l.iter().all(|&v| v > 0 && v < b);
                out[c] = if interior {
                    (mine[c / 64] >> (c % 64) & 1) as u8
                } else {
                    boundary_sign(s, b, l, neighbours, &bits_of)
                };
            }
        }
    }
}

fn boundary_sign<'b>(
    s: usize,
    b: usize,
    l: [usize; 3],
    neighbours: &[Class; 27],
    bits_of: &impl Fn(u32) -> &'b [u64],
) -> u8 {
    // Offsets of the blocks holding this corner, per axis.
    let range = |v: usize| -> (i64, i64) {
        if v == 0 {
            (-1, 0)
        } else if v == b {
            (0, 1)
        } else {
            (0, 0)
        }
    };
    let (rx, ry, rz) = (range(l[0]), range(l[1]), range(l[2]));
    let (mut any_empty, mut any_full) = (false, false);
    for dz in rz.0..=rz.1 {
        for dy in ry.0..=ry.1 {
            for dx in rx.0..=rx.1 {
                match neighbours[((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)) as usize] {
                    Class::Empty => any_empty = true,
                    Class::Full => any_full = true,
                    Class::Block(_) => {}
                }
            }
        }
    }
    if any_empty {
        return 0;
    }
    if any_full {
        return 1;
    }
    // The owner: the block whose half-open range holds the corner.
    let o = l.map(|v| usize::from(v == b));
    let Class::Block(owner) = neighbours[(o[0] + 1) + 3 * (o[1] + 1) + 9 * (o[2] + 1)] else {
        return 0;
    };
    let c = corner_index(s, l[0] - o[0] * b, l[1] - o[1] * b, l[2] - o[2] * b);
    (bits_of(owner)[c / 64] >> (c % 64) & 1) as u8
}

/// A sign-changing lattice edge of a block: axis and local start corner.
#[derive(Clone, Copy, Debug)]
pub struct EdgeRef {
    /// The axis.
    pub axis: u8,
    /// Local start corner index.
    pub corner: u32,
}

/// Finds every sign-changing edge of the closed block, its crossing and normal. Fills
/// `edge_slot[axis * s³ + corner]` with the crossing's index.
#[allow(clippy::too_many_arguments)]
pub fn crossings<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    local: &S::Local,
    grid: &Grid,
    coords: [i64; 3],
    signs: &[u8],
    scratch: &mut Scratch,
    edges: &mut Vec<EdgeRef>,
    edge_slot: &mut Vec<u32>,
    out: &mut Vec<Crossing>,
) {
    let s = side(grid);
    let n = s * s * s;
    let stride = [1, s, s * s];
    edges.clear();
    edge_slot.clear();
    edge_slot.resize(3 * n, u32::MAX);
    out.clear();
    for k in 0..s {
        for j in 0..s {
            for i in 0..s {
                let c = corner_index(s, i, j, k);
                let l = [i, j, k];
                for a in 0..3 {
                    if l[a] + 1 < s && signs[c] != signs[c + stride[a]] {
                        edge_slot[a * n + c] = edges.len() as u32;
                        edges.push(EdgeRef {
                            axis: a as u8,
                            corner: c as u32,
                        });
                    }
                }
            }
        }
    }
    let m = edges.len();
    if m == 0 {
        return;
    }
    let base = coords.map(|c| c * grid.block as i64);
    let start = |e: &EdgeRef| {
        let c = e.corner as usize;
        let l = [c % s, (c / s) % s, c / (s * s)];
        grid.corner([0, 1, 2].map(|i| base[i] + l[i] as i64))
    };
    let sc = scratch;
    sc.lo.clear();
    sc.lo.resize(m, 0.0);
    sc.hi.clear();
    sc.hi.resize(m, 1.0);
    sc.flo.clear();
    sc.flo.resize(m, f64::NAN);
    sc.fhi.clear();
    sc.fhi.resize(m, f64::NAN);
    for _ in 0..BISECTION_ROUNDS {
        sc.xs.clear();
        sc.ys.clear();
        sc.zs.clear();
        for (e, edge) in edges.iter().enumerate() {
            let mut p = start(edge);
            p[edge.axis as usize] += 0.5 * (sc.lo[e] + sc.hi[e]) * grid.cell;
            sc.xs.push(p[0]);
            sc.ys.push(p[1]);
            sc.zs.push(p[2]);
        }
        sc.out.clear();
        sc.out.resize(m, 0.0);
        sampler.batch(ev, local, &sc.xs, &sc.ys, &sc.zs, &mut sc.out);
        for (e, edge) in edges.iter().enumerate() {
            let f = sc.out[e];
            let mid = 0.5 * (sc.lo[e] + sc.hi[e]);
            let start_inside = signs[edge.corner as usize] == 1;
            if (f < 0.0) == start_inside {
                sc.lo[e] = mid;
                sc.flo[e] = f;
            } else {
                sc.hi[e] = mid;
                sc.fhi[e] = f;
            }
        }
    }
    // A bracket still touching an edge end has no value there: sample those ends (few:
    // crossings within 1/2^rounds of a corner, such as caps on the region's faces), so
    // the interpolation below applies to them too.
    sc.xs.clear();
    sc.ys.clear();
    sc.zs.clear();
    let mut ends = Vec::new();
    for (e, edge) in edges.iter().enumerate() {
        for (t, known) in [(0.0, sc.flo[e]), (1.0, sc.fhi[e])] {
            if known.is_nan() {
                let mut p = start(edge);
                p[edge.axis as usize] += t * grid.cell;
                sc.xs.push(p[0]);
                sc.ys.push(p[1]);
                sc.zs.push(p[2]);
                ends.push((e, t == 0.0));
            }
        }
    }
    if !ends.is_empty() {
        sc.out.clear();
        sc.out.resize(ends.len(), 0.0);
        sampler.batch(ev, local, &sc.xs, &sc.ys, &sc.zs, &mut sc.out);
        for (k, &(e, at_lo)) in ends.iter().enumerate() {
            let f = sc.out[k];
            if at_lo { sc.flo[e] = f } else { sc.fhi[e] = f }
        }
    }
    for (e, edge) in edges.iter().enumerate() {
        let (lo, hi, flo, fhi) = (sc.lo[e], sc.hi[e], sc.flo[e], sc.fhi[e]);
        // Interpolate on the final bracket when both ends were sampled with finite,
        // opposite values; otherwise take its middle.
        let t = if flo.is_finite() && fhi.is_finite() && (flo < 0.0) != (fhi < 0.0) {
            let w = flo / (flo - fhi);
            lo + (hi - lo) * w.clamp(0.0, 1.0)
        } else {
            0.5 * (lo + hi)
        };
        // Never exactly on a corner: crossings of edges that share a corner must stay
        // distinct points (they may become polygon centres).
        let t = t.clamp(1e-3, 1.0 - 1e-3);
        let a = edge.axis as usize;
        let mut pos = start(edge);
        pos[a] += t * grid.cell;
        let mut outward = [0.0; 3];
        outward[a] = if signs[edge.corner as usize] == 1 {
            1.0
        } else {
            -1.0
        };
        let normal = normal_at(sampler, ev, local, grid.cell, pos, outward.into(), sc);
        out.push(Crossing {
            pos: pos.into(),
            normal,
        });
    }
}

/// `v / |v|`, unless `|v|` is infinite, NaN or too small to divide by.
fn unit(v: DVec3) -> Option<DVec3> {
    let len = v.length();
    (len.is_finite() && len > 1e-300).then(|| v / len)
}

/// The outward normal: the gradient of F; where that is NaN, infinite or zero, a central
/// finite difference of F; where that fails too, the edge's own direction (inside corner
/// to outside corner), which is always a sane plane for the QEF, so no vertex can fly off.
#[allow(clippy::too_many_arguments)]
fn normal_at<S: Sampler>(
    sampler: &S,
    ev: &mut S::Evals,
    local: &S::Local,
    cell: f64,
    p: [f64; 3],
    outward: DVec3,
    sc: &mut Scratch,
) -> DVec3 {
    // Where the region's face caps the model, this is the face's normal (see
    // `isoforge_field::clip_grad`).
    let g = sampler.grad(ev, local, p);
    if let Some(n) = unit(DVec3::new(g[1], g[2], g[3])) {
        return n;
    }
    let h = cell * 1e-3;
    sc.xs.clear();
    sc.ys.clear();
    sc.zs.clear();
    for a in 0..3 {
        for sign in [1.0, -1.0] {
            let mut q = p;
            q[a] += sign * h;
            sc.xs.push(q[0]);
            sc.ys.push(q[1]);
            sc.zs.push(q[2]);
        }
    }
    sc.out.clear();
    sc.out.resize(6, 0.0);
    sampler.batch(ev, local, &sc.xs, &sc.ys, &sc.zs, &mut sc.out);
    let fd = DVec3::from([0, 1, 2].map(|a| sc.out[2 * a] - sc.out[2 * a + 1]));
    unit(fd).unwrap_or(outward)
}
