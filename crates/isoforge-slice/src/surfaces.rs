//! What each part of an island's inside is: sparse infill, solid skin, the visible top,
//! a bridge over air, or the first solid layer over sparse infill (an internal bridge).
//! Found with polygon booleans against the neighbouring layers' regions.

use crate::bridges::bridge_angle;
use crate::clip::{difference, grow_round, intersect, offset, opening};
use crate::geom::{Region, region_area};

/// The layers around one layer, as far as the classification looks.
pub struct Neighbours<'a> {
    /// Regions of the layers above, nearest first (fewer at the top of the model).
    pub above: Vec<&'a Region>,
    /// Regions of the layers below, nearest first (fewer at the bottom: the bed).
    pub below: Vec<&'a Region>,
    /// True when the layer directly below is the bed or a raft (nothing is bridged).
    pub on_bed: bool,
}

/// An island's inside split by kind, before any line is laid.
#[derive(Clone, Debug, Default)]
pub struct Surfaces {
    /// Sparse infill.
    pub sparse: Region,
    /// Solid infill that is not seen (under a top, over a bottom).
    pub skin: Region,
    /// The visible top surface.
    pub top: Region,
    /// Bridges over air: each area with the direction its lines run, radians.
    pub bridges: Vec<(Region, f64)>,
    /// Solid over the sparse infill of the layer below.
    pub internal_bridge: Region,
}

/// Parts of a bridge narrower than this many line widths are not bridged (a slope leaves a
/// sliver over air on every layer; a line width covers it).
const BRIDGE_MIN_WIDTH_PER_LINE: f64 = 1.0;

/// Bridge lines reach this many line widths onto supported material at each end, so they
/// are anchored (PrusaSlicer's bridges reach a few widths past the edge too).
const BRIDGE_ANCHOR_PER_LINE: f64 = 3.0;

/// Sparse patches smaller than this are printed solid, mm²: a thin pin's core would get a
/// line or two of sparse infill that holds nothing up and leaves the pin hollow (the 3 mm
/// pin of fixtures/slice extruded 85% of its volume with it sparse). PrusaSlicer's
/// `solid_infill_below_area` defaults to the same 70 mm² (about a 9.4 mm round core).
const SOLID_BELOW_AREA: f64 = 70.0;

/// Splits `inner` (an island's inside its walls) into solid and sparse: solid where a
/// layer within `top` above or `bottom` below lacks material, and sparse patches too small
/// to be worth it. Beyond the first or last layer there is nothing, so those layers are
/// solid.
pub fn split_solid(inner: &Region, n: &Neighbours, top: usize, bottom: usize) -> (Region, Region) {
    if inner.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let mut covered = inner.clone();
    let layers = (0..top)
        .map(|k| n.above.get(k).copied())
        .chain((0..bottom).map(|k| n.below.get(k).copied()));
    for r in layers {
        let Some(r) = r else {
            covered.clear();
            break;
        };
        covered = intersect(&covered, r);
        if covered.is_empty() {
            break;
        }
    }
    covered.retain(|shape| region_area(&vec![shape.clone()]) >= SOLID_BELOW_AREA);
    (difference(inner, &covered), covered)
}

/// Classifies the solid part of an island: bridges where it is over air, an internal
/// bridge where it is over the layer below's sparse infill, the top where nothing is
/// directly above, skin for the rest. `sparse_below` is the layer below's sparse region.
pub fn classify(
    inner: &Region,
    solid: Region,
    sparse: Region,
    n: &Neighbours,
    sparse_below: Option<&Region>,
    w: f64,
) -> Surfaces {
    let mut out = Surfaces {
        sparse,
        ..Default::default()
    };
    let mut solid = solid;
    if !n.on_bed
        && let Some(&below) = n.below.first()
    {
        let air = opening(
            &difference(inner, below),
            0.5 * BRIDGE_MIN_WIDTH_PER_LINE * w,
        );
        if !air.is_empty() {
            let area = intersect(&grow_round(&air, BRIDGE_ANCHOR_PER_LINE * w), inner);
            let anchors = offset(below, 0.25 * w);
            for shape in area {
                let piece = vec![shape];
                let angle = bridge_angle(&piece, &anchors, w);
                out.bridges.push((piece, angle));
            }
            let all: Region = out.bridges.iter().flat_map(|b| b.0.clone()).collect();
            solid = difference(&solid, &all);
            out.sparse = difference(&out.sparse, &all);
        }
        if let Some(sb) = sparse_below
            && !solid.is_empty()
            && !sb.is_empty()
        {
            let ib = opening(&intersect(&solid, sb), w);
            if !ib.is_empty() {
                solid = difference(&solid, &ib);
                out.internal_bridge = ib;
            }
        }
    }
    match n.above.first() {
        Some(above) => {
            out.top = difference(&solid, above);
            out.skin = if out.top.is_empty() {
                solid
            } else {
                difference(&solid, &out.top)
            };
        }
        None => out.top = solid,
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;
    use crate::geom::region_area;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Region {
        region_from_contours(&[vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
    }

    #[test]
    fn a_pyramid_has_skin_where_the_layer_above_is_smaller() {
        let sq = |s: f64| rect(-s / 2.0, -s / 2.0, s / 2.0, s / 2.0);
        let layers: Vec<Region> = [20.0, 16.0, 12.0, 8.0, 4.0].into_iter().map(sq).collect();
        let n = Neighbours {
            above: vec![&layers[2]],
            below: vec![&layers[0]],
            on_bed: false,
        };
        let (solid, sparse) = split_solid(&layers[1], &n, 1, 1);
        assert!((region_area(&sparse) - 144.0).abs() < 1e-6);
        assert!((region_area(&solid) - 112.0).abs() < 1e-6);
        // A small layer's sparse core is solid: a 6 mm square over and under larger ones.
        let small = sq(6.0);
        let n = Neighbours {
            above: vec![&layers[0]],
            below: vec![&layers[0]],
            on_bed: false,
        };
        let (solid, sparse) = split_solid(&small, &n, 1, 1);
        assert!(sparse.is_empty());
        assert!((region_area(&solid) - 36.0).abs() < 1e-6);
        // The last layer is all top.
        let n = Neighbours {
            above: vec![],
            below: vec![&layers[3]],
            on_bed: false,
        };
        let (solid, sparse) = split_solid(&layers[4], &n, 1, 1);
        assert!(sparse.is_empty());
        let s = classify(&layers[4], solid, sparse, &n, None, 0.45);
        assert!((region_area(&s.top) - 16.0).abs() < 1e-6);
    }

    #[test]
    fn a_deck_between_pillars_is_bridged_along_the_gap() {
        // Pillars at x in [-15, -10] and [10, 15]; the deck spans x in [-15, 15].
        let below =
            crate::clip::union(&rect(-15.0, -5.0, -10.0, 5.0), &rect(10.0, -5.0, 15.0, 5.0));
        let deck = rect(-14.0, -4.0, 14.0, 4.0);
        let above = rect(-15.0, -5.0, 15.0, 5.0);
        let n = Neighbours {
            above: vec![&above],
            below: vec![&below],
            on_bed: false,
        };
        let (solid, sparse) = split_solid(&deck, &n, 1, 1);
        let s = classify(&deck, solid, sparse, &n, None, 0.45);
        assert_eq!(s.bridges.len(), 1);
        let (area, angle) = &s.bridges[0];
        // Along x (0 or 180 degrees), reaching onto both pillars.
        assert!(angle.sin().abs() < 0.05, "angle {angle}");
        let (lo, hi) = crate::geom::bbox(area.iter().flatten().flatten()).unwrap();
        assert!(lo[0] < -10.5 && hi[0] > 10.5, "{lo:?} {hi:?}");
    }
}
