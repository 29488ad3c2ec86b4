//! Random numbers and warps shared by every method.
//!
//! Determinism: each pixel sample draws from its own generator, seeded by a hash of
//! (seed, pixel, sample index), so an image does not depend on the thread count or tile
//! order, and a single pixel can be re-rendered alone.

pub mod anchor;
pub mod brdf;
pub mod light_point;
pub mod patch;

use crate::accel::Ray;
use crate::scene::Camera;
use glam::DVec3;
use rand::Rng as _;
use rand_pcg::Pcg32;

pub type Rng = Pcg32;

/// SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of one pixel sample: a hash of (seed, pixel index, sample index).
pub fn sample_rng(seed: u64, pixel: u64, sample: u64) -> Rng {
    let state = mix64(seed ^ mix64(pixel.wrapping_add(0x9e37_79b9_7f4a_7c15) ^ mix64(sample)));
    let stream = mix64(state ^ 0x2545_f491_4f6c_dd1d);
    Pcg32::new(state, stream)
}

/// A seed for an independent family of streams: a hash of `seed` and a `tag` naming the
/// family.
pub fn derive_seed(seed: u64, tag: u64) -> u64 {
    mix64(mix64(seed ^ 0x6a09_e667_f3bc_c908) ^ tag)
}

/// A uniform number in [0, 1).
#[inline]
pub fn uniform(rng: &mut Rng) -> f32 {
    rng.random::<f32>()
}

/// The camera ray of one sample of pixel `(x, y)`: through a uniformly jittered position
/// inside the pixel (a box filter), from two uniform numbers, horizontal first.
pub fn camera_ray(camera: &Camera, (x, y): (u32, u32), rng: &mut Rng) -> Ray {
    camera.ray(x as f32 + uniform(rng), y as f32 + uniform(rng))
}

/// An orthonormal basis `(t, b)` completing unit `n` (Duff et al., "Building an Orthonormal
/// Basis, Revisited").
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal() {
        let mut rng = sample_rng(1, 2, 3);
        for _ in 0..10_000 {
            let n = DVec3::new(
                uniform(&mut rng) as f64 - 0.5,
                uniform(&mut rng) as f64 - 0.5,
                uniform(&mut rng) as f64 - 0.5,
            )
            .normalize_or(DVec3::Z);
            let (t, b) = basis(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-12, "{n} {t} {b}");
            }
            assert!((t.length() - 1.0).abs() < 1e-12 && (b.length() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn sample_streams_differ_per_pixel_and_sample() {
        let draw = |s, p, i| uniform(&mut sample_rng(s, p, i));
        assert_eq!(draw(7, 3, 4), draw(7, 3, 4));
        assert_ne!(draw(7, 3, 4), draw(7, 4, 3));
        assert_ne!(draw(7, 3, 4), draw(8, 3, 4));
        assert_ne!(draw(7, 3, 4), draw(7, 3, 5));
    }
}
