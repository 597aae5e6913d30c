//! Judging bridges: each bridge line should start and end on material printed on the
//! layer below (anchored) and cross air between (it is a bridge, not a dab).

use super::GcodeReport;
use super::features::Footprint;

/// One bridge line as printed.
#[derive(Clone, Debug, PartialEq)]
pub struct BridgeLine {
    /// The layer.
    pub layer: usize,
    /// The G-code line of the move.
    pub line: usize,
    /// Start and end, x and y.
    pub from: [f64; 2],
    /// End.
    pub to: [f64; 2],
    /// Its length, mm.
    pub length: f64,
    /// True when it crosses material of the layer below within the anchor length of
    /// its start.
    pub start_held: bool,
    /// The same at its end.
    pub end_held: bool,
    /// How much of it runs over nothing, mm.
    pub over_air: f64,
}

/// Every move at least `min_length` mm long whose feature `is_bridge` accepts, judged
/// against the layer below's lines (material within `reach` of a line counts). An end is
/// anchored when the line crosses material within `anchor` mm of it: a bridge over the
/// top of a pillar filled with sparse infill lands on the pillar's walls and infill
/// lines, not necessarily on a line at its very end.
pub fn bridge_lines(
    r: &GcodeReport,
    is_bridge: impl Fn(&str) -> bool,
    reach: f64,
    min_length: f64,
    anchor: f64,
) -> Vec<BridgeLine> {
    let mut out = Vec::new();
    let layers: std::collections::BTreeSet<usize> = r
        .extrusions
        .iter()
        .filter(|x| is_bridge(&x.feature))
        .filter_map(|x| x.layer)
        .collect();
    for l in layers {
        let Some(lb) = l.checked_sub(1) else { continue };
        let below: Vec<_> = r
            .extrusions
            .iter()
            .filter(|x| x.layer == Some(lb))
            .collect();
        let here: Vec<_> = r
            .extrusions
            .iter()
            .filter(|x| x.layer == Some(l) && is_bridge(&x.feature))
            .filter(|x| (x.to[0] - x.from[0]).hypot(x.to[1] - x.from[1]) >= min_length)
            .collect();
        let pts = here.iter().chain(&below).flat_map(|x| [x.from, x.to]);
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in pts {
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        if !lo[0].is_finite() {
            continue;
        }
        let cell = reach * 0.25;
        let print = Footprint::new(
            below.iter().copied(),
            [lo[0] - 1.0, lo[1] - 1.0],
            [hi[0] + 1.0, hi[1] + 1.0],
            cell,
            reach,
        );
        for x in here {
            let (a, b) = ([x.from[0], x.from[1]], [x.to[0], x.to[1]]);
            let length = (b[0] - a[0]).hypot(b[1] - a[1]);
            let steps = (length / cell).ceil().max(1.0) as usize;
            let step = length / steps as f64;
            // Whether each sample (at the middle of each step) is over material.
            let held: Vec<bool> = (0..steps)
                .map(|k| {
                    let t = (k as f64 + 0.5) / steps as f64;
                    print.covers([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
                })
                .collect();
            let air = held.iter().filter(|&&h| !h).count() as f64 * step;
            let ends = ((anchor / step).ceil() as usize).clamp(1, steps);
            let start_held = held[..ends].iter().any(|&h| h);
            let end_held = held[steps - ends..].iter().any(|&h| h);
            out.push(BridgeLine {
                layer: l,
                line: x.line,
                from: a,
                to: b,
                length,
                start_held,
                end_held,
                over_air: air,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::parse;

    #[test]
    fn a_line_between_two_pads_is_anchored_and_crosses_air() {
        let g = "G90\nM82\nG92 E0\n;LAYER:0\n;TYPE:WALL\nG1 X0 Y0 F600\nG1 X2 Y0 E1\nG0 X20 Y0\nG1 X22 Y0 E2\n;LAYER:1\n;TYPE:BRIDGE\nG0 X1 Y0\nG1 X21 Y0 E3\nG1 X21 Y5 E3.5\n";
        let r = parse(g).unwrap();
        let lines = bridge_lines(&r, |f| f == "BRIDGE", 0.3, 2.0, 0.5);
        assert_eq!(lines.len(), 2);
        let l = &lines[0];
        assert!(l.start_held && l.end_held);
        assert!((l.over_air - 17.4).abs() < 0.5, "{l:?}");
        assert!(lines[1].start_held && !lines[1].end_held);
    }
}
