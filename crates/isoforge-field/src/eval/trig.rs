//! sin, cos and atan2 in plain arithmetic, so that a loop over a block of points
//! vectorizes.
//!
//! libm's `sin` and `cos` are calls the compiler cannot vectorize: on the gyroid sphere at
//! depth 9 they were 45 % of the meshing time, most of it the batch evaluator's lattice
//! sampling, the rest the gradients (docs/architecture.md, "sin, cos and atan2"). Here
//! `x` is reduced to `r = x − k·π/2`, `|r| ≤ π/4` (Cody and Waite's reduction: π/2 in
//! three parts, the first two short enough that `k` times them is exact for `|k| < 2^20`,
//! and `r` carried as a sum of two doubles), and sin or cos of `r` is its Taylor
//! polynomial (Estrin's scheme, fused multiply-adds), to the term past which the rest is
//! under 10^-19 of the result. The error is under one ulp (the test
//! `within_an_ulp_of_libm`, and `tools/trig-accuracy.py`, which checks against 70-digit
//! decimal arithmetic), so the interval evaluator's enclosures, made with libm and
//! widened by two ulps (`enclose.rs`), still hold every value computed here. atan2 is the
//! series of atan on the smaller coordinate over the larger, under 1.8 ulp from the truth
//! measured (`enclose.rs` widens its enclosure by two ulps more).
//!
//! Beyond [`LIMIT`] the reduction would lose exactness, and libm answers. Every evaluator
//! calls these functions for sin and cos, so they agree bit for bit: the batch evaluator
//! the `*_in_range` ones over a whole block (then libm for lanes beyond the limit), the
//! point and gradient evaluators [`sin`], [`cos`] and [`sin_cos`].

/// Largest |x| reduced here: `k = x·2/π` stays below 2^20, so `k·P1` and `k·P2` are exact.
pub const LIMIT: f64 = 1.0e6;

/// π/2 = P1 + P2 + P3, P1 and P2 of 33 significant bits each (truncated), P3 rounded.
const P1: f64 = 1.5707963267341256;
const P2: f64 = 6.077100506303966e-11;
const P3: f64 = 2.0222662487959506e-21;
/// 1.5·2^52: adding it rounds a number below 2^51 to an integer held in the low bits.
const ROUND: f64 = 6755399441055744.0;
/// Below this, sin x rounds to x (x³/6 is under half an ulp of x) and cos x to 1.
const TINY: f64 = 1.0 / 134217728.0; // 2^-27

/// sin r / r − 1 as a polynomial in r²: (−1)^n / (2n+1)! for n = 1..8.
const S: [f64; 8] = [
    -0.16666666666666666,
    0.008333333333333333,
    -0.0001984126984126984,
    2.7557319223985893e-06,
    -2.505210838544172e-08,
    1.6059043836821613e-10,
    -7.647163731819816e-13,
    2.8114572543455206e-15,
];
/// (cos r − 1 + r²/2) / r⁴ as a polynomial in r²: (−1)^n / (2n)! for n = 2..9.
const C: [f64; 8] = [
    0.041666666666666664,
    -0.001388888888888889,
    2.48015873015873e-05,
    -2.755731922398589e-07,
    2.08767569878681e-09,
    -1.1470745597729725e-11,
    4.779477332387385e-14,
    -1.5619206968586225e-16,
];

/// `c[0] + c[1]·z + … + c[7]·z⁷` by Estrin's scheme: three levels of fused multiply-adds
/// instead of Horner's seven, which the point evaluators' latency notices.
#[inline(always)]
fn poly(c: &[f64; 8], z: f64) -> f64 {
    let z2 = z * z;
    let z4 = z2 * z2;
    let p01 = c[1].mul_add(z, c[0]);
    let p23 = c[3].mul_add(z, c[2]);
    let p45 = c[5].mul_add(z, c[4]);
    let p67 = c[7].mul_add(z, c[6]);
    let low = p23.mul_add(z2, p01);
    let high = p67.mul_add(z2, p45);
    high.mul_add(z4, low)
}

/// `x` reduced: (r, r's rounding error, the quarter turn k mod 4).
#[inline(always)]
fn reduce(x: f64) -> (f64, f64, u64) {
    let shifted = x * std::f64::consts::FRAC_2_PI + ROUND;
    let k = shifted - ROUND;
    let quarter = shifted.to_bits() & 3;
    // x − k·P1 is exact (Sterbenz: both are within a factor of two, or k is 0), k·P2 too.
    let a = x - k * P1;
    let b = k * P2;
    let r = a - b;
    // Two-sum: the rounding error of a − b, exactly.
    let v = r - a;
    let err = (a - (r - v)) + (-b - v) - k * P3;
    // Renormalized: k·P3 reaches 10^-15 near the limit, and the kernel's first-order
    // use of the error term wants it under half an ulp of r (two-sum again: near a
    // multiple of π/2, r may be the smaller).
    let hi = r + err;
    let w = hi - r;
    (hi, (r - (hi - w)) + (err - w), quarter)
}

/// sin(r + e) and cos(r + e) for |r| ≤ π/4 and e tiny.
#[inline(always)]
fn kernel(r: f64, e: f64) -> (f64, f64) {
    let z = r * r;
    // sin(r + e) ≈ sin r + e·cos r, and cos r ≈ 1 − r²/2 is enough for e's term.
    let sin = r + (r * z * poly(&S, z) + e * (1.0 - 0.5 * z));
    // 1 − z/2 with its rounding error added back, as fdlibm does.
    let half = 0.5 * z;
    let w = 1.0 - half;
    let cos = w + (((1.0 - w) - half) + (z * z * poly(&C, z) - r * e));
    (sin, cos)
}

/// sin and cos of `x` for |x| ≤ [`LIMIT`] (anything else gives a meaningless number; the
/// public functions send it to libm).
#[inline(always)]
fn reduced(x: f64) -> (f64, f64) {
    let (r, e, q) = reduce(x);
    let (s, c) = kernel(r, e);
    // sin x by quarter turn: s, c, −s, −c; cos x: c, −s, −c, s.
    let (s1, c1) = if q & 1 == 0 { (s, c) } else { (c, -s) };
    if q & 2 == 0 { (s1, c1) } else { (-s1, -c1) }
}

/// sin x for |x| ≤ [`LIMIT`], plain arithmetic (vectorizes in a loop).
#[inline(always)]
pub fn sin_in_range(x: f64) -> f64 {
    if x.abs() < TINY { x } else { reduced(x).0 }
}

/// cos x for |x| ≤ [`LIMIT`], plain arithmetic (vectorizes in a loop).
#[inline(always)]
pub fn cos_in_range(x: f64) -> f64 {
    if x.abs() < TINY { 1.0 } else { reduced(x).1 }
}

/// True when `x` is reduced here (finite and within [`LIMIT`]).
#[inline(always)]
pub fn in_range(x: f64) -> bool {
    x.abs() <= LIMIT
}

/// sin x. This and the next two are calls, as libm's were: inlined into the point
/// evaluator's loop they slowed it on every tape (colonnade, which has no sin, went from
/// 2.0 to 2.4 ms in the `field` bench).
#[inline(never)]
pub fn sin(x: f64) -> f64 {
    if in_range(x) {
        sin_in_range(x)
    } else {
        x.sin()
    }
}

/// cos x.
#[inline(never)]
pub fn cos(x: f64) -> f64 {
    if in_range(x) {
        cos_in_range(x)
    } else {
        x.cos()
    }
}

/// sin x and cos x, reduced once.
#[inline(never)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !in_range(x) {
        x.sin_cos()
    } else if x.abs() < TINY {
        (x, 1.0)
    } else {
        reduced(x)
    }
}

/// π, π/2 and π/4 as a double and the rest: the rest is added after the angle's own sum
/// so the angle keeps the bits a lone double of π would lose.
const PI_HI: f64 = std::f64::consts::PI;
const PI_LO: f64 = 1.2246467991473532e-16;
const HALF_PI_HI: f64 = std::f64::consts::FRAC_PI_2;
const HALF_PI_LO: f64 = 6.123233995736766e-17;
const QUARTER_PI_HI: f64 = std::f64::consts::FRAC_PI_4;
const QUARTER_PI_LO: f64 = 3.061616997868383e-17;
/// Above this ratio, atan(num / den) is taken as π/4 + atan((num − den) / (num + den))
/// ([`atan_ratio`]).
const HALF: f64 = 0.5;

/// (atan u / u − 1) / u² as a polynomial in u²: (−1)^k / (2k + 1) for k = 1..28. At
/// |u| ≤ 1/2 the rest of the series is under 10^-18 of the result.
const A: [f64; 28] = [
    -0.3333333333333333,
    0.2,
    -0.14285714285714285,
    0.1111111111111111,
    -0.09090909090909091,
    0.07692307692307693,
    -0.06666666666666667,
    0.058823529411764705,
    -0.05263157894736842,
    0.047619047619047616,
    -0.043478260869565216,
    0.04,
    -0.037037037037037035,
    0.034482758620689655,
    -0.03225806451612903,
    0.030303030303030304,
    -0.02857142857142857,
    0.02702702702702703,
    -0.02564102564102564,
    0.024390243902439025,
    -0.023255813953488372,
    0.022222222222222223,
    -0.02127659574468085,
    0.02040816326530612,
    -0.0196078431372549,
    0.018867924528301886,
    -0.01818181818181818,
    0.017543859649122806,
];

/// `A[0] + A[1]·z + … + A[27]·z²⁷`: seven chunks of four by Horner, side by side, joined
/// by Horner in z⁴.
#[inline(always)]
fn atan_poly(z: f64) -> f64 {
    let chunk = |k: usize| {
        let c = &A[4 * k..4 * k + 4];
        c[3].mul_add(z, c[2]).mul_add(z, c[1]).mul_add(z, c[0])
    };
    let z4 = (z * z) * (z * z);
    let mut p = chunk(6);
    for k in (0..6).rev() {
        p = p.mul_add(z4, chunk(k));
    }
    p
}

/// atan(num / den) for 0 ≤ num ≤ den. Above a half, π/4 + atan(u), u = (num − den) /
/// (num + den), which needs no rounded quotient first: num − den is exact there
/// (Sterbenz), and the one division is the only rounding before the series. Every
/// choice is a select between values computed either way, so a loop of it vectorizes.
#[inline(always)]
fn atan_ratio(num: f64, den: f64) -> f64 {
    let big = num > HALF * den;
    let u = if big { num - den } else { num } / if big { num + den } else { den };
    let z = u * u;
    let small = (u * z).mul_add(atan_poly(z), u);
    let (hi, lo) = if big {
        (QUARTER_PI_HI, QUARTER_PI_LO)
    } else {
        (0.0, 0.0)
    };
    hi + (small + lo)
}

/// Largest |x| or |y| for [`atan2_reduced`]: num + den must not overflow.
const ATAN2_LIMIT: f64 = 1e300;

/// True when atan2(y, x) is computed here: both finite, neither zero, neither beyond
/// [`ATAN2_LIMIT`] (zeros and infinities pick angles by their signs, which libm knows).
#[inline(always)]
pub fn atan2_in_range(y: f64, x: f64) -> bool {
    x != 0.0 && y != 0.0 && x.abs() <= ATAN2_LIMIT && y.abs() <= ATAN2_LIMIT
}

/// atan2(y, x) where [`atan2_in_range`] holds, plain arithmetic (vectorizes in a loop):
/// the angle of the smaller of |x|, |y| over the larger, then turned into its octant.
#[inline(always)]
pub fn atan2_reduced(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay > ax;
    let a = atan_ratio(ax.min(ay), ax.max(ay));
    let turned = HALF_PI_HI - (a - HALF_PI_LO);
    let a = if steep { turned } else { a };
    let back = PI_HI - (a - PI_LO);
    let a = if x < 0.0 { back } else { a };
    a.copysign(y)
}

/// atan2(y, x): the angle of the point (x, y), in [−π, π].
#[inline(never)]
pub fn atan2(y: f64, x: f64) -> f64 {
    if atan2_in_range(y, x) {
        atan2_reduced(y, x)
    } else {
        y.atan2(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Units in the last place between two doubles of one sign (0 when equal).
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let key = |v: f64| {
            let bits = v.to_bits() as i64;
            if bits < 0 { i64::MIN - bits } else { bits }
        };
        key(a).abs_diff(key(b))
    }

    /// A simple deterministic generator (splitmix64), so the test needs no crate.
    fn numbers(seed: u64) -> impl Iterator<Item = f64> {
        let mut s = seed;
        std::iter::from_fn(move || {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            Some(((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64)
        })
    }

    #[test]
    fn within_an_ulp_of_libm() {
        // Spread over scales: model coordinates, gyroid arguments, and up to the limit.
        let mut worst = 0;
        for (i, u) in numbers(7).take(400_000).enumerate() {
            let scale = [1.0, 10.0, 1e3, LIMIT][i % 4];
            let x = (2.0 * u - 1.0) * scale;
            let (s, c) = sin_cos(x);
            worst = worst.max(ulps(s, x.sin())).max(ulps(c, x.cos()));
            assert_eq!(s.to_bits(), sin(x).to_bits());
            assert_eq!(c.to_bits(), cos(x).to_bits());
        }
        // libm is within an ulp of the truth too: one apart means both may be right.
        assert!(worst <= 1, "{worst} ulps from libm");
    }

    #[test]
    fn atan2_within_two_ulps_of_libm_and_at_its_special_points() {
        let mut worst = 0;
        let mut pairs = numbers(11);
        for i in 0..400_000 {
            let (u, v) = (pairs.next().unwrap_or(0.5), pairs.next().unwrap_or(0.5));
            let scale = [1.0, 1e-3, 1e3, 1e300][i % 4];
            let (y, x) = ((2.0 * u - 1.0) * scale, (2.0 * v - 1.0) * scale);
            worst = worst.max(ulps(atan2(y, x), y.atan2(x)));
        }
        // The quotient's rounding alone is half an ulp of t, up to an ulp of an angle
        // below 1/2 (docs/architecture.md, "sin, cos and atan2").
        assert!(worst <= 2, "{worst} ulps from libm");
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e-310,
        ];
        for y in special {
            for x in special {
                let (ours, libm) = (atan2(y, x), y.atan2(x));
                assert!(ours.to_bits() == libm.to_bits() || ours.is_nan() && libm.is_nan());
            }
        }
    }

    #[test]
    fn exact_points_and_signs() {
        assert_eq!(sin(0.0).to_bits(), 0.0f64.to_bits());
        assert_eq!(sin(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(cos(0.0), 1.0);
        assert!(sin(f64::NAN).is_nan() && cos(f64::INFINITY).is_nan());
        for x in [
            1e-300,
            -3e-9,
            std::f64::consts::PI,
            1e6,
            -1e6,
            1e6 + 1.0,
            1e300,
        ] {
            assert!(ulps(sin(x), x.sin()) <= 1, "sin {x}");
            assert!(ulps(cos(x), x.cos()) <= 1, "cos {x}");
        }
    }
}
