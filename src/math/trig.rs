//! Inverse and direct trigonometry for the hot paths (the environment map's direction
//! mapping and its sampling), without calls into libm: `atan2`, `acos`, `sin`/`cos` of a
//! fraction of a turn, and `floor`, in `f64`, accurate to a few units in the last place
//! (under 1e-15 absolute; libm's are correctly rounded or nearly), so that nothing they
//! feed (a texel's coordinates, a sampling cell) differs from libm's but by rounding.
//!
//! `floor` is here because the default x86-64 target has no `roundsd` (SSE4.1): `f64::floor`
//! is a call into libm there.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// `tan(π/8)`: above it, [`atan_unit`] reduces its argument by `π/4`.
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;

/// `atan(z)/z` as a polynomial in `z²` on `|z| ≤ tan(π/8)` (a least-squares fit at
/// Chebyshev nodes in 40-digit arithmetic; the maximal error of `z·P(z²)` is 4e-16).
const ATAN: [f64; 10] = [
    0.999_999_999_999_999_1,
    -0.333_333_333_332_245_7,
    0.199_999_999_788_767_92,
    -0.142_857_126_905_069_24,
    0.111_110_497_140_415_36,
    -0.090_895_443_903_317_52,
    0.076_736_777_539_746_85,
    -0.065_068_012_324_210_22,
    0.050_272_998_609_859_7,
    -0.025_349_282_209_907_64,
];

/// `atan(t)` for `t` in [0, 1]: `atan(z)` for `z = t`, or `π/4 + atan(z)` for
/// `z = (t − 1)/(t + 1)` above `tan(π/8)`.
fn atan_unit(t: f64) -> f64 {
    let (z, offset) = if t > TAN_PI_8 {
        ((t - 1.0) / (t + 1.0), FRAC_PI_4)
    } else {
        (t, 0.0)
    };
    let w = z * z;
    let p = ATAN.iter().rev().fold(0.0, |acc, &c| acc * w + c);
    z * p + offset
}

/// `atan2(y, x)`, in [−π, π] (0 for `(0, 0)`), as `f64::atan2` to under 1e-15.
pub fn atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (small, large) = if ay > ax { (ax, ay) } else { (ay, ax) };
    let t = if large > 0.0 { small / large } else { 0.0 };
    let mut a = atan_unit(t);
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    a.copysign(y)
}

/// `acos(c)` for `c` in [−1, 1] (clamped), as `f64::acos` to under 1e-15: `atan2` of the
/// sine, `√((1 − c)(1 + c))`, accurate near ±1 too.
pub fn acos(c: f64) -> f64 {
    let c = c.clamp(-1.0, 1.0);
    atan2(((1.0 - c) * (1.0 + c)).sqrt(), c)
}

/// `(−1)^k / n!` for `n = 2k + first`, `k` in 0..N: the Taylor coefficients of the sine
/// (`first` 1) or the cosine (`first` 0).
const fn taylor<const N: usize>(first: usize) -> [f64; N] {
    let mut c = [0.0; N];
    let mut factorial = 1.0;
    let mut n = 1;
    while n <= 2 * N {
        factorial *= n as f64;
        if n % 2 == first % 2 && (n - first) / 2 < N {
            let k = (n - first) / 2;
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            c[k] = sign / factorial;
        }
        n += 1;
    }
    if first == 0 {
        c[0] = 1.0;
    }
    c
}

const SIN: [f64; 8] = taylor(1);
const COS: [f64; 9] = taylor(0);

/// `(sin 2πx, cos 2πx)` for any finite `x` (a fraction of a turn): `x` reduced to the
/// nearest quarter turn, exactly (no fused multiply-adds: the default x86-64 target
/// has none, and `mul_add` would call libm), and Taylor polynomials on the remaining `|2πr| ≤ π/4`
/// (to the 15th and 16th power: truncation error under 1e-16).
pub fn sin_cos_turns(x: f64) -> (f64, f64) {
    let q = floor(x * 4.0 + 0.5) as f64;
    let a = 2.0 * PI * (x - q * 0.25);
    let a2 = a * a;
    let s = a * SIN.iter().rev().fold(0.0, |acc, &k| acc * a2 + k);
    let c = COS.iter().rev().fold(0.0, |acc, &k| acc * a2 + k);
    match (q as i64).rem_euclid(4) {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `floor(x)` for `|x| < 2^63`, as an integer: the truncation, one less where it rounded up.
pub fn floor(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from((t as f64) > x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Agreement with libm over the whole range, at many points and at the reductions'
    /// seams.
    #[test]
    fn agree_with_libm() {
        let mut worst = [0.0f64; 3];
        let n = 200_000;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let (phi, c) = (2.0 * PI * t - PI, 2.0 * t - 1.0);
            let (y, x) = phi.sin_cos();
            for (yy, xx) in [(y, x), (3.0 * y, 3.0 * x), (y, 0.0), (0.0, x)] {
                worst[0] = worst[0].max((atan2(yy, xx) - yy.atan2(xx)).abs());
            }
            worst[1] = worst[1].max((acos(c) - c.acos()).abs());
            let x = 3.0 * t - 1.0;
            let (s, cc) = sin_cos_turns(x);
            let (es, ec) = (2.0 * PI * x).sin_cos();
            worst[2] = worst[2].max((s - es).abs()).max((cc - ec).abs());
        }
        assert!(worst.iter().all(|&e| e < 2e-15), "{worst:?}");
        assert_eq!(acos(1.0), 0.0);
        assert!((acos(-1.0) - PI).abs() < 1e-15);
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!(sin_cos_turns(0.25), (1.0, 0.0));
    }

    #[test]
    fn floor_is_libms() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.3,
            1.0,
            1.999_999_999,
            7.5e10,
        ] {
            assert_eq!(floor(x) as f64, x.floor(), "{x}");
        }
    }
}
