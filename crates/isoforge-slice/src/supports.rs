//! Supports: what holds up the parts of a layer that lean further over the layer below
//! than the support angle allows.
//!
//! Each layer's overhang is its region beyond the layer below grown by h·tan(angle) (a
//! surface leaning less than the angle shifts less than that per layer). Supports are
//! built from the top down: every overhang is carried down to the bed or to the model
//! below it, kept `support_z_gap` clear of the part above and below (so it peels off) and
//! 60% of a line clear of it sideways. `grid` supports are straight columns; `tree`
//! supports are branches that start at points under the overhang and lean toward each
//! other as they go down, merging into trunks, so less material stands on the bed and
//! less touches the part. The top layers of either are a dense interface.

use crate::clip::{difference, intersect, offset, opening, union, union_all};
use crate::geom::{Point, Region, dist, inside_region, signed_area};
use crate::profile::{FdmSettings, SupportStyle};

/// Sideways clearance between support and part, in line widths (PrusaSlicer: 60%).
const XY_GAP_PER_LINE: f64 = 0.6;

/// Overhang pieces narrower than this many line widths, or smaller than its square, are
/// numerical specks, not overhangs.
const SPECK_PER_LINE: f64 = 0.1;

/// Dense interface layers at the top of a support.
const INTERFACE_LAYERS: usize = 2;

/// Tree tips are placed on a grid this far apart under each overhang, mm.
const TREE_TIP_SPACING: f64 = 3.0;

/// A branch leans at most this much from vertical, degrees (steeper than the support
/// angle would itself need support; 40 degrees prints clean with PLA).
const TREE_BRANCH_ANGLE: f64 = 40.0;

/// A branch's radius at its tip, and how much it grows per mm it descends.
const TREE_TIP_RADIUS: f64 = 0.8;
const TREE_RADIUS_GROWTH: f64 = 0.05;

/// One layer's support.
#[derive(Clone, Debug, Default)]
pub struct SupportLayer {
    /// The support's body (sparse lines).
    pub body: Region,
    /// Its dense top, under the part.
    pub interface: Region,
}

impl SupportLayer {
    /// Body and interface together.
    pub fn all(&self) -> Region {
        union(&self.body, &self.interface)
    }
}

/// The overhang of each layer: what needs support under it. `printed` is each layer's
/// region where something is printed (a patch too thin for any line holds nothing up).
pub fn overhangs(
    regions: &[Region],
    printed: &[Region],
    heights: &[f64],
    s: &FdmSettings,
) -> Vec<Region> {
    let w = s.line_width;
    let tan = s.support_overhang_angle.to_radians().tan().min(1e3);
    use rayon::prelude::*;
    (0..regions.len())
        .into_par_iter()
        .map(|l| {
            if l == 0 {
                return Vec::new();
            }
            let grow = heights[l] * tan;
            let lower = offset(&printed[l - 1], grow);
            // A steep slope leaves a strip narrower than a line on every layer: keep it
            // (the strips of many layers make the support's area); drop only specks.
            let mut over = opening(&difference(&regions[l], &lower), SPECK_PER_LINE * w);
            over.retain(|shape| {
                shape
                    .first()
                    .is_some_and(|c| signed_area(c) > SPECK_PER_LINE * w * w)
            });
            if over.is_empty() {
                return over;
            }
            // The whole of the steep part hangs, not only what lies beyond the grown layer
            // below: grown back toward it (as Slic3r does), or the strips of successive
            // layers would leave gaps between them.
            intersect(
                &offset(&over, grow),
                &difference(&regions[l], &printed[l - 1]),
            )
        })
        .collect()
}

/// What each layer's support must hold up: the overhangs `gap` layers above the layer
/// above (nearer where the part starts within the gap of the bed).
fn needs(over: Vec<Region>, gap: usize) -> Vec<Region> {
    let mut need = vec![Vec::new(); over.len()];
    for (l, o) in over.into_iter().enumerate() {
        if l == 0 || o.is_empty() {
            continue;
        }
        let j = (l - 1).saturating_sub(gap);
        need[j] = union(&need[j], &o);
    }
    need
}

/// Supports for every layer (empty when the profile has none). `printed` is each layer's
/// printed region (see [`overhangs`]).
pub fn supports(
    regions: &[Region],
    printed: &[Region],
    heights: &[f64],
    s: &FdmSettings,
) -> Vec<SupportLayer> {
    let n = regions.len();
    if s.supports == SupportStyle::None || n == 0 {
        return vec![SupportLayer::default(); n];
    }
    let w = s.line_width;
    let xy = XY_GAP_PER_LINE * w;
    let h = s.layer_height;
    let gap = if s.support_z_gap > 0.0 {
        ((s.support_z_gap / h).round() as usize).max(1)
    } else {
        0
    };
    let need = needs(overhangs(regions, printed, heights, s), gap);
    // Support keeps clear of what is printed (a sliver of the model too thin for any line
    // may be covered by support: the tip of a point standing on the bed).
    let blocked: Vec<Region> = {
        use rayon::prelude::*;
        printed.par_iter().map(|r| offset(r, xy)).collect()
    };
    let columns = match s.supports {
        SupportStyle::Tree => tree_columns(&need, &blocked, heights, w),
        _ => grid_columns(&need, &blocked),
    };
    // Not in the gap above the model below; specks dropped (a support narrower than a line
    // still gets the lines its hatch finds in it).
    let printed: Vec<Region> = (0..n)
        .map(|j| {
            let mut p = columns[j].clone();
            for k in 1..=gap {
                if let Some(b) = j.checked_sub(k) {
                    p = difference(&p, &blocked[b]);
                }
            }
            opening(&p, SPECK_PER_LINE * w)
        })
        .collect();
    (0..n)
        .map(|j| {
            // Dense where the support ends within INTERFACE_LAYERS above.
            let mut held = printed[j].clone();
            for k in 1..=INTERFACE_LAYERS {
                held = match printed.get(j + k) {
                    Some(p) => intersect(&held, p),
                    None => Vec::new(),
                };
            }
            let interface = difference(&printed[j], &held);
            SupportLayer {
                body: held,
                interface,
            }
        })
        .collect()
}

/// Straight columns: each layer's support is everything above it that needs holding up,
/// less the model.
fn grid_columns(need: &[Region], blocked: &[Region]) -> Vec<Region> {
    let n = need.len();
    let mut out = vec![Vec::new(); n];
    let mut carry: Region = Vec::new();
    for j in (0..n).rev() {
        carry = union(&carry, &need[j]);
        carry = difference(&carry, &blocked[j]);
        out[j] = carry.clone();
    }
    out
}

/// A branch of a tree support on one layer.
#[derive(Clone, Copy, Debug)]
struct Branch {
    at: Point,
    radius: f64,
}

/// Tree columns: branches from tips under the overhangs, each leaning toward its nearest
/// neighbour as it descends (merging when they meet) and away from the model.
fn tree_columns(need: &[Region], blocked: &[Region], heights: &[f64], w: f64) -> Vec<Region> {
    let n = need.len();
    let mut out = vec![Vec::new(); n];
    let mut branches: Vec<Branch> = Vec::new();
    let lean = TREE_BRANCH_ANGLE.to_radians().tan();
    for j in (0..n).rev() {
        // New tips under the overhangs this layer holds up.
        branches.extend(tips(&need[j]).into_iter().map(|at| Branch {
            at,
            radius: TREE_TIP_RADIUS.max(w),
        }));
        if branches.is_empty() {
            continue;
        }
        let step = heights.get(j).copied().unwrap_or(0.2) * lean;
        // Lean each branch toward its nearest neighbour; merge those that meet.
        let snapshot = branches.clone();
        for (i, b) in branches.iter_mut().enumerate() {
            let nearest = snapshot
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != i)
                .map(|(_, o)| o.at)
                .min_by(|a, c| dist(*a, b.at).total_cmp(&dist(*c, b.at)));
            if let Some(t) = nearest {
                let d = dist(t, b.at);
                if d > 0.0 {
                    let m = step.min(d * 0.5);
                    let to = [
                        b.at[0] + (t[0] - b.at[0]) / d * m,
                        b.at[1] + (t[1] - b.at[1]) / d * m,
                    ];
                    // Never lean into the model.
                    if !inside_region(to, &blocked[j]) {
                        b.at = to;
                    }
                }
            }
            b.radius += TREE_RADIUS_GROWTH * heights.get(j).copied().unwrap_or(0.2);
        }
        merge_branches(&mut branches);
        // A branch standing on the model stops there (it rests on its top).
        branches.retain(|b| !inside_region(b.at, &blocked[j]));
        let discs: Vec<Region> = branches.iter().map(|b| vec![vec![disc(b)]]).collect();
        let area = union_all(discs.iter());
        out[j] = difference(&area, &blocked[j]);
    }
    out
}

/// Tip points under an overhang: a grid, plus the centre of any piece too small to get a
/// grid point.
fn tips(over: &Region) -> Vec<Point> {
    let mut out = Vec::new();
    for shape in over {
        let piece = vec![shape.clone()];
        let Some((lo, hi)) = crate::geom::bbox(shape.iter().flatten()) else {
            continue;
        };
        let mut found = false;
        let (i0, i1) = (
            (lo[0] / TREE_TIP_SPACING).floor() as i64,
            (hi[0] / TREE_TIP_SPACING).ceil() as i64,
        );
        let (j0, j1) = (
            (lo[1] / TREE_TIP_SPACING).floor() as i64,
            (hi[1] / TREE_TIP_SPACING).ceil() as i64,
        );
        for i in i0..=i1 {
            for j in j0..=j1 {
                let p = [i as f64 * TREE_TIP_SPACING, j as f64 * TREE_TIP_SPACING];
                if inside_region(p, &piece) {
                    out.push(p);
                    found = true;
                }
            }
        }
        if !found {
            out.push([(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5]);
        }
    }
    out
}

/// Joins branches closer than their radii into one, at their weighted middle.
fn merge_branches(branches: &mut Vec<Branch>) {
    let mut i = 0;
    while i < branches.len() {
        let mut j = i + 1;
        while j < branches.len() {
            let (a, b) = (branches[i], branches[j]);
            if dist(a.at, b.at) < 0.5 * (a.radius + b.radius) {
                let (wa, wb) = (a.radius * a.radius, b.radius * b.radius);
                branches[i] = Branch {
                    at: [
                        (a.at[0] * wa + b.at[0] * wb) / (wa + wb),
                        (a.at[1] * wa + b.at[1] * wb) / (wa + wb),
                    ],
                    radius: (wa + wb).sqrt(),
                };
                branches.swap_remove(j);
            } else {
                j += 1;
            }
        }
        i += 1;
    }
}

/// A branch's cross-section: a 16-sided polygon, counter-clockwise.
fn disc(b: &Branch) -> Vec<Point> {
    (0..16)
        .map(|k| {
            let a = k as f64 / 16.0 * std::f64::consts::TAU;
            [b.at[0] + b.radius * a.cos(), b.at[1] + b.radius * a.sin()]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;
    use crate::geom::region_area;
    use crate::profile::Profile;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Region {
        region_from_contours(&[vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]])
    }

    /// A table: a 4 mm post with a 20 mm top from layer 20 on.
    fn table() -> (Vec<Region>, Vec<f64>) {
        let regions: Vec<Region> = (0..30)
            .map(|l| {
                if l < 20 {
                    rect(-2.0, -2.0, 2.0, 2.0)
                } else {
                    rect(-10.0, -10.0, 10.0, 10.0)
                }
            })
            .collect();
        (regions, vec![0.2; 30])
    }

    fn settings(style: &str) -> FdmSettings {
        let mut p = Profile::default_fdm();
        p.set(&format!("supports={style}")).unwrap();
        p.fdm().unwrap()
    }

    #[test]
    fn grid_supports_hold_up_the_table_top_with_a_gap() {
        let (regions, heights) = table();
        let sup = supports(&regions, &regions, &heights, &settings("grid"));
        // Under the top (layer 20, gap one layer): layers 0..=18 hold support, 19 is the gap.
        assert!(sup[19].all().is_empty());
        let a = region_area(&sup[18].all());
        assert!(a > 300.0 && a < 400.0, "{a}");
        assert!(!sup[18].interface.is_empty());
        assert!(sup[10].interface.is_empty() && !sup[10].body.is_empty());
        assert!(!sup[0].body.is_empty());
        // Never inside the post.
        for s in &sup {
            assert!(region_area(&intersect(&s.all(), &regions[0])) < 1e-6);
        }
        // Nothing above the top.
        assert!(sup[25].all().is_empty());
    }

    #[test]
    fn tree_supports_use_less_material_than_columns() {
        let (regions, heights) = table();
        let grid = supports(&regions, &regions, &heights, &settings("grid"));
        let tree = supports(&regions, &regions, &heights, &settings("tree"));
        let total = |s: &[SupportLayer]| s.iter().map(|l| region_area(&l.all())).sum::<f64>();
        assert!(!tree[18].all().is_empty() && !tree[0].all().is_empty());
        assert!(
            total(&tree) < 0.7 * total(&grid),
            "{} vs {}",
            total(&tree),
            total(&grid)
        );
    }

    #[test]
    fn no_supports_when_off() {
        let (regions, heights) = table();
        let sup = supports(&regions, &regions, &heights, &settings("none"));
        assert!(sup.iter().all(|s| s.all().is_empty()));
    }
}
