//! Print time as Marlin's planner spends it: each move accelerates and decelerates at the
//! machine's acceleration (trapezoids), and passes through a corner no faster than its
//! junction deviation allows. Marlin 2 (planner.cpp) computes a corner's limit as
//! v² = a·JD·sin(θ/2) / (1 − sin(θ/2)), θ the angle between the moves; a lookahead then
//! lowers each entry speed until every move can decelerate into the next one.

/// One move for the planner: its length, the speed asked, its acceleration and its unit
/// direction in x, y, z (`None` for a move of the extruder alone, which stops at both
/// ends).
#[derive(Copy, Clone, Debug)]
pub struct Block {
    /// Length, mm (x, y, z; or filament for an extruder-only move).
    pub length: f64,
    /// Speed asked, mm/s.
    pub speed: f64,
    /// Acceleration, mm/s².
    pub accel: f64,
    /// Unit direction, or `None` for extruder-only moves.
    pub dir: Option<[f64; 3]>,
    /// A pause after the move, s (dwell).
    pub pause: f64,
}

/// The machine's limits the planner honours.
#[derive(Copy, Clone, Debug)]
pub struct Limits {
    /// Junction deviation, mm.
    pub junction_deviation: f64,
}

/// The time each block takes, s (pauses included), planned as one sequence starting and
/// ending at rest.
pub fn block_times(blocks: &[Block], limits: Limits) -> Vec<f64> {
    let n = blocks.len();
    // The highest speed each block may enter at: the corner with the previous block.
    let mut max_entry = vec![0.0f64; n];
    for i in 1..n {
        let (a, b) = (&blocks[i - 1], &blocks[i]);
        max_entry[i] = match (a.dir, b.dir) {
            (Some(u), Some(v)) if a.pause == 0.0 => {
                let junction =
                    junction_speed(u, v, b.accel.min(a.accel), limits.junction_deviation);
                junction.min(a.speed).min(b.speed)
            }
            _ => 0.0,
        };
    }
    // Backward pass: every block must be able to slow down to the next one's entry.
    let mut entry = max_entry.clone();
    let mut exit_next = 0.0f64;
    for i in (0..n).rev() {
        let b = &blocks[i];
        entry[i] = entry[i].min((exit_next * exit_next + 2.0 * b.accel * b.length).sqrt());
        exit_next = entry[i];
    }
    // Forward pass: and speed up no faster than its acceleration allows.
    for i in 0..n {
        let b = &blocks[i];
        if i + 1 < n {
            let reach = (entry[i] * entry[i] + 2.0 * b.accel * b.length).sqrt();
            entry[i + 1] = entry[i + 1].min(reach);
        }
    }
    (0..n)
        .map(|i| {
            let b = &blocks[i];
            let v0 = entry[i];
            let v1 = if i + 1 < n { entry[i + 1] } else { 0.0 };
            trapezoid(b.length, v0, v1, b.speed, b.accel) + b.pause
        })
        .collect()
}

/// Marlin's junction speed limit between unit directions `u` then `v`.
fn junction_speed(u: [f64; 3], v: [f64; 3], accel: f64, jd: f64) -> f64 {
    // cos θ where θ is the angle between -u and v (0 for a full reversal).
    let cos = -(u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
    if cos > 0.999_999 {
        return 0.0;
    }
    if cos < -0.999_999 {
        return f64::INFINITY;
    }
    let sin_half = (0.5 * (1.0 - cos)).max(0.0).sqrt();
    (accel * jd * sin_half / (1.0 - sin_half)).sqrt()
}

/// The time to cover `d` mm entering at `v0`, leaving at `v1`, cruising at most at
/// `vmax`, accelerating at `a`.
fn trapezoid(d: f64, v0: f64, v1: f64, vmax: f64, a: f64) -> f64 {
    if d <= 0.0 || vmax <= 0.0 {
        return 0.0;
    }
    if a <= 0.0 || !a.is_finite() {
        return d / vmax;
    }
    let (v0, v1) = (v0.min(vmax), v1.min(vmax));
    let d_acc = (vmax * vmax - v0 * v0) / (2.0 * a);
    let d_dec = (vmax * vmax - v1 * v1) / (2.0 * a);
    if d_acc + d_dec <= d {
        (vmax - v0) / a + (vmax - v1) / a + (d - d_acc - d_dec) / vmax
    } else {
        let peak = ((2.0 * a * d + v0 * v0 + v1 * v1) * 0.5)
            .sqrt()
            .max(v0.max(v1));
        (peak - v0) / a + (peak - v1) / a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(length: f64, dir: [f64; 3]) -> Block {
        Block {
            length,
            speed: 100.0,
            accel: 1000.0,
            dir: Some(dir),
            pause: 0.0,
        }
    }

    const LIMITS: Limits = Limits {
        junction_deviation: 0.013,
    };

    #[test]
    fn a_long_move_cruises_and_a_short_one_never_reaches_speed() {
        // 100 mm at 100 mm/s, 1000 mm/s²: 0.1 s (5 mm) up, 0.1 s down, 90 mm cruising.
        let t = block_times(&[line(100.0, [1.0, 0.0, 0.0])], LIMITS);
        assert!((t[0] - 1.1).abs() < 1e-9, "{}", t[0]);
        // 1 mm: a triangle peaking at sqrt(1000) mm/s.
        let t = block_times(&[line(1.0, [1.0, 0.0, 0.0])], LIMITS);
        assert!((t[0] - 2.0 * 1000f64.sqrt() / 1000.0).abs() < 1e-9);
    }

    #[test]
    fn straight_runs_keep_speed_and_corners_slow_down() {
        let straight = block_times(
            &[line(10.0, [1.0, 0.0, 0.0]), line(10.0, [1.0, 0.0, 0.0])],
            LIMITS,
        );
        let one = block_times(&[line(20.0, [1.0, 0.0, 0.0])], LIMITS);
        assert!((straight.iter().sum::<f64>() - one[0]).abs() < 1e-9);
        let corner = block_times(
            &[line(10.0, [1.0, 0.0, 0.0]), line(10.0, [0.0, 1.0, 0.0])],
            LIMITS,
        );
        let reverse = block_times(
            &[line(10.0, [1.0, 0.0, 0.0]), line(10.0, [-1.0, 0.0, 0.0])],
            LIMITS,
        );
        let (c, r, s) = (
            corner.iter().sum::<f64>(),
            reverse.iter().sum::<f64>(),
            one[0],
        );
        assert!(s < c && c < r, "{s} {c} {r}");
        // A right angle at JD 0.013, 1000 mm/s²: v = sqrt(1000·0.013·0.7071/0.2929) ≈ 5.6 mm/s.
        let v = junction_speed([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1000.0, 0.013);
        assert!((v - 5.602).abs() < 0.01, "{v}");
    }
}
