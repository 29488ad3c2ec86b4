//! The sRGB transfer function (IEC 61966-2-1), the one place where linear values become display
//! values. Every 8-bit writer goes through [`encode_u8`] so that all back-ends produce the same
//! bytes.

use super::Image;

/// Linear → sRGB-encoded, for values in [0, 1].
pub fn encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB-encoded → linear, for values in [0, 1]; the inverse of [`encode`].
pub fn decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear value → 8-bit display value: NaN → 0, clamped to [0, 1], encoded, rounded to nearest.
pub fn encode_u8(linear: f32) -> u8 {
    // `clamp` passes NaN through (and `as u8` would then give 0 silently); make it explicit.
    let v = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    // In [0, 255] after clamping, so the cast cannot truncate.
    (encode(v) * 255.0).round() as u8
}

/// 8-bit display value → linear.
pub fn decode_u8(value: u8) -> f32 {
    decode(f32::from(value) / 255.0)
}

/// The whole image as interleaved 8-bit sRGB, row-major, 3 bytes per pixel.
pub fn encode_image_u8(img: &Image) -> Vec<u8> {
    img.pixels
        .as_flattened()
        .iter()
        .map(|&v| encode_u8(v))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        assert_eq!(encode_u8(0.0), 0);
        assert_eq!(encode_u8(1.0), 255);
        // 1.055 · 0.5^(1/2.4) − 0.055 = 0.73536 → 187.52.
        assert_eq!(encode_u8(0.5), 188);
        // Linear segment at the boundary: 12.92 · 0.0031308 · 255 = 10.31.
        assert_eq!(encode_u8(0.003_130_8), 10);
        assert_eq!(encode_u8(0.18), 118);
    }

    #[test]
    fn out_of_range_and_nan() {
        assert_eq!(encode_u8(-0.5), 0);
        assert_eq!(encode_u8(f32::NEG_INFINITY), 0);
        assert_eq!(encode_u8(7.0), 255);
        assert_eq!(encode_u8(f32::INFINITY), 255);
        assert_eq!(encode_u8(f32::NAN), 0);
    }

    #[test]
    fn branches_meet_at_the_boundary() {
        let t = 0.003_130_8_f32;
        let power = 1.055 * t.powf(1.0 / 2.4) - 0.055;
        assert!((encode(t) - power).abs() < 1e-4, "{} vs {power}", encode(t));
    }

    #[test]
    fn every_byte_survives_decode_then_encode() {
        for b in 0..=255u8 {
            assert_eq!(encode_u8(decode_u8(b)), b, "byte {b}");
        }
    }

    #[test]
    fn encode_is_monotonic() {
        let mut last = 0.0;
        for i in 1..=10_000 {
            let e = encode(i as f32 / 10_000.0);
            assert!(e > last, "not increasing at {i}");
            last = e;
        }
        assert!((last - 1.0).abs() < 1e-6);
    }
}
