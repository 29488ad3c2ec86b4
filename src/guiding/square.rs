//! The square map of the sphere that the directional quadtrees of a [`SpatialField`] live on
//! (see [`super::field`]): a direction's position on the unit square, its inverse, the
//! solid angle per unit of the square's area, and the quadrants of a node's square.
//!
//! [`SpatialField`]: super::SpatialField

use glam::Vec3;

/// The position of unit direction `d` on the square: `u = (cos θ + 1) / 2` about the world
/// `y` axis (equal-area in θ), and `v` the "diamond angle" of `(x, z)` over 4: a quarter of
/// the square per quadrant of the azimuth, along which `v` runs as `z / (|x| + |z|)` does
/// (no trigonometry either way, since the equal-area `atan2` here and `sin_cos` back showed
/// in a guided render's time: reports/README.md, "What changed between de6d183 and
/// ebcb7fc"); the price is a density over the square that varies by up to 2× with the
/// azimuth, [`square_jacobian`].
pub fn to_square(d: Vec3) -> [f32; 2] {
    let u = ((d.y + 1.0) * 0.5).clamp(0.0, 1.0);
    let s = d.x.abs() + d.z.abs();
    let a = if s <= 0.0 {
        0.0
    } else if d.z >= 0.0 {
        if d.x >= 0.0 {
            d.z / s
        } else {
            1.0 - d.x / s
        }
    } else if d.x < 0.0 {
        2.0 - d.z / s
    } else {
        3.0 + d.x / s
    };
    [u, (a * 0.25).clamp(0.0, 1.0)]
}

/// The unit direction at `(u, v)` of the square (inverse of [`to_square`]).
pub fn from_square(u: f64, v: f64) -> Vec3 {
    let y = (2.0 * u - 1.0).clamp(-1.0, 1.0) as f32;
    let a = (4.0 * v).clamp(0.0, 4.0) as f32;
    let quadrant = (a as u32).min(3);
    let t = a - quadrant as f32;
    let (x, z) = match quadrant {
        0 => (1.0 - t, t),
        1 => (-t, 1.0 - t),
        2 => (t - 1.0, -t),
        _ => (t, t - 1.0),
    };
    let r = (1.0 - y * y).max(0.0).sqrt() / (x * x + z * z).sqrt();
    Vec3::new(r * x, y, r * z).normalize()
}

/// Solid angle per unit area of the square at unit direction `d`: `2` per unit of `u` times
/// `dφ / dv = 4 (|cos φ| + |sin φ|)²` (along a quadrant's edge `(1 − t, t)` of the diamond,
/// `dφ / dt = 1 / ((1 − t)² + t²)`). From `8` on the axes to `16` halfway between them; it
/// integrates to `4π` over the square.
pub fn square_jacobian(d: Vec3) -> f64 {
    let (x, z) = (f64::from(d.x), f64::from(d.z));
    let r2 = x * x + z * z;
    if r2 <= 0.0 {
        return 4.0 * std::f64::consts::PI;
    }
    let s = x.abs() + z.abs();
    8.0 * s * s / r2
}

/// The quadrant of `(u, v)` in the unit square, `(u ≥ ½) + 2 (v ≥ ½)`, and `(u, v)` in that
/// quadrant's own unit square (exact in binary floating point).
pub(super) fn quadrant(u: f32, v: f32) -> (usize, f32, f32) {
    let (hu, hv) = (u >= 0.5, v >= 0.5);
    let q = usize::from(hu) + 2 * usize::from(hv);
    (
        q,
        2.0 * u - f32::from(u8::from(hu)),
        2.0 * v - f32::from(u8::from(hv)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_rng, uniform};
    use std::f64::consts::PI;

    fn uniforms(rng: &mut crate::sampling::Rng) -> [f64; 3] {
        [0; 3].map(|_| f64::from(uniform(rng)))
    }

    #[test]
    fn square_round_trips() {
        let mut rng = sample_rng(9, 0, 0);
        for _ in 0..100_000 {
            let [u, v] = uniforms(&mut rng)[..2].try_into().unwrap();
            let d = from_square(u, v);
            assert!((d.length() - 1.0).abs() < 1e-6, "{d}");
            let [a, b] = to_square(d);
            assert!((f64::from(a) - u).abs() < 1e-5, "u {u} → {a}");
            assert!((f64::from(b) - v).abs() < 1e-5, "v {v} → {b}");
        }
    }

    /// The square's solid angle per unit area integrates to the sphere's `4π` (midpoint rule
    /// on a 512² grid), and a cosine-weighted integral over the square matches the analytic
    /// `π` of the upper hemisphere; its square root misses.
    #[test]
    fn square_jacobian_integrates_to_the_sphere() {
        let n = 512;
        let (mut sphere, mut cosine, mut wrong) = (0.0, 0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let d = from_square(u, v);
                let area = 1.0 / (n * n) as f64;
                let jacobian = square_jacobian(d);
                sphere += jacobian * area;
                cosine += jacobian * area * f64::from(d.y.max(0.0));
                wrong += jacobian.sqrt() * area;
            }
        }
        assert!((sphere / (4.0 * PI) - 1.0).abs() < 1e-4, "∫ dω = {sphere}");
        assert!((cosine / PI - 1.0).abs() < 1e-4, "∫ cos dω = {cosine}");
        assert!((wrong / (4.0 * PI) - 1.0).abs() > 0.05, "{wrong}");
    }
}
