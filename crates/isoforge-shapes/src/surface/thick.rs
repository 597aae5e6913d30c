//! The field of a surface thickened into a solid: `thickness / 2` either side of it.
//!
//! Round edges: the solid is every point within `thickness / 2` of the surface, so the
//! field is the exact distance to the surface less half the thickness, and its edges are
//! half-cylinders. Flat edges: the slab is cut off where the surface ends, by walls
//! standing on its boundary along its normals, like a sheet cut with scissors.
//!
//! The distance comes from a closest-point search: the surface's patches are split (de
//! Casteljau) until each piece is small and nearly flat; a hierarchy over the pieces'
//! control-point boxes (each piece lies inside its box) finds the pieces near a point, and
//! on each a few Newton steps on |S(u, v) − p|² find the closest point, starting from the
//! best of its centre and corners. The interval callback is rigorous from below: nothing
//! of the surface is nearer a box than the nearest piece's box.

use glam::{DMat2, DVec2, DVec3};
use isoforge_field::{CustomField, Interval};

use super::Surface;
use super::patch::Patch;
use crate::bound::{finite_box, widened};
use crate::bvh::{Box3, Bvh};

/// How the slab ends at the surface's boundary.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Edges {
    /// Half-cylinders: the exact offset of the surface.
    Round,
    /// Walls along the surface's normals.
    Flat,
}

/// Pieces are split until their box is this fraction of the surface's size (and flat to
/// [`FLATNESS`]): small enough that Newton from the best corner never leaves its piece's
/// basin, large enough that a surface makes at most a few thousand pieces.
const PIECE_SIZE: f64 = 1.0 / 16.0;
/// How far a piece's control points may stray from its corners' bilinear patch, relative
/// to the surface's size.
const FLATNESS: f64 = 1e-3;
/// The most halvings of a patch: 4⁶ = 4096 pieces.
const MAX_SPLITS: usize = 6;
/// Newton steps on a piece; each roughly doubles the correct digits once close.
const NEWTON_STEPS: usize = 12;

/// The nearest point of the surface to a query point.
#[derive(Copy, Clone, Debug)]
pub struct Foot {
    /// The point.
    pub point: DVec3,
    /// The surface's parameters there.
    pub s: f64,
    /// As `s`.
    pub t: f64,
    /// ∂S/∂s and ∂S/∂t there.
    pub ds: DVec3,
    /// As `ds`.
    pub dt: DVec3,
    /// The distance.
    pub distance: f64,
}

/// A box along a piece's own directions (tangents and normal at its centre) holding all
/// its control points, so the piece: a much tighter bound than its axis-aligned box for
/// a tilted piece, which spares the Newton search on pieces beside the nearest one.
#[derive(Clone, Debug)]
struct OrientedBox {
    centre: DVec3,
    axes: [DVec3; 3],
    lo: DVec3,
    hi: DVec3,
}

impl OrientedBox {
    fn of(piece: &Patch) -> OrientedBox {
        let jet = piece.jet(0.5, 0.5);
        let e1 = jet.du.try_normalize().unwrap_or(DVec3::X);
        let e3 = jet
            .du
            .cross(jet.dv)
            .try_normalize()
            .unwrap_or_else(|| crate::frame::any_normal(e1));
        let e2 = e3.cross(e1);
        let axes = [e1, e2, e3];
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &q in piece.points() {
            let d = q - jet.p;
            let c = DVec3::new(d.dot(e1), d.dot(e2), d.dot(e3));
            lo = lo.min(c);
            hi = hi.max(c);
        }
        OrientedBox {
            centre: jet.p,
            axes,
            lo,
            hi,
        }
    }

    fn distance(&self, p: DVec3) -> f64 {
        let d = p - self.centre;
        let c = DVec3::new(
            d.dot(self.axes[0]),
            d.dot(self.axes[1]),
            d.dot(self.axes[2]),
        );
        (self.lo - c).max(c - self.hi).max(DVec3::ZERO).length()
    }
}

thread_local! {
    /// The surface (by address) and piece that answered this thread's last query.
    static LAST_PIECE: std::cell::Cell<Option<(usize, usize)>> = const { std::cell::Cell::new(None) };
}

/// A thickened surface's field.
pub struct ThickSurface {
    pieces: Vec<Patch>,
    boxes: Vec<OrientedBox>,
    bvh: Bvh,
    half: f64,
    edges: Edges,
}

fn split_until_small(p: Patch, size: f64, depth: usize, out: &mut Vec<Patch>) {
    let b = p.hull_box();
    let diag = (b.max - b.min).length();
    if depth >= MAX_SPLITS || (diag <= size * PIECE_SIZE && p.flatness() <= size * FLATNESS) {
        out.push(p);
        return;
    }
    for q in p.split() {
        split_until_small(q, size, depth + 1, out);
    }
}

impl ThickSurface {
    /// The field of `surface` thickened to `thickness`.
    pub fn new(surface: &Surface, thickness: f64, edges: Edges) -> ThickSurface {
        let all = surface
            .patches()
            .iter()
            .fold(Box3::EMPTY, |b, p| b.union(p.hull_box()));
        let size = (all.max - all.min).length().max(1e-12);
        let mut pieces = Vec::new();
        for p in surface.patches() {
            // Coarse patches of a many-patch surface need fewer halvings.
            split_until_small(p.clone(), size, 0, &mut pieces);
        }
        let bvh = Bvh::new(pieces.iter().map(Patch::hull_box).collect());
        let boxes = pieces.iter().map(OrientedBox::of).collect();
        ThickSurface {
            pieces,
            boxes,
            bvh,
            half: 0.5 * thickness,
            edges,
        }
    }

    /// The closest point of the surface to `p`.
    ///
    /// Neighbouring queries (the mesher samples whole blocks in order) usually share
    /// their nearest piece: the piece that answered this thread's last query is tried
    /// first, so the best distance is tight from the start and the oriented boxes rule
    /// out nearly every other piece without a search.
    pub fn closest(&self, p: DVec3) -> Option<Foot> {
        let me = self as *const Self as usize;
        let mut best: Option<Foot> = None;
        let mut best_piece = usize::MAX;
        if let Some(i) = LAST_PIECE
            .with(|c| c.get())
            .filter(|&(owner, _)| owner == me)
            .map(|(_, i)| i)
            && i < self.pieces.len()
        {
            best = Some(closest_on(&self.pieces[i], p));
            best_piece = i;
        }
        self.bvh.min_search(p, &mut |i| {
            if i == best_piece {
                return best.map_or(f64::INFINITY, |b| b.distance);
            }
            // The oriented box bounds the piece's distance from below: skip the search
            // on pieces that cannot beat the best so far.
            if best.is_some_and(|b| self.boxes[i].distance(p) >= b.distance) {
                return f64::INFINITY;
            }
            let f = closest_on(&self.pieces[i], p);
            let d = f.distance;
            if best.is_none_or(|b| d < b.distance) {
                best = Some(f);
                best_piece = i;
            }
            d
        });
        if best_piece != usize::MAX {
            LAST_PIECE.with(|c| c.set(Some((me, best_piece))));
        }
        best
    }

    fn field(&self, p: DVec3) -> f64 {
        self.field_and_gradient(p).0
    }

    /// The field and, where it is known in closed form, its gradient (`None` on the
    /// first-order edge distance inside a flat slab, which is differenced instead).
    fn field_and_gradient(&self, p: DVec3) -> (f64, Option<DVec3>) {
        let Some(foot) = self.closest(p) else {
            return (f64::INFINITY, Some(DVec3::ZERO));
        };
        let normal = foot.ds.cross(foot.dt).normalize_or_zero();
        let away = p - foot.point;
        let round = foot.distance - self.half;
        let round_grad = if foot.distance > 1e-12 {
            away / foot.distance
        } else {
            normal
        };
        if self.edges == Edges::Round {
            return (round, Some(round_grad));
        }
        let w = away.dot(normal);
        let slab = w.abs() - self.half;
        let slab_grad = normal * w.signum();
        const EDGE: f64 = 1e-9;
        let on_edge =
            foot.s <= EDGE || foot.s >= 1.0 - EDGE || foot.t <= EDGE || foot.t >= 1.0 - EDGE;
        let (flat, flat_grad) = if on_edge {
            // Beyond the boundary: how far, across the surface.
            let lateral = away - normal * w;
            let l = lateral.length();
            if slab >= l {
                (slab, Some(slab_grad))
            } else {
                (l, Some(lateral / l))
            }
        } else {
            // Inside the boundary: how far to the nearest edge, to first order.
            let (ls, lt) = (foot.ds.length(), foot.dt.length());
            let to_edge = (foot.s * ls)
                .min((1.0 - foot.s) * ls)
                .min(foot.t * lt)
                .min((1.0 - foot.t) * lt);
            if slab >= -to_edge {
                (slab, Some(slab_grad))
            } else {
                (-to_edge, None)
            }
        };
        // The flat slab lies within the round one; keeping the larger value keeps the
        // round one's lower bounds valid for intervals.
        if round > flat {
            (round, Some(round_grad))
        } else {
            (flat, flat_grad)
        }
    }
}

/// The closest point of one piece to `p`: Newton on |S − p|² from the best of its centre
/// and corners, kept inside the piece.
fn closest_on(piece: &Patch, p: DVec3) -> Foot {
    // Start from the centre or the nearest corner (a patch passes through its corner
    // control points, so those cost nothing to measure).
    let mut jet = piece.jet(0.5, 0.5);
    let mut uv = DVec2::splat(0.5);
    let mut best = jet.p.distance_squared(p);
    for (corner, at) in piece.corners() {
        let d = corner.distance_squared(p);
        if d < best {
            best = d;
            uv = at;
        }
    }
    if uv != DVec2::splat(0.5) {
        jet = piece.jet(uv.x, uv.y);
    }
    for _ in 0..NEWTON_STEPS {
        let r = jet.p - p;
        let g = DVec2::new(jet.du.dot(r), jet.dv.dot(r));
        let (a, b, c) = (
            jet.du.dot(jet.du) + jet.duu.dot(r),
            jet.du.dot(jet.dv) + jet.duv.dot(r),
            jet.dv.dot(jet.dv) + jet.dvv.dot(r),
        );
        let mut h = DMat2::from_cols(DVec2::new(a, b), DVec2::new(b, c));
        if a <= 0.0 || h.determinant() <= 0.0 {
            // Not convex here: Gauss-Newton (first derivatives only) always descends.
            let (a, b, c) = (jet.du.dot(jet.du), jet.du.dot(jet.dv), jet.dv.dot(jet.dv));
            h = DMat2::from_cols(DVec2::new(a, b), DVec2::new(b, c));
        }
        let det = h.determinant();
        if !det.is_finite() || det.abs() < 1e-300 {
            break;
        }
        let step = -(h.inverse() * g);
        let next = (uv + step).clamp(DVec2::ZERO, DVec2::ONE);
        let next_jet = piece.jet(next.x, next.y);
        if next_jet.p.distance_squared(p) > jet.p.distance_squared(p) {
            // Overshot: take half the step instead, or stop.
            let half = (uv + step * 0.5).clamp(DVec2::ZERO, DVec2::ONE);
            let half_jet = piece.jet(half.x, half.y);
            if half_jet.p.distance_squared(p) >= jet.p.distance_squared(p) {
                break;
            }
            uv = half;
            jet = half_jet;
            continue;
        }
        let moved = (next - uv).length();
        uv = next;
        jet = next_jet;
        // A step of 1e-10 of a piece is far below a nanometre on any printable piece.
        if moved < 1e-10 {
            break;
        }
    }
    let (s, t) = piece.global(uv.x, uv.y);
    let (ws, wt) = (
        piece.s_range[1] - piece.s_range[0],
        piece.t_range[1] - piece.t_range[0],
    );
    Foot {
        point: jet.p,
        s,
        t,
        ds: jet.du / ws,
        dt: jet.dv / wt,
        distance: jet.p.distance(p),
    }
}

impl CustomField for ThickSurface {
    fn name(&self) -> &str {
        "thick_surface"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.field(DVec3::from(p))
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        let Some((c, h)) = finite_box(b) else {
            return Interval::ENTIRE;
        };
        let bx = Box3 {
            min: c - h,
            max: c + h,
        };
        // Nothing of the surface is nearer the box than the nearest piece's hull box.
        let lo = self.bvh.box_gap(&bx) - self.half;
        if lo > 0.0 || self.edges == Edges::Flat {
            return widened(lo, f64::INFINITY);
        }
        // The distance changes by at most 1 per mm.
        let hi = self
            .closest(c)
            .map_or(f64::INFINITY, |f| f.distance + h.length() - self.half);
        widened(lo, hi)
    }

    fn gradient(&self, p: [f64; 3]) -> [f64; 4] {
        let p = DVec3::from(p);
        let (v, g) = self.field_and_gradient(p);
        if let Some(g) = g {
            return [v, g.x, g.y, g.z];
        }
        let h = 1e-7 * (1.0 + p.abs().max_element());
        let d = |e: DVec3| (self.field(p + e * h) - self.field(p - e * h)) / (2.0 * h);
        [v, d(DVec3::X), d(DVec3::Y), d(DVec3::Z)]
    }
}
