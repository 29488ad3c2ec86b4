//! Random numbers and warps shared by every method.
//!
//! Determinism: each pixel sample draws from its own generator, seeded by a hash of
//! (seed, pixel, sample index), so an image does not depend on the thread count or tile
//! order, and a single pixel can be re-rendered alone.

pub mod anchor;
pub mod light_point;
pub mod patch;

use crate::accel::Ray;
use crate::scene::Camera;
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

/// A seed for the family `stream` by one draw of [`sample_rng`]`(seed, stream, u64::MAX)`:
/// the genetic plan's streams (see [`Stream`]). Not [`derive_seed`]'s hash: a different,
/// equally fixed derivation, so the two never give the same seed by construction, and
/// neither may change without changing the images.
pub fn derived_seed(seed: u64, stream: u64) -> u64 {
    // One sample_rng draw mixes the two into a fresh 64-bit seed.
    let mut rng = sample_rng(seed, stream, u64::MAX);
    rng.random::<u64>()
}

/// The families of random streams besides the render's own, each named by a fixed 64-bit
/// tag (most of them ASCII) from which its seed is derived. Their tags differ, so no two
/// families share random numbers, and none shares the render's (which draws from the user's
/// seed itself).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// The genetic plan's baseline pass (`srt` samples per pixel; [`derived_seed`]).
    Baseline,
    /// The test paths a GA pixel evolves on ([`derived_seed`]).
    TestPaths,
    /// The second set of test paths a GA pixel places its data-driven samplers from
    /// ([`derived_seed`]).
    Placement,
    /// The genetic algorithm's own draws at a GA pixel ([`derived_seed`]).
    Ga,
    /// The gate's `pt` samples at a GA pixel ([`derived_seed`]).
    GatePt,
    /// The gate's samples of the evolved estimator ([`derived_seed`]).
    Gate,
    /// The gate's fresh `srt` test paths that check a mixture's variance ([`derived_seed`]).
    Check,
    /// The spatial guide's training passes, one stream per pass: the tag XOR the pass index
    /// ([`derive_seed`]).
    Spatial,
    /// The first of a reference's two independent halves ([`derive_seed`]).
    ReferenceFirst,
    /// The second of a reference's two halves ([`derive_seed`]).
    ReferenceSecond,
}

impl Stream {
    /// The family's tag, the `tag` or `stream` argument of the seed derivation.
    pub const fn tag(self) -> u64 {
        match self {
            Self::Baseline => 0x6261_7365_6c69_6e65,  // "baseline"
            Self::TestPaths => 0x7465_7374_7061_7468, // "testpath"
            Self::Placement => 0x706c_6163_656d_656e, // "placemen"
            Self::Ga => 0x6765_6e65_7469_6373,        // "genetics"
            Self::GatePt => 0x6761_7465_5f70_7400,    // "gate_pt"
            Self::Gate => 0x6761_7465_0000_0000,      // "gate"
            Self::Check => 0x6368_6563_6b00_0000,     // "check"
            Self::Spatial => 0x7370_6174_6961_6c00,   // "spatial"
            Self::ReferenceFirst => 0x05ee_d0f5_ec00_da1f,
            Self::ReferenceSecond => 0x7e5e_ed00_fa11_0b0b,
        }
    }
}

/// The unbiased sample variance of `n` samples from their sum and sum of squares,
/// `(Σx² − Σx · mean) / (n − 1)` (per channel for a colour); may round below zero.
pub fn sample_variance<T>(sum: T, sum_sq: T, n: f64) -> T
where
    T: Copy
        + std::ops::Sub<Output = T>
        + std::ops::Mul<Output = T>
        + std::ops::Div<f64, Output = T>,
{
    (sum_sq - sum * (sum / n)) / (n - 1.0)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::basis;
    use glam::DVec3;

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
    fn stream_tags_differ() {
        use Stream::*;
        let all = [
            Baseline,
            TestPaths,
            Ga,
            GatePt,
            Gate,
            Check,
            Spatial,
            ReferenceFirst,
            ReferenceSecond,
        ];
        for (i, a) in all.iter().enumerate() {
            for b in &all[i + 1..] {
                assert_ne!(a.tag(), b.tag(), "{a:?} and {b:?}");
            }
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
