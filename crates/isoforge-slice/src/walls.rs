//! Walls: perimeter loops inset from an island's outline, and where the island (or the gap
//! left between loops) is too narrow for a loop, lines of its own width along its centre.
//!
//! A loop of width w can go around a region only where the region is at least 2w across:
//! narrower, its two sides would overlap (a 0.6 mm wall printed as one 0.45 mm loop lays
//! two lines 0.15 mm apart: 148% of the wall's volume). So at each depth the region is
//! split by an opening of radius w into the part where a loop fits and the thin rest. The
//! thin rest is printed along its centre line: as one line of the local width where it is
//! under 1.5 w across, as two lines of half the width where it is wider (a 0.8 mm wall:
//! two 0.4 mm lines). Thin parts at depth 0 are thin walls; deeper ones are the gaps
//! between loops (a 1.2 mm wall leaves a 0.3 mm gap between its two 0.45 mm lines).

use crate::clip::{difference, offset, opening};
use crate::geom::{Contour, Point, Region, dist, polyline_length, region_area};
use crate::medial::{CentreLine, centre_lines};

/// A centre line wider than this many line widths is printed as two lines of half its
/// width (between one and two line widths one line would be over 1.5 w wide, two lines
/// under 0.75 w each; the switch sits where both errors are equal).
const TWO_LINES_ABOVE: f64 = 1.5;

/// Lines narrower than this fraction of the nozzle are not printed: they would only ooze.
const MIN_WIDTH_PER_NOZZLE: f64 = 0.25;

/// Centre-line pixels per line width: a tenth resolves a 0.4 mm wall with 9 pixels.
const PIXELS_PER_LINE: f64 = 10.0;

/// A closed loop of constant width.
#[derive(Clone, Debug, PartialEq)]
pub struct Loop {
    /// 0 for the outermost loop (touching the outline), then inward.
    pub depth: usize,
    /// The loop (closed; the last point connects to the first).
    pub contour: Contour,
}

/// A line of varying width.
#[derive(Clone, Debug, PartialEq)]
pub struct Bead {
    /// The points; a closed bead repeats its first point at the end.
    pub points: Vec<Point>,
    /// The width of each segment (one fewer than the points).
    pub widths: Vec<f64>,
}

impl Bead {
    /// True when the bead ends where it starts.
    #[cfg(test)]
    pub fn closed(&self) -> bool {
        self.points.len() > 2 && self.points.first() == self.points.last()
    }

    /// Its volume per mm of height, mm²: the sum of segment length times width.
    pub fn area(&self) -> f64 {
        self.points
            .windows(2)
            .zip(&self.widths)
            .map(|(w, width)| dist(w[0], w[1]) * width)
            .sum()
    }
}

/// One island's walls.
#[derive(Clone, Debug, Default)]
pub struct Walls {
    /// Loops from the outside in.
    pub loops: Vec<Loop>,
    /// Thin walls: lines of their own width where the island is too narrow for a loop.
    pub thin: Vec<Bead>,
    /// Gap fill: lines of their own width in the gaps between loops.
    pub gaps: Vec<Bead>,
    /// What is left inside the innermost loop, for skins and infill.
    pub inner: Region,
}

/// What walls to make.
#[derive(Copy, Clone, Debug)]
pub struct WallSpec {
    /// Loops.
    pub count: usize,
    /// Line width, mm.
    pub width: f64,
    /// Nozzle diameter, mm (the narrowest line printed is a fraction of it).
    pub nozzle: f64,
    /// Print thin walls.
    pub thin_walls: bool,
    /// Fill the gaps between loops.
    pub gap_fill: bool,
}

/// Builds the walls of one island (a region of one outer contour and its holes).
pub fn walls(island: &Region, spec: &WallSpec) -> Walls {
    let w = spec.width;
    let mut out = Walls::default();
    let mut region = island.clone();
    for depth in 0..spec.count {
        if region.is_empty() {
            break;
        }
        let fits = opening(&region, w);
        let wanted = if depth == 0 {
            spec.thin_walls
        } else {
            spec.gap_fill
        };
        if wanted && region_area(&region) - region_area(&fits) > 1e-6 {
            let thin = difference(&region, &fits);
            let beads = thin_beads(&thin, spec);
            if depth == 0 {
                out.thin.extend(beads);
            } else {
                out.gaps.extend(beads);
            }
        }
        if fits.is_empty() {
            region.clear();
            break;
        }
        for c in offset(&fits, -0.5 * w).into_iter().flatten() {
            out.loops.push(Loop { depth, contour: c });
        }
        region = offset(&fits, -w);
    }
    out.inner = region;
    out
}

/// Lines along the centre of a thin region: one of the local width, or two of half of it.
pub fn thin_beads(thin: &Region, spec: &WallSpec) -> Vec<Bead> {
    if thin.is_empty() {
        return Vec::new();
    }
    let w = spec.width;
    let min_width = MIN_WIDTH_PER_NOZZLE * spec.nozzle;
    let mut out = Vec::new();
    for line in centre_lines(thin, w / PIXELS_PER_LINE) {
        for run in runs(&line, min_width, TWO_LINES_ABOVE * w) {
            let bead = if run.double {
                double_bead(&run.line)
            } else {
                single_bead(&run.line)
            };
            if polyline_length(&bead.points) >= w.min(4.0 * min_width) && bead.area() > 0.0 {
                out.push(bead);
            }
        }
    }
    out
}

/// A stretch of a centre line printed one way.
struct Run {
    line: CentreLine,
    double: bool,
}

/// Splits a centre line where it gets too narrow to print (dropped) or crosses the width
/// where two lines replace one.
fn runs(line: &CentreLine, min_width: f64, two_above: f64) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    let class = |w: f64| {
        if w < min_width {
            None
        } else {
            Some(w > two_above)
        }
    };
    let mut current: Option<(bool, CentreLine)> = None;
    for (p, &width) in line.points.iter().zip(&line.widths) {
        match (class(width), current.as_mut()) {
            (Some(d), Some((cd, cl))) if *cd == d => {
                cl.points.push(*p);
                cl.widths.push(width);
            }
            (c, _) => {
                if let Some((d, cl)) = current.take()
                    && cl.points.len() >= 2
                {
                    out.push(Run {
                        line: cl,
                        double: d,
                    });
                }
                current = c.map(|d| {
                    (
                        d,
                        CentreLine {
                            points: vec![*p],
                            widths: vec![width],
                        },
                    )
                });
            }
        }
    }
    if let Some((d, cl)) = current
        && cl.points.len() >= 2
    {
        out.push(Run {
            line: cl,
            double: d,
        });
    }
    out
}

/// One line of the local width; segment widths are the mean of their ends'.
fn single_bead(line: &CentreLine) -> Bead {
    let widths = line
        .widths
        .windows(2)
        .map(|w| 0.5 * (w[0] + w[1]))
        .collect();
    Bead {
        points: line.points.clone(),
        widths,
    }
}

/// Two lines of half the local width, a quarter of the width to each side of the centre,
/// joined at the ends into one loop (no travel between them).
fn double_bead(line: &CentreLine) -> Bead {
    let n = line.points.len();
    let normal = |i: usize| -> Point {
        let a = line.points[i.saturating_sub(1)];
        let b = line.points[(i + 1).min(n - 1)];
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy);
        if l > 0.0 {
            [-dy / l, dx / l]
        } else {
            [0.0, 0.0]
        }
    };
    let side = |sign: f64| -> Vec<Point> {
        (0..n)
            .map(|i| {
                let q = normal(i);
                let d = sign * line.widths[i] * 0.25;
                [line.points[i][0] + q[0] * d, line.points[i][1] + q[1] * d]
            })
            .collect()
    };
    let mut points = side(1.0);
    let mut back = side(-1.0);
    back.reverse();
    points.extend(back);
    if let Some(&first) = points.first() {
        points.push(first);
    }
    let half: Vec<f64> = line.widths.iter().map(|w| 0.5 * w).collect();
    let seg = |a: f64, b: f64| 0.5 * (a + b);
    let mut widths: Vec<f64> = half.windows(2).map(|w| seg(w[0], w[1])).collect();
    // The turn at the far end, the way back, and the turn home.
    widths.push(half[n - 1]);
    widths.extend(half.windows(2).rev().map(|w| seg(w[0], w[1])));
    widths.push(half[0]);
    Bead { points, widths }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clip::region_from_contours;

    const SPEC: WallSpec = WallSpec {
        count: 2,
        width: 0.45,
        nozzle: 0.4,
        thin_walls: true,
        gap_fill: true,
    };

    fn strip(t: f64) -> Region {
        region_from_contours(&[vec![[0.0, 0.0], [20.0, 0.0], [20.0, t], [0.0, t]]])
    }

    /// The area the walls cover: loops are w wide, beads their own width.
    fn covered(wl: &Walls, w: f64) -> f64 {
        let loops: f64 = wl
            .loops
            .iter()
            .map(|l| {
                let mut c = l.contour.clone();
                c.push(c[0]);
                polyline_length(&c) * w
            })
            .sum();
        loops + wl.thin.iter().chain(&wl.gaps).map(Bead::area).sum::<f64>()
    }

    #[test]
    fn thin_walls_are_printed_at_their_volume() {
        for t in [0.4, 0.6, 0.8, 1.2] {
            let wl = walls(&strip(t), &SPEC);
            let share = covered(&wl, SPEC.width) / (20.0 * t);
            assert!(
                (share - 1.0).abs() < 0.06,
                "{t} mm wall: {:.0}% ({} loops, {} thin, {} gaps)",
                share * 100.0,
                wl.loops.len(),
                wl.thin.len(),
                wl.gaps.len()
            );
        }
    }

    #[test]
    fn an_eight_tenths_wall_gets_two_half_width_lines() {
        let wl = walls(&strip(0.8), &SPEC);
        assert!(wl.loops.is_empty());
        assert_eq!(wl.thin.len(), 1);
        let b = &wl.thin[0];
        assert!(b.closed());
        let mid: Vec<f64> = b
            .points
            .windows(2)
            .zip(&b.widths)
            .filter(|(p, _)| p[0][0] > 2.0 && p[0][0] < 18.0)
            .map(|(_, w)| *w)
            .collect();
        assert!(mid.iter().all(|w| (w - 0.4).abs() < 0.03), "{mid:?}");
    }

    #[test]
    fn a_square_gets_two_loops_and_its_inside() {
        let sq = region_from_contours(&[vec![[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]]);
        let wl = walls(&sq, &SPEC);
        assert_eq!(wl.loops.len(), 2);
        assert!(wl.thin.is_empty() && wl.gaps.is_empty());
        let side = 10.0 - 4.0 * 0.45;
        assert!((region_area(&wl.inner) - side * side).abs() < 1e-3);
    }

    #[test]
    fn without_thin_walls_a_thin_wall_is_not_printed() {
        let spec = WallSpec {
            thin_walls: false,
            ..SPEC
        };
        let wl = walls(&strip(0.6), &spec);
        assert!(wl.loops.is_empty() && wl.thin.is_empty());
    }
}
