//! The comparison picture of an equal-time sweep (`genpath sweep --picture`): one column per
//! method and one for the reference; the renders on top, each method's per-pixel error below
//! it, labelled with the method's seconds, samples and relMSE (and its ratio to the first
//! method's). One self-contained SVG: the images are PNGs inside it, the labels text.

use super::Row;
use crate::image::svg::{image_element, png_bytes, text, PngError};
use crate::image::{srgb, Image};
use std::fmt::Write;

/// A render of the picture: its row of the sweep, and its image.
pub struct Panel<'a> {
    pub row: &'a Row,
    pub image: &'a Image,
}

/// The per-pixel error shown: the pixel's term of relMSE, `(x − ref)² / (ref² + 0.01)`
/// averaged over the channels (its mean over the image is the relMSE in the label).
fn pixel_error(x: [f32; 3], r: [f32; 3]) -> f64 {
    (0..3)
        .map(|c| {
            let (x, r) = (f64::from(x[c]), f64::from(r[c]));
            // A NaN pixel shows as the scale's top, not as a hole.
            let d = if (x - r).is_finite() { x - r } else { 1e3 };
            d * d / (r * r + 0.01)
        })
        .sum::<f64>()
        / 3.0
}

/// The error scale: log10 of the per-pixel error from `ERROR_RANGE.0` to `ERROR_RANGE.1`.
const ERROR_RANGE: (f64, f64) = (-4.0, 1.0);

/// A dark-to-bright colour ramp (black, purple, orange, yellow, white) at `t` in [0, 1].
fn ramp(t: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [0.35, 0.05, 0.5],
        [0.9, 0.3, 0.1],
        [1.0, 0.85, 0.1],
        [1.0, 1.0, 1.0],
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64;
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let f = t - i as f64;
    let c = |k: usize| STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f;
    [0, 1, 2].map(|k| (c(k) * 255.0).round() as u8)
}

fn scale_position(error: f64) -> f64 {
    let (lo, hi) = ERROR_RANGE;
    (error.max(1e-30).log10() - lo) / (hi - lo)
}

/// The error map of `image` against `reference`, as 8-bit RGB.
fn error_map(image: &Image, reference: &Image) -> Vec<u8> {
    let mut out = Vec::with_capacity((image.width * image.height * 3) as usize);
    for y in 0..image.height {
        for x in 0..image.width {
            let e = pixel_error(image.get(x, y), reference.get(x, y));
            out.extend_from_slice(&ramp(scale_position(e)));
        }
    }
    out
}

const MARGIN: u32 = 12;
const LABEL: u32 = 44;

/// The error scale at `(x, y)`, `w` wide: a ramp with its decades.
fn error_scale(out: &mut String, x: u32, bottom: u32, w: u32) {
    let (lo, hi) = ERROR_RANGE;
    text(
        out,
        x,
        bottom - 8,
        11,
        "normal",
        "(x − ref)² / (ref² + 0.01)",
    );
    let steps = 64;
    for k in 0..steps {
        let c = ramp(f64::from(k) / f64::from(steps - 1));
        let _ = writeln!(
            out,
            r##"<rect x="{}" y="{bottom}" width="{}" height="24" fill="#{:02x}{:02x}{:02x}"/>"##,
            x + k * w / steps,
            w / steps + 1,
            c[0],
            c[1],
            c[2]
        );
    }
    for decade in (lo as i32)..=(hi as i32) {
        let f = (f64::from(decade) - lo) / (hi - lo);
        let tx = x + (f * f64::from(w - 24)) as u32;
        text(out, tx, bottom + 40, 11, "normal", &format!("1e{decade}"));
    }
}

/// Why a sweep's picture was not drawn.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    #[error("{method} is {}×{}, the reference {}×{}", size.0, size.1, reference.0, reference.1)]
    Size {
        method: String,
        size: (u32, u32),
        reference: (u32, u32),
    },
    #[error(transparent)]
    Png(#[from] PngError),
}

/// The picture of `panels` (every image of `reference`'s size) against `reference`, titled
/// `title`: an SVG document.
pub fn svg(title: &str, panels: &[Panel], reference: &Image) -> Result<String, PictureError> {
    let (w, h) = (reference.width, reference.height);
    if let Some(p) = panels
        .iter()
        .find(|p| (p.image.width, p.image.height) != (w, h))
    {
        return Err(PictureError::Size {
            method: p.row.method.clone(),
            size: (p.image.width, p.image.height),
            reference: (w, h),
        });
    }
    let columns = panels.len() as u32 + 1;
    let width = MARGIN + columns * (w + MARGIN);
    let title_h = 28;
    let height = title_h + 2 * (LABEL + h + MARGIN) + 24;
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}">"#
    );
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    text(&mut out, MARGIN, 20, 15, "bold", title);
    let first = panels.first().map(|p| p.row);
    let (top, bottom) = (title_h + LABEL, title_h + LABEL + h + MARGIN + LABEL);
    for (i, p) in panels.iter().enumerate() {
        let x = MARGIN + i as u32 * (w + MARGIN);
        let r = p.row;
        text(&mut out, x, top - 24, 14, "bold", &r.method);
        let ratio = match first {
            Some(f) if i > 0 => format!(
                " — {:.2} × {}'s",
                (r.relmse * r.seconds) / (f.relmse * f.seconds),
                f.method
            ),
            _ => String::new(),
        };
        let line = format!(
            "{:.2} s, {} spp, relMSE {:.3e}{ratio}",
            r.seconds, r.spp, r.relmse
        );
        text(&mut out, x, top - 8, 11, "normal", &line);
        image_element(
            &mut out,
            x,
            top,
            w,
            h,
            &png_bytes(w, h, &srgb::encode_image_u8(p.image))?,
        );
        text(&mut out, x, bottom - 8, 11, "normal", "per-pixel error");
        image_element(
            &mut out,
            x,
            bottom,
            w,
            h,
            &png_bytes(w, h, &error_map(p.image, reference))?,
        );
    }
    let x = MARGIN + panels.len() as u32 * (w + MARGIN);
    text(&mut out, x, top - 24, 14, "bold", "reference");
    image_element(
        &mut out,
        x,
        top,
        w,
        h,
        &png_bytes(w, h, &srgb::encode_image_u8(reference))?,
    );
    error_scale(&mut out, x, bottom, w);
    out.push_str("</svg>\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_map_is_dark_where_the_image_is_right_and_bright_where_it_is_wrong() {
        let mut reference = Image::new(2, 1);
        reference.set(0, 0, [0.5; 3]);
        reference.set(1, 0, [0.5; 3]);
        let mut image = reference.clone();
        image.set(1, 0, [5.0; 3]);
        let map = error_map(&image, &reference);
        assert_eq!(&map[0..3], &[0, 0, 0]);
        assert_eq!(&map[3..6], &[255, 255, 255]);
        image.set(1, 0, [f32::NAN; 3]);
        assert_eq!(&error_map(&image, &reference)[3..6], &[255, 255, 255]);
    }
}
