//! Metaballs: blobs whose fields add up, so nearby balls melt into each other.
//!
//! Each ball `[x, y, z, r]` contributes a falloff of its distance d; the solid is where
//! the sum exceeds the threshold T, so the field is `T − Σ falloff`. Both falloffs are
//! scaled so a ball contributes exactly 1 at its own radius: one ball at T = 1 is the
//! sphere of radius r.
//!
//! - Blinn's `(r/d)²`, as Banate CAD and most blob tools define it. It never reaches
//!   zero, so every ball counts everywhere; far from all balls the sum is small and the
//!   interval enclosure of the sum proves the space empty.
//! - Wyvill's compact "soft object" polynomial (Wyvill, McPheeters, Wyvill 1986),
//!   `((R² − d²) / (R² − r²))³` inside the reach R = `reach`·r and 0 beyond. A ball that
//!   cannot reach an octree cell is decided there (`max(0, ..)` picks 0) and drops out
//!   of the cell's simplified tape, so dozens to hundreds of balls cost about as much as
//!   the few that meet each cell.
//!
//! Everything is a kernel expression: metaballs run at kernel speed and mix with
//! everything else. The sum is a balanced tree over the balls in spatial order (sorted
//! along their longest spread), so a cell's simplified tape keeps neighbours together.

use isoforge_field::Shape;

/// How a ball's contribution falls off with distance.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Falloff {
    /// `(r/d)²`.
    Blinn,
    /// Wyvill's compact polynomial, zero beyond `reach` radii.
    Wyvill {
        /// The reach in radii (> 1).
        reach: f64,
    },
}

/// The default reach of the compact falloff: twice the radius. Two balls of radius r
/// start to melt together when their centres come within 4r, as Blinn balls visibly do.
pub const DEFAULT_REACH: f64 = 2.0;

/// Why metaballs cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetaballError {
    /// No balls.
    #[error("no balls: give at least one [x, y, z, r]")]
    Empty,
    /// A ball with a bad number.
    #[error("ball {index}: {what}")]
    Ball {
        /// The 1-based ball.
        index: usize,
        /// What is wrong.
        what: String,
    },
    /// The threshold must be positive (at 0 or below, all space is inside).
    #[error("the threshold must be a positive number, not {0}")]
    Threshold(f64),
    /// The reach must exceed one radius.
    #[error("the reach must be a number above 1 (in radii), not {0}")]
    Reach(f64),
}

/// The metaball field of `balls` at `threshold`.
pub fn metaballs(
    balls: &[[f64; 4]],
    threshold: f64,
    falloff: Falloff,
) -> Result<Shape, MetaballError> {
    if balls.is_empty() {
        return Err(MetaballError::Empty);
    }
    if !(threshold.is_finite() && threshold > 0.0) {
        return Err(MetaballError::Threshold(threshold));
    }
    if let Falloff::Wyvill { reach } = falloff
        && !(reach.is_finite() && reach > 1.0)
    {
        return Err(MetaballError::Reach(reach));
    }
    for (i, b) in balls.iter().enumerate() {
        let bad = |what: &str| MetaballError::Ball {
            index: i + 1,
            what: what.to_string(),
        };
        if b.iter().any(|v| !v.is_finite()) {
            return Err(bad("every number must be finite"));
        }
        if b[3] <= 0.0 {
            return Err(bad(&format!("the radius must be positive, not {}", b[3])));
        }
    }
    let mut order: Vec<[f64; 4]> = balls.to_vec();
    let spread = |k: usize| {
        let (lo, hi) = order
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), b| {
                (lo.min(b[k]), hi.max(b[k]))
            });
        hi - lo
    };
    let axis = (0..3)
        .max_by(|&a, &b| spread(a).total_cmp(&spread(b)))
        .unwrap_or(0);
    order.sort_by(|a, b| a[axis].total_cmp(&b[axis]));
    let terms: Vec<Shape> = order.iter().map(|b| contribution(*b, falloff)).collect();
    Ok(threshold - sum(&terms))
}

/// One ball's falloff at the point (x, y, z).
fn contribution([cx, cy, cz, r]: [f64; 4], falloff: Falloff) -> Shape {
    let d2 = (Shape::x() - cx).square() + (Shape::y() - cy).square() + (Shape::z() - cz).square();
    match falloff {
        // r²/d², with d² kept off zero (a millionth of the radius) so the centre gives a
        // large finite value and intervals stay bounded.
        Falloff::Blinn => r * r / Shape::constant((r * 1e-6).powi(2)).max(&d2),
        Falloff::Wyvill { reach } => {
            let big = reach * r;
            let scaled = (big * big - d2) / (big * big - r * r);
            // The cube keeps the sign, so max(0, ..) outermost is zero beyond the reach
            // and a decided choice for cells out of reach. (Two multiplications: a
            // general power is a libm call, 7% of meshing a lava lamp.)
            Shape::constant(0.0).max(&(scaled.square() * &scaled))
        }
    }
}

fn sum(terms: &[Shape]) -> Shape {
    match terms {
        [] => Shape::constant(0.0),
        [one] => one.clone(),
        _ => {
            let (l, r) = terms.split_at(terms.len() / 2);
            sum(l) + sum(r)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isoforge_field::{PointEval, Tape};

    fn at(s: &Shape, p: [f64; 3]) -> f64 {
        PointEval::new().eval(&Tape::new(s), p)
    }

    #[test]
    fn one_ball_at_threshold_one_is_its_sphere() {
        for falloff in [Falloff::Blinn, Falloff::Wyvill { reach: 2.0 }] {
            let s = metaballs(&[[1.0, 2.0, 3.0, 2.0]], 1.0, falloff).unwrap();
            assert!(at(&s, [3.0, 2.0, 3.0]).abs() < 1e-12, "{falloff:?}");
            assert!(at(&s, [2.9, 2.0, 3.0]) < 0.0);
            assert!(at(&s, [1.0, 4.1, 3.0]) > 0.0);
            assert!(at(&s, [1.0, 2.0, 3.0]) < 0.0, "the centre is inside");
        }
    }

    #[test]
    fn two_balls_melt_together() {
        // Centres 3 apart, radius 1: separate spheres would leave the midpoint outside.
        let balls = [[0.0, 0.0, 0.0, 1.0], [3.0, 0.0, 0.0, 1.0]];
        let blinn = metaballs(&balls, 0.5, Falloff::Blinn).unwrap();
        assert!(at(&blinn, [1.5, 0.0, 0.0]) < 0.0);
        let wyvill = metaballs(&balls, 1.0, Falloff::Wyvill { reach: 2.0 }).unwrap();
        // Beyond the reach of both balls nothing is added.
        assert_eq!(at(&wyvill, [10.0, 0.0, 0.0]), 1.0);
    }

    #[test]
    fn bad_input_is_refused() {
        let err = |balls: &[[f64; 4]], t: f64, f: Falloff| metaballs(balls, t, f).err();
        assert_eq!(err(&[], 1.0, Falloff::Blinn), Some(MetaballError::Empty));
        assert!(matches!(
            err(&[[0.0, 0.0, 0.0, -1.0]], 1.0, Falloff::Blinn),
            Some(MetaballError::Ball { index: 1, .. })
        ));
        assert_eq!(
            err(&[[0.0, 0.0, 0.0, 1.0]], 0.0, Falloff::Blinn),
            Some(MetaballError::Threshold(0.0))
        );
        assert_eq!(
            err(&[[0.0, 0.0, 0.0, 1.0]], 1.0, Falloff::Wyvill { reach: 1.0 }),
            Some(MetaballError::Reach(1.0))
        );
    }
}
