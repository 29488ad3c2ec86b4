//! Pure-Rust image files: EXR through `exr`, PNG through `png`. Used by [`super::write`] when
//! the crate is built without OpenImageIO; public so tests can compare them with the OIIO path.
//!
//! These write straight to `path`; [`super::write`] wraps them in [`super::write_atomic`].

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use super::{check_dims, srgb, Image, ImageError};

/// Writes a float32 linear RGB EXR (lossless compression).
pub fn write_exr(path: &Path, img: &Image) -> Result<(), ImageError> {
    check_dims(path, img)?;
    let width = img.width as usize;
    exr::prelude::write_rgb_file(path, width, img.height as usize, |x, y| {
        let [r, g, b] = img.pixels[y * width + x];
        (r, g, b)
    })
    .map_err(|e| ImageError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    })
}

/// Writes an 8-bit sRGB PNG (values encoded by [`srgb::encode_u8`]).
pub fn write_png(path: &Path, img: &Image) -> Result<(), ImageError> {
    check_dims(path, img)?;
    let write_err = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let file = File::create(path).map_err(|e| write_err(e.to_string()))?;
    let mut out = BufWriter::new(file);
    let mut encoder = png::Encoder::new(&mut out, img.width, img.height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder
        .write_header()
        .map_err(|e| write_err(e.to_string()))?;
    writer
        .write_image_data(&srgb::encode_image_u8(img))
        .map_err(|e| write_err(e.to_string()))?;
    writer.finish().map_err(|e| write_err(e.to_string()))?;
    // Dropping a BufWriter swallows flush errors (e.g. a full disk); surface them.
    out.flush().map_err(|e| write_err(e.to_string()))
}

/// Reads an 8-bit or 16-bit PNG (grey or RGB, alpha ignored) as linear RGB.
pub fn read_png(path: &Path) -> Result<Image, ImageError> {
    let mut img = read_png_encoded(path)?;
    for px in &mut img.pixels {
        *px = px.map(srgb::decode);
    }
    Ok(img)
}

/// Reads a PNG as [`read_png`] does, its sRGB-encoded values normalised to [0, 1] and not
/// decoded (8 bits: a 16-bit file is read at 8 bits).
pub fn read_png_encoded(path: &Path) -> Result<Image, ImageError> {
    let read_err = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    let file = File::open(path).map_err(|e| read_err(e.to_string()))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    // Palette → RGB, low bit depths → 8 bits, 16 bits → 8 bits: only 8-bit grey/RGB(A) remain.
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| read_err(e.to_string()))?;
    let mut buf = vec![0; reader.output_buffer_size()];
    let frame = reader
        .next_frame(&mut buf)
        .map_err(|e| read_err(e.to_string()))?;
    let stride = frame.color_type.samples();
    let mut img = Image::new(frame.width, frame.height);
    let bytes = &buf[..frame.buffer_size()];
    for (px, s) in img.pixels.iter_mut().zip(bytes.chunks_exact(stride)) {
        let v = |b: u8| f32::from(b) / 255.0;
        *px = if stride >= 3 {
            [v(s[0]), v(s[1]), v(s[2])]
        } else {
            [v(s[0]); 3]
        };
    }
    Ok(img)
}
