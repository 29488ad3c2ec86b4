//! Error metrics of an image against a reference.

use super::Image;

/// Error of an image against a reference, over all pixels and channels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ErrorMetrics {
    /// Mean of (x − ref)² / (ref² + 0.01).
    pub relmse: f64,
    /// Mean of (x − ref)².
    pub mse: f64,
    /// Mean of |x − ref| / (|ref| + 0.01).
    pub mape: f64,
    /// Fraction of pixels with a NaN, infinite or negative channel (left out of the means).
    pub bad_fraction: f64,
}

/// Compares `image` with `reference`; `None` when their sizes differ.
pub fn compare(image: &Image, reference: &Image) -> Option<ErrorMetrics> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return None;
    }
    let (mut relmse, mut mse, mut mape) = (0.0f64, 0.0f64, 0.0f64);
    let (mut bad, mut counted) = (0usize, 0usize);
    for (x, r) in image.pixels.iter().zip(&reference.pixels) {
        if x.iter().any(|c| !c.is_finite() || *c < 0.0) {
            bad += 1;
            continue;
        }
        for (&x, &r) in x.iter().zip(r) {
            let (x, r) = (x as f64, r as f64);
            let d = x - r;
            relmse += d * d / (r * r + 0.01);
            mse += d * d;
            mape += d.abs() / (r.abs() + 0.01);
            counted += 1;
        }
    }
    let n = counted.max(1) as f64;
    Some(ErrorMetrics {
        relmse: relmse / n,
        mse: mse / n,
        mape: mape / n,
        bad_fraction: bad as f64 / image.pixels.len().max(1) as f64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let mut a = Image::new(2, 1);
        let mut r = Image::new(2, 1);
        a.pixels = vec![[1.0, 1.0, 1.0], [0.0, 0.0, f32::NAN]];
        r.pixels = vec![[0.9, 1.0, 1.1], [0.0, 0.0, 0.0]];
        let m = compare(&a, &r).unwrap();
        let expected_relmse = (0.01 / 0.82 + 0.0 + 0.01 / 1.22) / 3.0;
        assert!((m.relmse - expected_relmse).abs() < 1e-7, "{m:?}");
        assert!((m.mse - 0.02 / 3.0).abs() < 1e-7);
        assert_eq!(m.bad_fraction, 0.5);
        assert_eq!(compare(&a, &Image::new(1, 2)), None);
    }
}
