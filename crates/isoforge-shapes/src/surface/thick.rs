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

/// Points handled together by the batch callback: the mesher's blocks come in rows, so a
/// group of 32 neighbours shares one short list of candidate pieces.
const GROUP: usize = 32;

impl ThickSurface {
    /// The field at a group of neighbouring points: one hierarchy query for the group's
    /// candidate pieces, then per point a Newton search warm-started from the previous
    /// point's answer, and only the candidates whose oriented box could beat it.
    fn group_values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        let pts: Vec<DVec3> = (0..out.len())
            .map(|i| DVec3::new(xs[i], ys[i], zs[i]))
            .collect();
        let group = Box3::around(pts.iter().copied());
        if !group.min.is_finite() || !group.max.is_finite() {
            for (o, &p) in out.iter_mut().zip(&pts) {
                *o = self.field(p);
            }
            return;
        }
        let centre = group.centre();
        let Some(first) = self.closest(centre) else {
            out.fill(f64::INFINITY);
            return;
        };
        // Every point's nearest piece lies within its distance, at most this, of the group.
        let reach = first.distance + (group.max - group.min).length() * 0.5;
        // Each candidate with its oriented box's distance from the group's centre: a point
        // `r` from the centre is at least that less `r` from the piece.
        let mut candidates = Vec::new();
        self.bvh.near_box(&group, reach, &mut |i| {
            candidates.push((i, self.boxes[i].distance(centre)));
        });
        let mut warm = first;
        // Where each piece last answered in this group: its next search starts there.
        let mut last_uv: Vec<(usize, DVec2)> = Vec::with_capacity(16);
        for (o, &p) in out.iter_mut().zip(&pts) {
            let mut best = closest_on(&self.pieces[warm.piece], warm.piece, p, Some(warm.uv));
            let off = p.distance(centre);
            for &(i, from_centre) in &candidates {
                if i == best.piece
                    || from_centre - off >= best.distance
                    || self.boxes[i].distance(p) >= best.distance
                {
                    continue;
                }
                let start = last_uv.iter().find(|(k, _)| *k == i).map(|(_, uv)| *uv);
                let f = closest_on(&self.pieces[i], i, p, start);
                match last_uv.iter_mut().find(|(k, _)| *k == i) {
                    Some(slot) => slot.1 = f.uv,
                    None => last_uv.push((i, f.uv)),
                }
                if f.distance < best.distance {
                    best = f;
                }
            }
            *o = self.at_foot(p, &best).0;
            warm = best;
        }
    }
}

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
    /// The piece it lies on, and where on it: a warm start for a neighbouring query.
    piece: usize,
    uv: DVec2,
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
    /// Per piece, a lower bound of the first-order distance to the surface's edge from
    /// any foot on it (`None` for a piece on the edge): what bounds a flat slab's field
    /// from above inside it.
    edge_room: Vec<Option<f64>>,
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
        let edge_room = pieces.iter().map(edge_room).collect();
        ThickSurface {
            pieces,
            boxes,
            edge_room,
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
            best = Some(closest_on(&self.pieces[i], i, p, None));
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
            let f = closest_on(&self.pieces[i], i, p, None);
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
        match self.closest(p) {
            Some(foot) => self.at_foot(p, &foot),
            None => (f64::INFINITY, Some(DVec3::ZERO)),
        }
    }

    /// The field at `p` whose closest surface point is `foot`.
    fn at_foot(&self, p: DVec3, foot: &Foot) -> (f64, Option<DVec3>) {
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
        let (wall, wall_grad) = if self.edge_room[foot.piece].is_some() {
            // A piece clear of the edge: how far to the nearest edge, to first order
            // (what `edge_room` bounds from below for the intervals).
            let (ls, lt) = (foot.ds.length(), foot.dt.length());
            let to_edge = (foot.s * ls)
                .min((1.0 - foot.s) * ls)
                .min(foot.t * lt)
                .min((1.0 - foot.t) * lt);
            (-to_edge, None)
        } else {
            wall(foot, away)
        };
        let (flat, flat_grad) = if slab >= wall {
            (slab, Some(slab_grad))
        } else {
            (wall, wall_grad)
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

/// How far `away` (a point less its foot) lies beyond the walls that cut a flat slab at
/// the surface's four sides, each wall taken to first order from the foot: the plane
/// through the side's line that the tangent plane extrapolates to (`(1 − s)·∂S/∂s` away
/// for the side s = 1), standing along the normal. The largest of the four signed
/// distances (negative when inside all of them), with its gradient when the foot lies on
/// that side.
///
/// A foot on the side s = 1 gives `away · ĉ`, the distance across the border (ĉ the
/// border's outward conormal), positive for every point beyond it. A foot a hair short of
/// the border gives nearly the same, since it is measured in the same plane, so a search
/// that stops at s = 1 − 10⁻⁷ with the point well beyond still reads outside. The first-order
/// distance to the edge alone, as on pieces clear of the border, reads `−(1 − s)·|∂S/∂s|`
/// there: barely negative, which made a sliver of stray samples inside.
fn wall(foot: &Foot, away: DVec3) -> (f64, Option<DVec3>) {
    // The outward conormals of the sides s = 1 and t = 1 (the others are their
    // opposites): each side's tangent direction's complement within the tangent plane.
    let across = |along: DVec3, side: DVec3| {
        let c = along - side * (along.dot(side) / side.length_squared().max(f64::MIN_POSITIVE));
        c.try_normalize()
            .map(|dir| (dir, c.length()))
            .or_else(|| along.try_normalize().map(|dir| (dir, along.length())))
    };
    let mut best = (f64::NEG_INFINITY, None);
    for (conormal, at) in [
        (across(foot.ds, foot.dt), foot.s),
        (across(foot.dt, foot.ds), foot.t),
    ] {
        // A degenerate patch (both tangents zero here): no direction to cut along.
        let Some((dir, speed)) = conormal else {
            return (0.0, None);
        };
        for (outward, room) in [(dir, 1.0 - at), (-dir, at)] {
            let d = away.dot(outward) - room * speed;
            if d > best.0 {
                best = (d, (room == 0.0).then_some(outward));
            }
        }
    }
    best
}

/// A lower bound of the first-order distance to the surface's edge, `min(s, 1 − s)·|∂S/∂s|`
/// and likewise in t, over a piece that does not touch the edge (`None` if it does).
///
/// |∂S/∂u| over the piece lies in the convex hull of its derivative net (the differences
/// of neighbouring control points, times the degree); its length is at least that hull's
/// extent along the mean difference direction, the smallest projection onto it.
fn edge_room(piece: &Patch) -> Option<f64> {
    let [s0, s1] = piece.s_range;
    let [t0, t1] = piece.t_range;
    if s0 <= 0.0 || s1 >= 1.0 || t0 <= 0.0 || t1 >= 1.0 {
        return None;
    }
    let (rows, cols) = piece.size();
    let speed = |diffs: Vec<DVec3>, degree: usize| -> f64 {
        let mean = diffs.iter().copied().sum::<DVec3>();
        let Some(dir) = mean.try_normalize() else {
            return 0.0;
        };
        let least = diffs
            .iter()
            .map(|d| d.dot(dir))
            .fold(f64::INFINITY, f64::min);
        (least * degree as f64).max(0.0)
    };
    let du: Vec<DVec3> = (0..rows - 1)
        .flat_map(|i| (0..cols).map(move |j| (i, j)))
        .map(|(i, j)| piece.at(i + 1, j) - piece.at(i, j))
        .collect();
    let dv: Vec<DVec3> = (0..rows)
        .flat_map(|i| (0..cols - 1).map(move |j| (i, j)))
        .map(|(i, j)| piece.at(i, j + 1) - piece.at(i, j))
        .collect();
    // Per unit of the surface's s and t (the piece spans a fraction of each).
    let vs = speed(du, rows - 1) / (s1 - s0);
    let vt = speed(dv, cols - 1) / (t1 - t0);
    Some(
        (s0 * vs)
            .min((1.0 - s1) * vs)
            .min(t0 * vt)
            .min((1.0 - t1) * vt),
    )
}

/// Where a Newton step that would leave the piece across a side goes instead: the
/// coordinate that reaches its bound first along the step is put exactly on it, and the
/// other takes the step that minimises the quadratic model with the first held there.
/// Without it a foot just inside an edge, u = 1 − 10⁻⁷ or 5·10⁻⁴ say, may never move:
/// the coupled 2D step is aimed at a point beyond the edge, and cut off there its other
/// coordinate can point uphill, so every halving fails and the search stops short of
/// the foot on the edge (on the lecture's patch that left rows of samples barely inside
/// the slab beyond its borders, meshed as loose slivers). `None` if the step stays inside.
fn projected(uv: DVec2, step: DVec2, h: DMat2, g: DVec2) -> Option<Step> {
    // The fraction of the step at which a coordinate reaches a bound, and that bound.
    let reach = |x: f64, dx: f64| {
        let to = x + dx;
        if to < 0.0 {
            Some((x / -dx, 0.0))
        } else if to > 1.0 {
            Some(((1.0 - x) / dx, 1.0))
        } else {
            None
        }
    };
    let (hxx, hxy, hyy) = (h.x_axis.x, h.x_axis.y, h.y_axis.y);
    let (on_u, on_v) = (reach(uv.x, step.x), reach(uv.y, step.y));
    let hold_u = match (on_u, on_v) {
        (None, None) => return None,
        (Some(_), None) => true,
        (None, Some(_)) => false,
        (Some((fu, _)), Some((fv, _))) => fu <= fv,
    };
    Some(if hold_u {
        let bound = on_u?.1;
        let du = bound - uv.x;
        Step::OnSide {
            held: 0,
            bound,
            free: if hyy > 0.0 {
                -(g.y + hxy * du) / hyy
            } else {
                0.0
            },
        }
    } else {
        let bound = on_v?.1;
        let dv = bound - uv.y;
        Step::OnSide {
            held: 1,
            bound,
            free: if hxx > 0.0 {
                -(g.x + hxy * dv) / hxx
            } else {
                0.0
            },
        }
    })
}

/// A move in a piece's (u, v).
enum Step {
    /// One coordinate (`held`: 0 for u, 1 for v) put on a bound of the piece, the other
    /// moved by `free`.
    OnSide { held: usize, bound: f64, free: f64 },
    /// Both moved, and cut off at the piece's sides.
    Free(DVec2),
}

/// The first of the step's full length, a half, ... a 32nd (kept inside the piece) that
/// brings the piece no farther from `p` than `here` (squared), with the jet there. A
/// projected step keeps its held coordinate on the bound and shortens the other one's.
/// After a few halvings the step is too small to matter: 1/32 of a Newton step near the
/// foot is below its error.
fn descend(
    piece: &Patch,
    p: DVec3,
    uv: DVec2,
    step: &Step,
    here: f64,
) -> Option<(DVec2, super::patch::Jet)> {
    let mut scale = 1.0;
    for _ in 0..6 {
        let next = match *step {
            Step::OnSide {
                held: 0,
                bound,
                free,
            } => DVec2::new(bound, uv.y + free * scale),
            Step::OnSide { bound, free, .. } => DVec2::new(uv.x + free * scale, bound),
            Step::Free(step) => uv + step * scale,
        }
        .clamp(DVec2::ZERO, DVec2::ONE);
        let next_jet = piece.jet(next.x, next.y);
        if next_jet.p.distance_squared(p) <= here {
            return Some((next, next_jet));
        }
        scale *= 0.5;
    }
    None
}

/// The closest point of one piece to `p`: Newton on |S − p|² from the best of its centre
/// and corners, kept inside the piece.
fn closest_on(piece: &Patch, index: usize, p: DVec3, start: Option<DVec2>) -> Foot {
    let (mut uv, mut jet) = match start {
        Some(uv) => (uv, piece.jet(uv.x, uv.y)),
        None => {
            // The centre or the nearest corner (a patch passes through its corner
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
            (uv, jet)
        }
    };
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
        // A coordinate held at its bound by a gradient pointing out of the piece stays
        // there (the foot lies on that edge); Newton goes on along the other one alone,
        // since the coupled 2D step would be aimed at a point outside the piece.
        let held_u = (uv.x <= 0.0 && g.x > 0.0) || (uv.x >= 1.0 && g.x < 0.0);
        let held_v = (uv.y <= 0.0 && g.y > 0.0) || (uv.y >= 1.0 && g.y < 0.0);
        let step = match (held_u, held_v) {
            (false, false) => {
                let det = h.determinant();
                if !det.is_finite() || det.abs() < 1e-300 {
                    break;
                }
                -(h.inverse() * g)
            }
            (false, true) if h.x_axis.x > 0.0 => DVec2::new(-g.x / h.x_axis.x, 0.0),
            (true, false) if h.y_axis.y > 0.0 => DVec2::new(0.0, -g.y / h.y_axis.y),
            _ => break,
        };
        // Backtrack until the distance drops: first along the step projected onto the
        // piece, then along the step cut off at the piece's sides.
        let here = jet.p.distance_squared(p);
        let Some((next, next_jet)) = projected(uv, step, h, g)
            .and_then(|onto| descend(piece, p, uv, &onto, here))
            .or_else(|| descend(piece, p, uv, &Step::Free(step), here))
        else {
            break;
        };
        let moved = (next - uv).length();
        uv = next;
        jet = next_jet;
        // The distance is stationary at the foot, so a foot off by ε (of the piece) moves
        // the distance by about ε² times the piece's size squared: at ε = 1e-5 that is
        // 1e-10 of the piece, and Newton's next step would be ~ε² anyway.
        if moved < 1e-5 {
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
        piece: index,
        uv,
    }
}

impl CustomField for ThickSurface {
    fn name(&self) -> &str {
        "thick_surface"
    }

    fn value(&self, p: [f64; 3]) -> f64 {
        self.field(DVec3::from(p))
    }

    fn values(&self, xs: &[f64], ys: &[f64], zs: &[f64], out: &mut [f64]) {
        for start in (0..out.len()).step_by(GROUP) {
            let end = (start + GROUP).min(out.len());
            self.group_values(
                &xs[start..end],
                &ys[start..end],
                &zs[start..end],
                &mut out[start..end],
            );
        }
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
        if lo > 0.0 {
            return widened(lo, f64::INFINITY);
        }
        let Some(foot) = self.closest(c) else {
            return widened(lo, f64::INFINITY);
        };
        // The distance changes by at most 1 per mm.
        let reach = foot.distance + h.length();
        let round_hi = reach - self.half;
        if self.edges == Edges::Round {
            return widened(lo, round_hi);
        }
        // Flat: every point's foot lies on a piece within `reach` of the box. If none of
        // them is on the surface's edge, the field there is max(round, −distance to the
        // edge), and each piece bounds that distance from below.
        let mut room = f64::INFINITY;
        self.bvh.near_box(&bx, reach, &mut |i| {
            room = room.min(self.edge_room[i].unwrap_or(f64::NEG_INFINITY));
        });
        if room == f64::NEG_INFINITY {
            return widened(lo, f64::INFINITY);
        }
        widened(lo, round_hi.max(-room))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A point just beyond the border reads outside from its foot on the border, and as
    /// much from a foot a search left a hair short of it (the old reading there was the
    /// first-order distance to the edge, −10⁻⁷ × |∂S/∂s|: inside).
    #[test]
    fn a_foot_a_hair_short_of_the_border_still_reads_outside() {
        let net: Vec<Vec<[f64; 3]>> = (0..3)
            .map(|i| {
                (0..3)
                    .map(|j| [i as f64, j as f64, [0.0, 0.8, 0.2][i] + [0.3, 0.0, 0.5][j]])
                    .collect()
            })
            .collect();
        let s = crate::surface::bezier(&net).unwrap();
        let f = ThickSurface::new(&s, 0.3, Edges::Flat);
        let at = s.point(1.0, 0.4);
        let out = (at - s.point(1.0 - 1e-6, 0.4)).normalize();
        for (beyond, below) in [(0.05, 0.0), (0.02, 0.1), (0.1, -0.05)] {
            let h = 1e-6;
            let normal = (s.point(1.0, 0.4 + h) - s.point(1.0, 0.4 - h))
                .cross(out)
                .normalize();
            let p = at + out * beyond + normal * below;
            let foot = f.closest(p).unwrap();
            assert_eq!(foot.s, 1.0, "{beyond}, {below}");
            let exact = f.at_foot(p, &foot).0;
            assert!(exact > 0.5 * beyond, "{beyond}, {below}: {exact}");
            let mut short = foot;
            short.s = 1.0 - 1e-7;
            short.point -= foot.ds * 1e-7;
            let v = f.at_foot(p, &short).0;
            assert!(
                (v - exact).abs() < 1e-5,
                "{beyond}, {below}: {v} vs {exact}"
            );
        }
    }
}
