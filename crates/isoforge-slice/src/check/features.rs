//! Judging what a G-code file prints, from its parsed moves alone (any slicer's file): how
//! often it retracts, how long each layer takes, how much it extrudes where, and whether
//! anything is printed over nothing.

use super::{Extrude, GcodeReport};

pub use super::bridges::{BridgeLine, bridge_lines};

/// Retractions: runs of moves that pull filament back (with or without motion: a wipe
/// retracts while it moves), each run counted once.
pub fn retractions(r: &GcodeReport) -> usize {
    let mut count = 0;
    let mut pulling = false;
    for m in &r.moves {
        let pulls = m.e < 0.0;
        if pulls && !pulling {
            count += 1;
        }
        pulling = pulls;
    }
    count
}

/// Each layer's time at the feed rates asked (accelerations ignored, so a lower bound on
/// what a printer takes) with its waits, s, by layer number.
pub fn layer_times(r: &GcodeReport) -> Vec<(usize, f64)> {
    let mut times: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    for m in &r.moves {
        let Some(l) = m.layer else { continue };
        let d = ((m.to[0] - m.from[0]).powi(2)
            + (m.to[1] - m.from[1]).powi(2)
            + (m.to[2] - m.from[2]).powi(2))
        .sqrt();
        let len = d.max(m.e.abs());
        if m.feed > 0.0 {
            *times.entry(l).or_default() += len / m.feed;
        }
    }
    for &(l, t) in &r.dwells {
        if let Some(l) = l {
            *times.entry(l).or_default() += t;
        }
    }
    times.into_iter().collect()
}

/// Extruded volume, mm³, of the moves `keep` accepts, for filament of diameter `d`.
pub fn volume_where(r: &GcodeReport, d: f64, keep: impl Fn(&Extrude) -> bool) -> f64 {
    let a = std::f64::consts::PI * (d / 2.0).powi(2);
    r.extrusions
        .iter()
        .filter(|x| keep(x))
        .map(|x| x.e * a)
        .sum()
}

/// A layer's printed footprint on a grid: every cell within `reach` of an extrusion's
/// centre line.
pub struct Footprint {
    origin: [f64; 2],
    cell: f64,
    nx: usize,
    ny: usize,
    on: Vec<bool>,
}

impl Footprint {
    /// The footprint of `moves` on a grid over `lo`..`hi` with cells of `cell` mm.
    pub fn new<'a>(
        moves: impl IntoIterator<Item = &'a Extrude>,
        lo: [f64; 2],
        hi: [f64; 2],
        cell: f64,
        reach: f64,
    ) -> Footprint {
        let nx = ((hi[0] - lo[0]) / cell).ceil().max(1.0) as usize + 1;
        let ny = ((hi[1] - lo[1]) / cell).ceil().max(1.0) as usize + 1;
        let mut f = Footprint {
            origin: lo,
            cell,
            nx,
            ny,
            on: vec![false; nx.saturating_mul(ny).min(100_000_000)],
        };
        let r = (reach / cell).ceil() as i64;
        for m in moves {
            let len = (m.to[0] - m.from[0]).hypot(m.to[1] - m.from[1]);
            let steps = (len / (0.5 * cell)).ceil().max(1.0) as usize;
            for k in 0..=steps {
                let t = k as f64 / steps as f64;
                let p = [
                    m.from[0] + t * (m.to[0] - m.from[0]),
                    m.from[1] + t * (m.to[1] - m.from[1]),
                ];
                let (ci, cj) = f.cell_of(p);
                for dj in -r..=r {
                    for di in -r..=r {
                        let (i, j) = (ci + di, cj + dj);
                        let c = [
                            f.origin[0] + (i as f64 + 0.5) * cell,
                            f.origin[1] + (j as f64 + 0.5) * cell,
                        ];
                        if (c[0] - p[0]).hypot(c[1] - p[1]) <= reach {
                            f.set(i, j);
                        }
                    }
                }
            }
        }
        f
    }

    fn cell_of(&self, p: [f64; 2]) -> (i64, i64) {
        (
            ((p[0] - self.origin[0]) / self.cell).floor() as i64,
            ((p[1] - self.origin[1]) / self.cell).floor() as i64,
        )
    }

    fn set(&mut self, i: i64, j: i64) {
        if i >= 0 && j >= 0 && (i as usize) < self.nx && (j as usize) < self.ny {
            let k = j as usize * self.nx + i as usize;
            if let Some(c) = self.on.get_mut(k) {
                *c = true;
            }
        }
    }

    /// True when `p` is within reach of a printed line.
    pub fn covers(&self, p: [f64; 2]) -> bool {
        let (i, j) = self.cell_of(p);
        i >= 0
            && j >= 0
            && (i as usize) < self.nx
            && (j as usize) < self.ny
            && self
                .on
                .get(j as usize * self.nx + i as usize)
                .copied()
                .unwrap_or(false)
    }
}

/// A stretch of extrusion printed over nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct OverNothing {
    /// The layer.
    pub layer: usize,
    /// The G-code line of the move.
    pub line: usize,
    /// How long the stretch over nothing runs, mm.
    pub length: f64,
}

/// Extrusions with a stretch longer than `span` mm that has nothing within `reach` on the
/// `below` layers under it (two: one layer of air is a support's Z gap). Moves `skip`
/// accepts (bridges, when judging only supports) are not judged. Layer 0 sits on the bed.
pub fn over_nothing(
    r: &GcodeReport,
    below: usize,
    reach: f64,
    span: f64,
    skip: impl Fn(&Extrude) -> bool,
) -> Vec<OverNothing> {
    let Some((lo, hi)) = extent(r) else {
        return Vec::new();
    };
    let cell = reach * 0.5;
    let mut by_layer: std::collections::BTreeMap<usize, Vec<&Extrude>> = Default::default();
    for x in &r.extrusions {
        if let Some(l) = x.layer {
            by_layer.entry(l).or_default().push(x);
        }
    }
    let layers: Vec<usize> = by_layer.keys().copied().collect();
    let mut prints: std::collections::BTreeMap<usize, Footprint> = Default::default();
    let mut out = Vec::new();
    for &l in &layers {
        if l == layers[0] {
            continue;
        }
        for b in 1..=below {
            let Some(lb) = l.checked_sub(b) else { continue };
            if !prints.contains_key(&lb)
                && let Some(ms) = by_layer.get(&lb)
            {
                prints.insert(lb, Footprint::new(ms.iter().copied(), lo, hi, cell, reach));
            }
        }
        prints.retain(|&k, _| k + below >= l);
        let held = |p: [f64; 2]| {
            (1..=below).any(|b| {
                l.checked_sub(b)
                    .and_then(|lb| prints.get(&lb))
                    .is_some_and(|f| f.covers(p))
            })
        };
        for x in &by_layer[&l] {
            if skip(x) {
                continue;
            }
            let len = (x.to[0] - x.from[0]).hypot(x.to[1] - x.from[1]);
            let steps = (len / cell).ceil().max(1.0) as usize;
            let (mut run, mut worst) = (0.0f64, 0.0f64);
            for k in 0..=steps {
                let t = k as f64 / steps as f64;
                let p = [
                    x.from[0] + t * (x.to[0] - x.from[0]),
                    x.from[1] + t * (x.to[1] - x.from[1]),
                ];
                if held(p) {
                    run = 0.0;
                } else {
                    run += len / steps as f64;
                    worst = worst.max(run);
                }
            }
            if worst > span {
                out.push(OverNothing {
                    layer: l,
                    line: x.line,
                    length: worst,
                });
            }
        }
    }
    out
}

/// The x-y box of every extrusion.
fn extent(r: &GcodeReport) -> Option<([f64; 2], [f64; 2])> {
    let mut it = r.extrusions.iter().flat_map(|x| [x.from, x.to]);
    let first = it.next()?;
    let (mut lo, mut hi) = ([first[0], first[1]], [first[0], first[1]]);
    for p in it {
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    Some(([lo[0] - 2.0, lo[1] - 2.0], [hi[0] + 2.0, hi[1] + 2.0]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::parse;

    #[test]
    fn retractions_wipes_and_layer_times_are_counted() {
        let g = "G90\nM82\nG92 E0\n;LAYER:0\nG1 X10 Y0 E1 F600\nG1 E0 F2400\nG0 X20 F6000\nG1 E1\nG1 X30 E2 F600\n;LAYER:1\nG1 X29 Y0 E1.5 F600\nG1 X28 E1 F600\nG1 E0.5\nG4 P2000\n";
        let r = parse(g).unwrap();
        assert_eq!(retractions(&r), 2);
        let t = layer_times(&r);
        // Layer 0: 10 mm at 10 mm/s, 1 mm of E at 40 mm/s, 10 mm at 100, 1 mm of E at 100
        // (the feed carries over), 10 mm at 10.
        assert!(
            (t[0].1 - (1.0 + 0.025 + 0.1 + 0.01 + 1.0)).abs() < 1e-9,
            "{t:?}"
        );
        // Layer 1: two 1 mm moves at 10 mm/s, 0.5 mm of E at 10 mm/s, a 2 s wait.
        assert!((t[1].1 - (0.1 + 0.1 + 0.05 + 2.0)).abs() < 1e-9, "{t:?}");
    }

    #[test]
    fn a_line_over_air_is_found_and_one_over_a_line_is_not() {
        let g = "G90\nM82\nG92 E0\n;LAYER:0\nG1 X0 Y0 F600\nG1 X10 Y0 E1\n;LAYER:1\nG1 X0 Y0.1 E1.5\nG1 X10 Y0.1 E2\nG1 X10 Y10 E3\n";
        let r = parse(g).unwrap();
        let bad = over_nothing(&r, 1, 0.45, 1.0, |_| false);
        assert_eq!(bad.len(), 1);
        assert_eq!(bad[0].layer, 1);
        assert!(bad[0].length > 9.0, "{bad:?}");
    }
}
