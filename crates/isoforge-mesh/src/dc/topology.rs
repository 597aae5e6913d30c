//! When eight octree cells may become one without changing the mesh's topology.
//!
//! The test looks at the 27 corner signs of the eight children (the parent's corners, edge
//! midpoints, face centres and centre) and asks that the surface inside the parent, as the
//! children draw it, be the one the parent alone would draw: a single disk that crosses each
//! parent edge at most once and meets each parent face in one curve. It is the idea of
//! Ju et al. 2002 (§4.1, after Gerstner and Pajarola) and of Schaefer, Ju and Warren's
//! manifold dual contouring (2007, the Euler-characteristic test), written for this
//! mesher's face rule (an ambiguous face pairs its crossings around its inside corners;
//! a finest cell with a face joined the other way, `leaf.rs`, never merges):
//!
//! 1. every child has at most one patch, and the parent's own sign pattern has exactly one
//!    patch and no ambiguous face, so the parent is one vertex with one ring around it;
//! 2. each parent edge: its middle agrees with one of its ends (the two half-edges hold at
//!    most one crossing between them, and each half holds at most one by induction);
//! 3. each parent face: the four child faces on it draw no closed loop (so their curves join
//!    the face's two crossings, or are absent, as the parent face's own segment does);
//! 4. inside: the children's patches, glued along the segments on shared faces, are one
//!    connected surface with Euler characteristic 1 (V − E + F over crossings, face
//!    segments and patches), i.e. a disk (its boundary is one loop, by 1 and 3).
//!
//! Why this is enough for a manifold mesh whatever the neighbours' sizes: a leaf's vertex is
//! surrounded by the polygons of the crossing edges on its boundary, in the order of the
//! surface's curve along the boundary. Neighbours cut the leaf's faces into smaller squares,
//! each drawing its own segments; because every square at every level on the face draws the
//! same curves as its children did (tests 2 and 3, applied when each square's cell was
//! merged), any such cut draws curves isotopic to the leaf's own ring. So the ring is one
//! loop, and the vertex's fan is one disk.

use super::cell::{CASES, other_axes};

/// The sign of grid point `(i, j, k)`, each 0..=2, of the 3×3×3 child corner grid.
#[inline]
fn at(signs: u32, p: [usize; 3]) -> bool {
    signs >> (p[0] + 3 * p[1] + 9 * p[2]) & 1 == 1
}

/// The corner pattern of child `c` (offsets `c & 1`, `c >> 1 & 1`, `c >> 2 & 1`): bit `k`
/// set when its corner `k` is inside.
fn child_pattern(signs: u32, c: usize) -> u8 {
    let o = [c & 1, c >> 1 & 1, c >> 2 & 1];
    let mut pattern = 0u8;
    for k in 0..8 {
        let p = [o[0] + (k & 1), o[1] + (k >> 1 & 1), o[2] + (k >> 2 & 1)];
        pattern |= u8::from(at(signs, p)) << k;
    }
    pattern
}

/// The parent's corner pattern: the grid's eight outer corners.
pub fn parent_pattern(signs: u32) -> u8 {
    let mut pattern = 0u8;
    for k in 0..8 {
        let p = [2 * (k & 1), 2 * (k >> 1 & 1), 2 * (k >> 2 & 1)];
        pattern |= u8::from(at(signs, p)) << k;
    }
    pattern
}

/// True when any face of a cell with this corner pattern is ambiguous (inside corners
/// diagonal, four crossings).
pub fn has_ambiguous_face(pattern: u8) -> bool {
    (0..3).any(|n| {
        let (u, v) = other_axes(n);
        (0..2).any(|side| {
            let corner = |a: usize, b: usize| pattern >> ((side << n) | (a << u) | (b << v)) & 1;
            let (s00, s10, s01, s11) = (corner(0, 0), corner(1, 0), corner(0, 1), corner(1, 1));
            s00 == s11 && s10 == s01 && s00 != s10
        })
    })
}

/// The segments of one square face with corner signs `s[a][b]` (a along u, b along v):
/// pairs of its edges, edges numbered 0: b = 0 (along u), 1: b = 1, 2: a = 0 (along v),
/// 3: a = 1. An ambiguous square pairs the edges around each inside corner.
fn square_segments(s: [[bool; 2]; 2]) -> ([[usize; 2]; 2], usize) {
    let crossing = [
        s[0][0] != s[1][0],
        s[0][1] != s[1][1],
        s[0][0] != s[0][1],
        s[1][0] != s[1][1],
    ];
    let n = crossing.iter().filter(|&&c| c).count();
    match n {
        2 => {
            let mut e = crossing
                .iter()
                .enumerate()
                .filter(|(_, c)| **c)
                .map(|(i, _)| i);
            let (a, b) = (e.next().unwrap_or(0), e.next().unwrap_or(0));
            ([[a, b], [0, 0]], 1)
        }
        4 => {
            if s[0][0] {
                // Inside at (0,0) and (1,1): edges 0 and 2 meet at (0,0), 1 and 3 at (1,1).
                ([[0, 2], [1, 3]], 2)
            } else {
                // Inside at (1,0) and (0,1): edges 0 and 3 meet at (1,0), 1 and 2 at (0,1).
                ([[0, 3], [1, 2]], 2)
            }
        }
        _ => ([[0, 0], [0, 0]], 0),
    }
}

/// Union-find over a handful of items.
struct Sets<const N: usize>([u8; N]);

impl<const N: usize> Sets<N> {
    fn new() -> Self {
        let mut p = [0u8; N];
        for (i, v) in p.iter_mut().enumerate() {
            *v = i as u8;
        }
        Sets(p)
    }
    fn find(&mut self, mut a: usize) -> usize {
        while self.0[a] as usize != a {
            a = self.0[a] as usize;
        }
        a
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.0[ra.max(rb)] = ra.min(rb) as u8;
        }
    }
}

/// The point of the grid at `(u, v)` on the plane `w` along axis `n`.
fn grid_point(n: usize, w: usize, u: usize, v: usize) -> [usize; 3] {
    let (au, av) = other_axes(n);
    let mut p = [0; 3];
    p[n] = w;
    p[au] = u;
    p[av] = v;
    p
}

/// Test 3 on the face of axis `n` at `w` (0 or 2): no closed loop among the four child
/// squares' segments.
fn face_has_no_loop(signs: u32, n: usize, w: usize) -> bool {
    // Unit edges of the 3×3 grid on the face: along u at (a, b) for a in 0..2, b in 0..3 is
    // `a + 2 b`; along v at (a, b) for a in 0..3, b in 0..2 is `6 + a + 3 b`.
    let along_u = |a: usize, b: usize| a + 2 * b;
    let along_v = |a: usize, b: usize| 6 + a + 3 * b;
    let on_rim = |e: usize| {
        if e < 6 {
            let b = e / 2;
            b == 0 || b == 2
        } else {
            let a = (e - 6) % 3;
            a == 0 || a == 2
        }
    };
    let mut sets: Sets<12> = Sets::new();
    let mut used = [false; 12];
    for a in 0..2 {
        for b in 0..2 {
            let s = [0, 1].map(|da| [0, 1].map(|db| at(signs, grid_point(n, w, a + da, b + db))));
            // The square's edges 0..4 as unit edges of the face grid.
            let edge = [
                along_u(a, b),
                along_u(a, b + 1),
                along_v(a, b),
                along_v(a + 1, b),
            ];
            let (segs, count) = square_segments(s);
            for seg in &segs[..count] {
                let (x, y) = (edge[seg[0]], edge[seg[1]]);
                used[x] = true;
                used[y] = true;
                sets.union(x, y);
            }
        }
    }
    // A component with no unit edge on the face's rim is a closed loop.
    let mut reaches_rim = [false; 12];
    for (e, &u) in used.iter().enumerate() {
        if u && on_rim(e) {
            let r = sets.find(e);
            reaches_rim[r] = true;
        }
    }
    (0..12).all(|e| !used[e] || reaches_rim[sets.find(e)])
}

/// True when the eight children whose 27 corner signs are `signs` (bit `i + 3j + 9k` for
/// grid point `(i, j, k)`, set when inside) may merge into one cell with one vertex. The
/// caller checks that each child is itself a leaf (a merged cell or a finest cell).
///
/// The answer depends on the 27 bits alone, and smooth surfaces show the same few thousand
/// patterns over and over, so each thread keeps the last answers in a small direct-mapped
/// table: the test was a fifth of meshing time on the gyroid before it.
pub fn collapsible(signs: u32) -> bool {
    thread_local! {
        static CACHE: std::cell::RefCell<Vec<u32>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    // An entry is the 27 bits, bit 27 the answer, bit 31 "filled".
    const SLOTS: usize = 1 << 14;
    CACHE.with(|cache| {
        let mut cache = cache.borrow_mut();
        if cache.is_empty() {
            cache.resize(SLOTS, 0);
        }
        let slot = (signs.wrapping_mul(0x9e37_79b1) >> 18) as usize % SLOTS;
        let entry = cache[slot];
        if entry >> 31 == 1 && entry & ((1 << 27) - 1) == signs {
            return entry >> 27 & 1 == 1;
        }
        let answer = collapsible_uncached(signs);
        cache[slot] = 1 << 31 | u32::from(answer) << 27 | signs;
        answer
    })
}

/// [`collapsible`] without the cache.
pub fn collapsible_uncached(signs: u32) -> bool {
    // 1. One patch for the parent.
    let parent = parent_pattern(signs);
    if CASES[parent as usize].patches != 1 || has_ambiguous_face(parent) {
        return false;
    }
    // 2. Each parent edge crossed at most once.
    for a in 0..3 {
        let (b, c) = other_axes(a);
        for ub in [0, 2] {
            for uc in [0, 2] {
                let point = |t: usize| {
                    let mut p = [0; 3];
                    p[a] = t;
                    p[b] = ub;
                    p[c] = uc;
                    at(signs, p)
                };
                let (s0, s1, s2) = (point(0), point(1), point(2));
                if s1 != s0 && s1 != s2 {
                    return false;
                }
            }
        }
    }
    // 1, continued: none or one patch for each child.
    let patterns: [u8; 8] = std::array::from_fn(|c| child_pattern(signs, c));
    if patterns.iter().any(|&p| CASES[p as usize].patches > 1) {
        return false;
    }
    // 3. No closed loop on a parent face.
    for n in 0..3 {
        for w in [0, 2] {
            if !face_has_no_loop(signs, n, w) {
                return false;
            }
        }
    }
    // 4. The children's surface is one disk: V − E + F = 1 and connected.
    let mut vertices = 0i32;
    for a in 0..3 {
        let (b, c) = other_axes(a);
        for t in 0..2 {
            for ub in 0..3 {
                for uc in 0..3 {
                    let mut p = [0; 3];
                    p[a] = t;
                    p[b] = ub;
                    p[c] = uc;
                    let mut q = p;
                    q[a] = t + 1;
                    if at(signs, p) != at(signs, q) {
                        vertices += 1;
                    }
                }
            }
        }
    }
    let mut edges = 0i32;
    let mut sets: Sets<8> = Sets::new();
    for n in 0..3 {
        for w in 0..3 {
            for a in 0..2 {
                for b in 0..2 {
                    let s = [0, 1]
                        .map(|da| [0, 1].map(|db| at(signs, grid_point(n, w, a + da, b + db))));
                    let (_, count) = square_segments(s);
                    edges += count as i32;
                    if w == 1 && count > 0 {
                        // An inner face: its segments join the patches of the two children
                        // on either side of it.
                        let (au, av) = other_axes(n);
                        let mut lo = [0usize; 3];
                        lo[au] = a;
                        lo[av] = b;
                        let child = |side: usize| {
                            let mut o = lo;
                            o[n] = side;
                            o[0] | o[1] << 1 | o[2] << 2
                        };
                        sets.union(child(0), child(1));
                    }
                }
            }
        }
    }
    let with_patch: Vec<usize> = (0..8)
        .filter(|&c| CASES[patterns[c] as usize].patches == 1)
        .collect();
    let faces = with_patch.len() as i32;
    let Some(&first) = with_patch.first() else {
        return false;
    };
    let root = sets.find(first);
    if with_patch.iter().any(|&c| sets.find(c) != root) {
        return false;
    }
    vertices - edges + faces == 1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 27 signs of a field sampled on the 3×3×3 grid over [0, 2]³.
    fn signs_of(f: impl Fn([f64; 3]) -> f64) -> u32 {
        let mut s = 0u32;
        for k in 0..3 {
            for j in 0..3 {
                for i in 0..3 {
                    if f([i as f64, j as f64, k as f64]) < 0.0 {
                        s |= 1 << (i + 3 * j + 9 * k);
                    }
                }
            }
        }
        s
    }

    #[test]
    fn a_plane_through_the_cell_collapses() {
        assert!(collapsible(signs_of(|p| p[2] - 0.7)));
        assert!(collapsible(signs_of(|p| p[0] + 0.3 * p[1]
            - 0.4 * p[2]
            - 1.1)));
    }

    #[test]
    fn homogeneous_and_bubbles_do_not() {
        assert!(!collapsible(0));
        assert!(!collapsible((1 << 27) - 1));
        // Only the centre inside: a bubble the parent cannot see.
        assert!(!collapsible(1 << 13));
        // Only a face centre inside.
        assert!(!collapsible(1 << (1 + 3)));
    }

    #[test]
    fn an_edge_crossed_twice_does_not() {
        // Inside only at the middle of the edge along x at y = z = 0, and around it: the
        // parent corners are all outside.
        assert!(!collapsible(signs_of(
            |p| (p[0] - 1.0).abs() + p[1] + p[2] - 0.5
        )));
    }

    #[test]
    fn a_tunnel_through_the_cell_does_not() {
        // A slab with a hole: inside where |z − 1| < 0.6, except near the z axis through
        // the centre. The parent sees a plain slab (corners outside) – or nothing.
        let f = |p: [f64; 3]| {
            let slab = (p[2] - 1.0).abs() - 0.6;
            let hole = 0.4 - ((p[0] - 1.0).powi(2) + (p[1] - 1.0).powi(2)).sqrt();
            slab.max(hole)
        };
        assert!(!collapsible(signs_of(f)));
    }

    /// A small xorshift generator: the sweeps below need many cases, not a dependency.
    fn next(x: &mut u64) -> f64 {
        *x ^= *x << 13;
        *x ^= *x >> 7;
        *x ^= *x << 17;
        (*x >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn every_plane_that_the_parent_sees_collapses() {
        // A plane cuts any cube in one disk that crosses each edge at most once: whenever
        // the parent's corners see it, the merge must be allowed.
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut seen = 0;
        for _ in 0..20_000 {
            let n = [next(&mut x) - 0.5, next(&mut x) - 0.5, next(&mut x) - 0.5];
            let d = next(&mut x) * 3.0 - 1.5 + 1e-7;
            let signs =
                signs_of(|p| n[0] * (p[0] - 1.0) + n[1] * (p[1] - 1.0) + n[2] * (p[2] - 1.0) - d);
            let parent = parent_pattern(signs);
            if parent != 0 && parent != 255 {
                seen += 1;
                assert!(collapsible(signs), "plane {n:?} {d}");
            }
        }
        assert!(seen > 5_000);
    }

    #[test]
    fn small_balls_inside_the_cell_never_collapse() {
        // A ball that misses every parent corner is a surface the parent cannot draw.
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..20_000 {
            let c = [
                0.2 + 1.6 * next(&mut x),
                0.2 + 1.6 * next(&mut x),
                0.2 + 1.6 * next(&mut x),
            ];
            let r = 0.1 + 0.9 * next(&mut x);
            let signs = signs_of(|p| {
                (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2) - r * r
            });
            if parent_pattern(signs) == 0 {
                assert!(!collapsible(signs), "ball {c:?} {r}");
            }
        }
    }

    #[test]
    fn the_cache_gives_the_uncached_answers() {
        let mut x = 0x1234_5678_9abc_def1u64;
        let mut planes = Vec::new();
        for _ in 0..2000 {
            let n = [next(&mut x) - 0.5, next(&mut x) - 0.5, next(&mut x) - 0.5];
            let d = next(&mut x) * 2.0 - 1.0;
            planes.push(signs_of(|p| {
                n[0] * (p[0] - 1.0) + n[1] * (p[1] - 1.0) + n[2] * (p[2] - 1.0) - d
            }));
            planes.push((next(&mut x) * (1u64 << 27) as f64) as u32);
        }
        // Twice over, so the second round reads the cache.
        for _ in 0..2 {
            for &s in &planes {
                assert_eq!(collapsible(s), collapsible_uncached(s), "{s:#x}");
            }
        }
    }
}
