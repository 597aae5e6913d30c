//! Tool paths of one layer in print order: skirt, then island by island its perimeters
//! (innermost first, the outer wall last so it is laid against support), then its skins
//! and infill. Each island, and each infill line within it, starts at the point nearest to
//! where the nozzle is. Loops start at their seam: the point nearest the back of the bed,
//! so seams line up from layer to layer.

use crate::geom::{Contour, Point, Region, dist};

/// What a path is, for speeds and the `;TYPE:` comments.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Role {
    /// Loops around the first layer, to prime the nozzle.
    Skirt,
    /// The outermost perimeter.
    OuterWall,
    /// Inner perimeters.
    InnerWall,
    /// Solid top and bottom skin.
    Skin,
    /// Sparse infill.
    Fill,
}

impl Role {
    /// The name in `;TYPE:` comments (Cura's names, which G-code viewers know).
    pub fn name(self) -> &'static str {
        match self {
            Role::Skirt => "SKIRT",
            Role::OuterWall => "WALL-OUTER",
            Role::InnerWall => "WALL-INNER",
            Role::Skin => "SKIN",
            Role::Fill => "FILL",
        }
    }
}

/// One extrusion: a polyline (closed loops repeat their first point at the end).
#[derive(Clone, Debug, PartialEq)]
pub struct Extrusion {
    /// Its role.
    pub role: Role,
    /// The points in print order.
    pub points: Vec<Point>,
}

/// One island of a layer, ready to order.
#[derive(Clone, Debug, Default)]
pub struct Island {
    /// Perimeter loops, outermost first (each inset's contours).
    pub loops: Vec<Vec<Contour>>,
    /// Solid skin lines.
    pub skin: Vec<Vec<Point>>,
    /// Sparse infill lines.
    pub fill: Vec<Vec<Point>>,
}

/// The seam target: far behind the bed's back edge, so the rear-most point of each loop wins.
const SEAM_TARGET: Point = [0.0, 1.0e6];

/// A closed loop as a path starting at its seam (the vertex nearest `SEAM_TARGET`).
pub fn loop_from_seam(c: &Contour) -> Vec<Point> {
    let Some(start) = (0..c.len()).min_by(|&a, &b| {
        dist(c[a], SEAM_TARGET)
            .total_cmp(&dist(c[b], SEAM_TARGET))
            .then(c[a][0].total_cmp(&c[b][0]))
    }) else {
        return Vec::new();
    };
    let mut p: Vec<Point> = c[start..].iter().chain(&c[..start]).copied().collect();
    p.push(c[start]);
    p
}

/// Orders open lines greedily: each next line is the one with an end nearest the
/// current position, reversed if its far end is nearer.
pub fn order_lines(lines: Vec<Vec<Point>>, role: Role, pos: &mut Point, out: &mut Vec<Extrusion>) {
    let mut left: Vec<Option<Vec<Point>>> = lines.into_iter().map(Some).collect();
    let mut remaining = left.len();
    while remaining > 0 {
        let mut best = (f64::INFINITY, 0, false);
        for (k, l) in left.iter().enumerate() {
            if let Some(l) = l
                && let (Some(&a), Some(&b)) = (l.first(), l.last())
            {
                let (da, db) = (dist(*pos, a), dist(*pos, b));
                if da < best.0 {
                    best = (da, k, false);
                }
                if db < best.0 {
                    best = (db, k, true);
                }
            }
        }
        let Some(mut l) = left.get_mut(best.1).and_then(Option::take) else {
            break;
        };
        remaining -= 1;
        if best.2 {
            l.reverse();
        }
        if let Some(&last) = l.last() {
            *pos = last;
        }
        out.push(Extrusion { role, points: l });
    }
}

/// The layer's extrusions in print order, starting from `pos` (updated to the end).
pub fn order_layer(skirt: &[Contour], mut islands: Vec<Island>, pos: &mut Point) -> Vec<Extrusion> {
    let mut out = Vec::new();
    for c in skirt {
        let p = loop_from_seam(c);
        if let Some(&last) = p.last() {
            *pos = last;
        }
        out.push(Extrusion {
            role: Role::Skirt,
            points: p,
        });
    }
    while !islands.is_empty() {
        // The island whose first loop's seam (or first line) is nearest.
        let entry = |isl: &Island| -> Point {
            isl.loops
                .last()
                .and_then(|l| l.first())
                .and_then(|c| loop_from_seam(c).first().copied())
                .or_else(|| isl.skin.first().and_then(|l| l.first().copied()))
                .or_else(|| isl.fill.first().and_then(|l| l.first().copied()))
                .unwrap_or(*pos)
        };
        let k = (0..islands.len())
            .min_by(|&a, &b| {
                dist(*pos, entry(&islands[a])).total_cmp(&dist(*pos, entry(&islands[b])))
            })
            .unwrap_or(0);
        let isl = islands.swap_remove(k);
        for (depth, inset) in isl.loops.iter().enumerate().rev() {
            let role = if depth == 0 {
                Role::OuterWall
            } else {
                Role::InnerWall
            };
            // Within one inset, nearest contour first.
            let mut cs: Vec<&Contour> = inset.iter().collect();
            while !cs.is_empty() {
                let j = (0..cs.len())
                    .min_by(|&a, &b| {
                        let da = loop_from_seam(cs[a])
                            .first()
                            .map_or(f64::INFINITY, |p| dist(*pos, *p));
                        let db = loop_from_seam(cs[b])
                            .first()
                            .map_or(f64::INFINITY, |p| dist(*pos, *p));
                        da.total_cmp(&db)
                    })
                    .unwrap_or(0);
                let p = loop_from_seam(cs.swap_remove(j));
                if let Some(&last) = p.last() {
                    *pos = last;
                }
                out.push(Extrusion { role, points: p });
            }
        }
        order_lines(isl.skin, Role::Skin, pos, &mut out);
        order_lines(isl.fill, Role::Fill, pos, &mut out);
    }
    out
}

/// Splits a layer's regions into islands: each shape of `outline` with the perimeters,
/// skin and fill lines that lie in it. Lines are assigned by their first point.
pub fn islands(
    outline: &Region,
    loops: Vec<Vec<Contour>>,
    skin: Vec<Vec<Point>>,
    fill: Vec<Vec<Point>>,
) -> Vec<Island> {
    let mut out: Vec<Island> = outline.iter().map(|_| Island::default()).collect();
    if out.is_empty() {
        return out;
    }
    let which = |p: Point| -> usize {
        outline
            .iter()
            .position(|shape| crate::geom::inside_contours(p, shape))
            .unwrap_or_else(|| {
                // On a boundary: the nearest shape.
                (0..outline.len())
                    .min_by(|&a, &b| {
                        crate::geom::distance_to_contours(p, &outline[a])
                            .total_cmp(&crate::geom::distance_to_contours(p, &outline[b]))
                    })
                    .unwrap_or(0)
            })
    };
    for (depth, inset) in loops.into_iter().enumerate() {
        for c in inset {
            let Some(&p) = c.first() else { continue };
            let isl = &mut out[which(p)];
            if isl.loops.len() <= depth {
                isl.loops.resize(depth + 1, Vec::new());
            }
            isl.loops[depth].push(c);
        }
    }
    for l in skin {
        if let Some(&p) = l.first() {
            out[which(p)].skin.push(l);
        }
    }
    for l in fill {
        if let Some(&p) = l.first() {
            out[which(p)].fill.push(l);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seam_is_the_rear_most_point() {
        let c = vec![
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [5.0, 12.0],
            [0.0, 10.0],
        ];
        let p = loop_from_seam(&c);
        assert_eq!(p[0], [5.0, 12.0]);
        assert_eq!(p.last(), Some(&[5.0, 12.0]));
        assert_eq!(p.len(), 6);
    }

    #[test]
    fn lines_are_ordered_nearest_first_and_flipped() {
        let lines = vec![vec![[10.0, 0.0], [20.0, 0.0]], vec![[0.0, 1.0], [9.0, 1.0]]];
        let mut pos = [0.0, 0.0];
        let mut out = Vec::new();
        order_lines(lines, Role::Fill, &mut pos, &mut out);
        assert_eq!(out[0].points[0], [0.0, 1.0]);
        assert_eq!(out[1].points[0], [10.0, 0.0]);
        assert_eq!(pos, [20.0, 0.0]);
    }

    #[test]
    fn outer_wall_is_printed_last_among_loops() {
        let sq = |a: f64, b: f64| vec![[a, a], [b, a], [b, b], [a, b]];
        let isl = Island {
            loops: vec![vec![sq(0.0, 10.0)], vec![sq(1.0, 9.0)]],
            skin: vec![],
            fill: vec![vec![[2.0, 2.0], [8.0, 8.0]]],
        };
        let mut pos = [0.0, 0.0];
        let out = order_layer(&[], vec![isl], &mut pos);
        let roles: Vec<Role> = out.iter().map(|e| e.role).collect();
        assert_eq!(roles, [Role::InnerWall, Role::OuterWall, Role::Fill]);
    }
}
