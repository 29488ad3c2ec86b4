//! Spectra in Mitsuba's RGB variants: a constant, or wavelength:value pairs integrated
//! against the CIE 1931 colour-matching functions into linear sRGB
//! (`spectrum_list_to_srgb`, `src/core/spectrum.cpp`), with the data of [`super::tables`].

use super::tables::{CIE_X, CIE_Y, CIE_Z, D65};
use glam::DVec3;

/// A `<spectrum value=…>`.
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    Uniform(f64),
    /// Wavelengths in nm, increasing, with a value each.
    Samples(Vec<(f64, f64)>),
}

/// How a colour is used, which decides Mitsuba's conversion of a spectrum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorUse {
    /// A reflectance: D65-weighted, clamped to [0, 1].
    Reflectance,
    /// An emitter's radiance: not D65-weighted, unbounded; a constant becomes the sRGB
    /// colour of a flat spectrum (reddish, as in Mitsuba's RGB variants).
    Emission,
    /// An unbounded quantity (η, k): D65-weighted, only negatives clamped.
    Unbounded,
}

const CIE_MIN: f64 = 360.0;
const CIE_MAX: f64 = 830.0;
const CIE_SAMPLES: usize = 95;
const CIE_Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;

/// Why a `<spectrum>`'s value is no spectrum.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SpectrumError {
    #[error("<spectrum>: could not parse \"{0}\" as a finite number")]
    NotANumber(String),
    #[error("<spectrum>: \"{0}\" is not wavelength:value")]
    NotAPair(String),
    #[error("<spectrum> needs one value or at least two wavelength:value pairs")]
    TooFewPairs,
    #[error("<spectrum>: wavelengths must increase")]
    NotIncreasing,
}

impl Spectrum {
    /// `"0.5"` or `"400:0.1, 500:0.4, …"`.
    pub fn parse(text: &str) -> Result<Spectrum, SpectrumError> {
        let tokens: Vec<&str> = super::numbers::tokens(text).collect();
        let number = |t: &str| {
            super::numbers::parse_f64(t).ok_or_else(|| SpectrumError::NotANumber(t.to_string()))
        };
        if let [single] = tokens[..] {
            if !single.contains(':') {
                return Ok(Spectrum::Uniform(number(single)?));
            }
        }
        let mut samples = Vec::with_capacity(tokens.len());
        for t in tokens {
            let (w, v) = t
                .split_once(':')
                .ok_or_else(|| SpectrumError::NotAPair(t.to_string()))?;
            samples.push((number(w)?, number(v)?));
        }
        if samples.len() < 2 {
            return Err(SpectrumError::TooFewPairs);
        }
        if samples.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(SpectrumError::NotIncreasing);
        }
        Ok(Spectrum::Samples(samples))
    }

    /// Linear sRGB as Mitsuba's RGB variants use it for `usage`, and whether it was clamped.
    pub fn to_rgb(&self, usage: ColorUse) -> (DVec3, bool) {
        match self {
            Spectrum::Uniform(v) if usage == ColorUse::Emission => {
                (*v * xyz_to_srgb(DVec3::ONE), false)
            }
            Spectrum::Uniform(v) => (DVec3::splat(*v), false),
            Spectrum::Samples(s) => {
                let rgb = list_to_srgb(s, usage != ColorUse::Emission);
                let clamped = if usage == ColorUse::Reflectance {
                    rgb.clamp(DVec3::ZERO, DVec3::ONE)
                } else {
                    rgb.max(DVec3::ZERO)
                };
                (clamped, clamped != rgb)
            }
        }
    }
}

/// Mitsuba's table lookup: linear interpolation of the 95 samples, zero outside.
fn lookup(table: &[f64; 95], w: f64) -> f64 {
    if !(CIE_MIN..=CIE_MAX).contains(&w) {
        return 0.0;
    }
    let t = (w - CIE_MIN) * ((CIE_SAMPLES - 1) as f64 / (CIE_MAX - CIE_MIN));
    let i0 = (t as usize).min(CIE_SAMPLES - 2);
    let w1 = t - i0 as f64;
    (1.0 - w1) * table[i0] + w1 * table[i0 + 1]
}

/// `spectrum_list_to_srgb`: 1000 wavelengths across the CIE range, the piecewise-linear
/// spectrum (zero outside its range) times x̄ȳz̄ (and D65 where `d65`), to XYZ, to sRGB.
fn list_to_srgb(samples: &[(f64, f64)], d65: bool) -> DVec3 {
    const STEPS: usize = 1000;
    let mut xyz = DVec3::ZERO;
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        let (first, last) = (samples[0].0, samples[samples.len() - 1].0);
        if w < first || w > last {
            continue;
        }
        let index = samples
            .partition_point(|s| s.0 <= w)
            .saturating_sub(1)
            .min(samples.len() - 2);
        let ((w0, v0), (w1, v1)) = (samples[index], samples[index + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let weight = if d65 { lookup(&D65, w) } else { 1.0 };
        xyz += DVec3::new(lookup(&CIE_X, w), lookup(&CIE_Y, w), lookup(&CIE_Z, w)) * v * weight;
    }
    xyz *= (CIE_MAX - CIE_MIN) * CIE_Y_NORMALIZATION / STEPS as f64;
    xyz_to_srgb(xyz)
}

/// Mitsuba's XYZ → linear sRGB (Rec. 709) matrix.
fn xyz_to_srgb(xyz: DVec3) -> DVec3 {
    DVec3::new(
        3.240479 * xyz.x - 1.537150 * xyz.y - 0.498535 * xyz.z,
        -0.969256 * xyz.x + 1.875991 * xyz.y + 0.041556 * xyz.z,
        0.055648 * xyz.x - 0.204043 * xyz.y + 1.057311 * xyz.z,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_constants_and_lists() {
        assert_eq!(Spectrum::parse("0.5"), Ok(Spectrum::Uniform(0.5)));
        assert!(
            matches!(Spectrum::parse("400:0.1, 700:0.2"), Ok(Spectrum::Samples(s)) if s.len() == 2)
        );
        assert!(Spectrum::parse("700:0.1, 400:0.2").is_err());
        assert!(Spectrum::parse("400:x, 500:1").is_err());
        assert!(Spectrum::parse("400:1").is_err());
    }

    /// Values from Mitsuba 3.9.1's own `spectrum_list_to_srgb` and `xyz_to_srgb`.
    #[test]
    fn spectra_convert_as_mitsuba_converts_them() {
        let close = |a: DVec3, b: [f64; 3]| (a - DVec3::from(b)).abs().max_element() < 1e-3;
        let flat = |v| Spectrum::Samples(vec![(360.0, v), (830.0, v)]);
        let (r, _) = flat(0.5).to_rgb(ColorUse::Reflectance);
        assert!(close(r, [0.499492, 0.499436, 0.499401]), "{r}");
        let (e, _) = Spectrum::Uniform(1.0).to_rgb(ColorUse::Emission);
        assert!(close(e, [1.20479, 0.948291, 0.908916]), "{e}");
        let (l, _) = flat(1.0).to_rgb(ColorUse::Emission);
        assert!(close(l, [1.20488, 0.948229, 0.909267]), "{l}");
        // The same flat spectrum as a reflectance is grey, not the emission's colour.
        assert!(!close(
            flat(1.0).to_rgb(ColorUse::Reflectance).0,
            [1.20488, 0.948229, 0.909267]
        ));
    }
}
